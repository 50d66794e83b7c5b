//! `bodyseg rig import` of the real iai_kinect2 calibration in `../shared/data` and of
//! the other tools' real files in `tests/fixtures/calib` (every format in one rig, placed
//! with OpenPTrack's poses), then `bodyseg rig show`; bad input: a folder missing a file,
//! repeated camera names, a camera OpenPTrack does not know, the Azure Kinect SDK's own
//! test file (byte order mark, deprecated model).

use crate::common::{
    assert_contains_all, assert_help, assert_ok, assert_one_error, bodyseg, bodyseg_line, fails_in,
    fails_line_in, files_in, stderr, stdout, succeeds_in, tempdir, words,
};
use bodyseg_pipeline::read_rig;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The real iai_kinect2 folder of a Kinect v2 (serial 196605135147).
fn kinect2_folder() -> PathBuf {
    bodyseg_calib::testing::kinect_v2_test_dir()
}

/// A temporary folder with a copy of the real folder's files in a folder of each name.
fn kinect_folders(names: &[&str]) -> tempfile::TempDir {
    let dir = tempdir();
    for name in names {
        let to = dir.path().join(name);
        std::fs::create_dir(&to).expect("create camera folder");
        let real = std::fs::read_dir(kinect2_folder()).expect("read ../shared/data/iai_kinect2");
        for entry in real {
            let from = entry.expect("dir entry").path();
            let file = from.file_name().expect("a file name");
            std::fs::copy(&from, to.join(file)).expect("copy calibration file");
        }
    }
    dir
}

/// Asserts a successful `rig import` whose stderr has its `import ...` timing line
/// holding `summary`; returns stderr.
fn assert_imported(out: &Output, summary: &str) -> String {
    assert_ok(out, "bodyseg rig import");
    let err = stderr(out);
    assert!(
        err.lines()
            .any(|l| l.starts_with("import ") && l.contains(summary)),
        "{summary:?} not in: {err}"
    );
    err
}

#[test]
fn import_two_cameras_then_show() {
    let dir = kinect_folders(&["kinect_a", "kinect_b"]);
    let d = dir.path();
    let out = bodyseg_line(
        d,
        "rig import --from iai_kinect2 kinect_a kinect_b --out rig.toml",
    );
    let err = assert_imported(&out, " ms  2 cameras → rig.toml");
    assert!(
        err.contains("note:") && err.contains("world_from_depth"),
        "{err}"
    );

    let rig = read_rig(&d.join("rig.toml")).expect("rig.toml reads back");
    let names: Vec<&str> = rig.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["kinect_a", "kinect_b"]);
    for c in &rig.cameras {
        // calib_color.yaml: cameraMatrix[0] = 1.0599465578241038e+03; the rig stores it
        // through TOML's shortest round-trip float text, so it comes back exactly.
        assert_eq!(c.color.fx, 1.0599465578241038e+03);
        assert_eq!(c.depth.width, 512);
        assert_eq!(c.color.height, 1080);
        // calib_pose.yaml: translation[0] = -5.2052476112081990e-02 m.
        let t = c.color_from_depth.translation_m();
        assert!((t[0] - -0.052).abs() < 1e-4, "{t:?}");
        // calib_depth.yaml: depthShift = -1.3354238655403018e+01 mm.
        assert_eq!(c.depth_shift_mm, -1.3354238655403018e+01);
        assert_eq!(c.world_from_depth.translation_m(), [0.0; 3]);
    }

    let text = stdout(&succeeds_in(d, &["rig", "show", "rig.toml"]));
    assert_contains_all(
        &text,
        &[
            "2 cameras",
            "kinect_a",
            "kinect_b",
            "fx 1059.95",
            "baseline 52.1 mm",
        ],
    );
}

#[test]
fn names_and_no_note_with_world_from_depth_identity() {
    let dir = kinect_folders(&["k"]);
    let d = dir.path();
    let out = bodyseg_line(
        d,
        "rig import --from iai_kinect2 k --name front --world-from-depth-identity --out rig.toml",
    );
    assert_ok(&out, "bodyseg rig import --name");
    assert!(!stderr(&out).contains("note:"), "{}", stderr(&out));
    let rig = read_rig(&d.join("rig.toml")).expect("rig.toml reads back");
    assert_eq!(rig.cameras.len(), 1);
    assert_eq!(rig.cameras[0].name, "front");
}

#[test]
fn folder_without_calib_pose_names_the_file() {
    let dir = kinect_folders(&["good", "bad"]);
    let d = dir.path();
    std::fs::remove_file(d.join("bad/calib_pose.yaml")).expect("remove calib_pose.yaml");
    let line = "rig import --from iai_kinect2 good bad --out rig.toml";
    let err = fails_line_in(d, line, &["calib_pose.yaml"]);
    // The cause once, not also chained as a source.
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

#[test]
fn repeated_camera_names_are_named() {
    let dir = kinect_folders(&["a", "b"]);
    let d = dir.path();
    let line = "rig import --from iai_kinect2 a b --name cam0 --name cam0 --out rig.toml";
    fails_line_in(d, line, &["\"cam0\"", "used twice"]);
}

#[test]
fn show_of_a_missing_rig_names_the_file() {
    let dir = tempdir();
    let d = dir.path();
    let out = bodyseg(d, &["rig", "show", "nope.toml"]);
    assert_one_error(&out, d, &[], &["nope.toml"]);
}

#[test]
fn import_help_names_the_flags_and_the_world_pose_gap() {
    assert_help(
        &["rig", "import", "--help"],
        &[
            "--from",
            "iai_kinect2",
            "azure_kinect",
            "--from ros",
            "--from opencv",
            "DEPTH.yaml,COLOR.yaml",
            "--poses",
            "camera_poses.yaml",
            "--depth-mode",
            "--color-resolution",
            "depth shift 0",
            "plumb_bob",
            "--name",
            "--world-from-depth-identity",
            "--out",
            "identity",
            "bodyseg calibrate world",
            "Examples:",
        ],
    );
}

/// A file or folder of `tests/fixtures/calib` (sources in its SOURCES.md).
fn calib_fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/calib")
        .join(rel)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 fixture path")
}

#[test]
fn every_format_in_one_rig_placed_by_openptrack() {
    let dir = tempdir();
    let d = dir.path();
    // An OpenCV FileStorage pair (as cv::FileStorage writes it), sizes and model inline.
    let opencv = |name: &str, w: u32, h: u32, f: f64| {
        let text = format!(
            "%YAML:1.0\n---\nimage_width: {w}\nimage_height: {h}\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ {f}, 0., {cx}, 0., {f}, {cy}, 0., 0., 1. ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0.1, -0.2, 0., 0., 0.05 ]\n",
            cx = f64::from(w) / 2.0 - 0.5,
            cy = f64::from(h) / 2.0 - 0.5
        );
        std::fs::write(d.join(name), text).expect("write OpenCV file");
    };
    opencv("ir.yml", 640, 480, 570.0);
    opencv("rgb.yml", 1280, 720, 910.5);
    let user_iai = calib_fixture("iai_kinect2/019469645147");
    let upstream_iai = calib_fixture("iai_kinect2/299150235147");
    let azure = calib_fixture("azure_kinect/pyk4a_calibration.json");
    let ros = format!(
        "{},{}",
        arg(&calib_fixture("ros/azure_kinect_depth_nfov_unbinned.yaml")),
        arg(&calib_fixture("ros/azure_kinect_rgb_720p.yaml"))
    );
    let poses = calib_fixture("openptrack/hgse-schneider/camera_poses.yaml");
    let out = bodyseg(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "--from",
            "iai_kinect2",
            "--from",
            "azure_kinect",
            "--from",
            "ros",
            "--from",
            "opencv",
            arg(&user_iai),
            arg(&upstream_iai),
            arg(&azure),
            &ros,
            "ir.yml,rgb.yml",
            "--name",
            "kinectAA",
            "--name",
            "kinectBB",
            "--name",
            "kinectCC",
            "--name",
            "kinectDD",
            "--name",
            "kinectEE",
            "--depth-mode",
            "NFOV_UNBINNED",
            "--color-resolution",
            "720P",
            "--poses",
            arg(&poses),
            "--out",
            "rig.toml",
        ],
    );
    let err = assert_imported(&out, "5 cameras → rig.toml");
    // The defaults taken, one note each, naming the camera.
    assert_contains_all(
        &err,
        &[
            "note: camera kinectBB: no calib_depth.yaml: depth shift 0 mm",
            "note: camera kinectDD: ros files hold no pose between the sensors",
            "note: camera kinectEE: opencv files hold no pose between the sensors",
            "sensors not imported (no camera of that name): kinectFF",
        ],
    );
    assert!(!err.contains("world_from_depth is the identity"), "{err}");

    let rig = read_rig(&d.join("rig.toml")).expect("rig.toml reads back");
    let c = &rig.cameras;
    // calib_depth.yaml of 019469645147: depthShift = -1.7729753302207246e+01.
    assert_eq!(c[0].depth_shift_mm, -1.7729753302207246e+01);
    assert_eq!(c[1].depth_shift_mm, 0.0);
    // The Azure Kinect in NFOV unbinned / 720P, rational; the ROS files of the same device.
    assert_eq!((c[2].depth.width, c[2].depth.height), (640, 576));
    assert_eq!((c[2].color.width, c[2].color.height), (1280, 720));
    assert!(c[2].color.distortion.is_rational() && c[3].color.distortion.is_rational());
    // ModelParameters[2] of the colour camera: fx_n = 0.4779651165008545, × 1280.
    assert_eq!(c[2].color.fx, 0.4779651165008545 * 1280.0);
    assert!(
        (c[3].color.fx - c[2].color.fx).abs() < 1e-3,
        "ROS is the driver's f32"
    );
    assert_eq!(c[4].color.fx, 910.5);
    let text = std::fs::read_to_string(d.join("rig.toml")).expect("rig.toml");
    let lengths: Vec<usize> = text
        .lines()
        .filter(|l| l.starts_with("distortion = "))
        .map(|l| l.matches(',').count() + 1)
        .collect();
    assert_eq!(lengths, [5, 5, 5, 5, 8, 8, 8, 8, 5, 5], "{text}");
    // OpenPTrack's pose is the colour sensor's: where the colour sensor sits in the world
    // is the file's translation (kinectAA: -1.20549, 4.06266, 2.39219; kinectEE:
    // 4.37345, 3.39255, 2.67796).
    for (cam, want) in [
        (&c[0], [-1.20549, 4.06266, 2.39219]),
        (&c[4], [4.37345, 3.39255, 2.67796]),
    ] {
        let world_from_color = cam
            .world_from_depth
            .compose(&cam.color_from_depth.inverse());
        let got = world_from_color.translation_m();
        for (g, w) in got.iter().zip(want) {
            // Composition rounding only.
            assert!((g - w).abs() < 1e-12, "{}: {got:?} vs {want:?}", cam.name);
        }
    }
    let shown = stdout(&succeeds_in(d, &["rig", "show", "rig.toml"]));
    assert!(
        shown.contains("rational distortion (8)") && shown.contains("Brown-Conrady distortion (5)"),
        "{shown}"
    );
}

#[test]
fn camera_unknown_to_openptrack_is_named_with_the_file() {
    let dir = tempdir();
    let d = dir.path();
    let poses = calib_fixture("openptrack/open_ptrack_v2/camera_poses.yaml");
    let folder = calib_fixture("iai_kinect2/019469645147");
    fails_in(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            arg(&folder),
            "--poses",
            arg(&poses),
            "--out",
            "rig.toml",
        ],
        &[
            "camera 019469645147: no sensor \"019469645147\"",
            "camera_poses.yaml",
            "kinect01, kinect02, kinect03",
            "--name",
        ],
    );
}

#[test]
fn azure_sdk_test_file_is_refused_for_its_model_not_its_byte_order_mark() {
    let dir = tempdir();
    let d = dir.path();
    let file = calib_fixture("azure_kinect/sdk_TestCalibration.json");
    let err = fails_in(
        d,
        &[
            "rig",
            "import",
            "--from",
            "azure_kinect",
            arg(&file),
            "--out",
            "rig.toml",
        ],
        &words("Intrinsics.ModelType Rational6KT sdk_TestCalibration.json"),
    );
    assert!(!err.contains("expected value"), "{err}");
}

#[test]
fn ros_file_without_distortion_model_is_plumb_bob() {
    let dir = tempdir();
    let d = dir.path();
    let text = std::fs::read_to_string(calib_fixture("ros/test_calibration.yaml"))
        .expect("fixture")
        .replace("distortion_model: plumb_bob\n", "");
    std::fs::write(d.join("old.yaml"), text).expect("write");
    let out = bodyseg_line(
        d,
        "rig import --from ros old.yaml --world-from-depth-identity --out rig.toml",
    );
    assert_ok(&out, "bodyseg rig import --from ros");
    let err = stderr(&out);
    assert_contains_all(
        &err,
        &[
            "note: camera old: distortion_model: missing, read as plumb_bob",
            "note: camera old: one ros file: depth registered to that sensor",
        ],
    );
    let rig = read_rig(&d.join("rig.toml")).expect("reads back");
    // test_calibration.yaml: camera_matrix data[0], distortion data[0].
    assert_eq!(rig.cameras[0].depth.fx, 1168.68);
    assert_eq!(rig.cameras[0].color.distortion.coefficients()[0], -1.04482);
}

/// `--from openptrack`: ROS camera_info files placed by OpenPTrack's poses; without
/// `--poses` it is refused before anything is read.
#[test]
fn openptrack_network_of_ros_cameras() {
    let dir = tempdir();
    let d = dir.path();
    let ros = format!(
        "{},{}",
        arg(&calib_fixture("ros/azure_kinect_depth_nfov_unbinned.yaml")),
        arg(&calib_fixture("ros/azure_kinect_rgb_720p.yaml"))
    );
    let import = |extra: &[&str]| {
        let mut args = vec![
            "rig",
            "import",
            "--from",
            "openptrack",
            ros.as_str(),
            "--name",
            "kinect02",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", "rig.toml"]);
        bodyseg(d, &args)
    };
    let before = files_in(d);
    let out = import(&[]);
    assert_one_error(&out, d, &before, &["--from openptrack needs --poses"]);
    let poses = calib_fixture("openptrack/open_ptrack_v2/camera_poses.yaml");
    let out = import(&["--poses", arg(&poses)]);
    assert_ok(&out, "rig import --from openptrack");
    let rig = read_rig(&d.join("rig.toml")).expect("rig.toml reads");
    assert_eq!(rig.cameras.len(), 1);
    // kinect02's pose (translation 1.74838, -2.65512, 3.82138) places the colour sensor:
    // world_from_color = world_from_depth · depth_from_color.
    let cam = &rig.cameras[0];
    let world_from_color = cam
        .world_from_depth
        .compose(&cam.color_from_depth.inverse());
    let t = world_from_color.translation_m();
    for (got, want) in t.iter().zip([1.74838, -2.65512, 3.82138]) {
        assert!((got - want).abs() < 1e-5, "{t:?}");
    }
}
