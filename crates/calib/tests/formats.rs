//! Vendor calibration formats: ROS `camera_info`, OpenPTrack `camera_poses.yaml`, Azure
//! Kinect factory JSON and the iai_kinect2 writer. For each: a small hand-written fixture
//! in the real tool's layout (tests/data/) read with its exact values, a write → read
//! round trip, and bad input rejected with an error naming the file and the key.

// Expected values are copied digit for digit from the fixtures.
#![allow(clippy::excessive_precision)]

use std::path::{Path, PathBuf};

use bodyseg_calib::{
    AzureKinectMode, CalibError, Distortion, Intrinsics, Pose, RgbdCamera,
    azure_kinect_json_to_string, parse_azure_kinect_json, parse_openptrack_poses,
    parse_ros_camera_info, read_azure_kinect_json, read_iai_kinect2, read_openptrack_poses,
    read_ros_camera_info, write_azure_kinect_json, write_iai_kinect2, write_openptrack_poses,
    write_ros_camera_info,
};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn fixture_text(name: &str) -> String {
    std::fs::read_to_string(data(name)).expect("fixture exists")
}

/// Asserts that an error's message starts with `key` and ends with the file name.
fn assert_names(err: &CalibError, key: &str, file: &str) {
    let msg = err.to_string();
    assert!(
        msg.contains(key) && msg.ends_with(file),
        "error should name {key} and {file}: {msg}"
    );
}

fn intrinsics(width: u32, height: u32) -> Intrinsics {
    Intrinsics::pinhole(
        width,
        height,
        612.345_678_901_234_5,
        611.987_654_321_098_7,
        638.123_456_789,
        367.987_654_321,
    )
    .with_distortion(Distortion::BrownConrady([
        0.123_456_789,
        -0.234_567_891,
        1.5e-4,
        -2.25e-5,
        0.045_678_9,
    ]))
}

fn camera() -> RgbdCamera {
    let mut cam = RgbdCamera::new("cam7", intrinsics(640, 576), intrinsics(1280, 720));
    cam.color_from_depth =
        Pose::from_quaternion_wxyz([0.999, 0.02, -0.035, 0.011], [-0.032, -0.0019, 0.004])
            .expect("valid pose");
    cam
}

// ---------------------------------------------------------------- ROS camera_info

#[test]
fn ros_fixture_reads_exact_values() {
    let info = read_ros_camera_info(&data("ros_camera_info.yaml")).expect("valid fixture");
    assert_eq!(info.camera_name, "narrow_stereo");
    assert_eq!(
        info.intrinsics,
        Intrinsics::pinhole(640, 480, 430.215550, 430.531693, 306.691343, 227.224800)
            .with_distortion(Distortion::BrownConrady([
                -0.337586, 0.111612, -0.000218, -0.000030, 0.0
            ]))
    );
}

#[test]
fn ros_write_then_read_is_bit_exact() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("cam.yaml");
    let want = intrinsics(1920, 1080);
    write_ros_camera_info(&path, "rgb_cam", &want).expect("writes");
    let info = read_ros_camera_info(&path).expect("reads back");
    assert_eq!(info.camera_name, "rgb_cam");
    assert_eq!(info.intrinsics, want, "floats are written round-trip exact");
}

#[test]
fn ros_bad_input_names_file_and_key() {
    let text = fixture_text("ros_camera_info.yaml");
    let file = Path::new("bad_info.yaml");
    let err = parse_ros_camera_info(&text.replace("plumb_bob", "equidistant"), file)
        .expect_err("fisheye model");
    assert_names(
        &err,
        "distortion_model: \"equidistant\" is not supported",
        "bad_info.yaml",
    );
    let err = parse_ros_camera_info(&text.replace("[430.215550,", "[-430.215550,"), file)
        .expect_err("negative focal length");
    assert_names(&err, "camera_matrix: fx", "bad_info.yaml");
    let err =
        parse_ros_camera_info(&text.replace("cols: 5", "cols: 4"), file).expect_err("wrong shape");
    assert_names(
        &err,
        "distortion_coefficients.data: a 1x4 matrix needs 4 values, got 5",
        "bad_info.yaml",
    );
    let err = parse_ros_camera_info(&text.replace("image_height: 480\n", ""), file)
        .expect_err("missing size");
    assert_eq!(err.to_string(), "missing key image_height: bad_info.yaml");
    let err = parse_ros_camera_info(&text.replace("0.111612", ".nan"), file)
        .expect_err("NaN coefficient");
    assert_names(&err, "distortion_coefficients.data[1]", "bad_info.yaml");
    let err = parse_ros_camera_info("image_width: [1, 2\n", file).expect_err("syntax");
    assert!(matches!(err, CalibError::Syntax { .. }), "{err}");
}

// ---------------------------------------------------------------- OpenPTrack

#[test]
fn openptrack_fixture_reads_sensors_in_file_order() {
    let poses =
        read_openptrack_poses(&data("openptrack_camera_poses.yaml")).expect("valid fixture");
    let names: Vec<&str> = poses.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["kinect2_head", "kinect2_far"]);
    assert_eq!(poses[0].1.translation_m(), [1.25, -2.5, 2.1]);
    let want = Pose::from_quaternion_wxyz(
        [0.497571048, 0.178935749, -0.80521087, 0.268403623],
        [1.25, -2.5, 2.1],
    )
    .expect("valid");
    assert_eq!(poses[0].1, want);
    // world_from_sensor: the sensor origin is at the translation in the world.
    assert_eq!(poses[1].1.transform_point([0.0; 3]), [-0.75, 3.0, 1.95]);
}

#[test]
fn openptrack_write_then_read_round_trips() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("camera_poses.yaml");
    let want = vec![
        ("b_cam".to_string(), camera().color_from_depth),
        (
            "a cam: odd/name".to_string(),
            Pose::from_quaternion_wxyz([0.0, 0.0, 1.0, 0.0], [1e-9, -3.0, 2.2]).expect("valid"),
        ),
        ("ident".to_string(), Pose::identity()),
    ];
    write_openptrack_poses(&path, &want).expect("writes");
    let got = read_openptrack_poses(&path).expect("reads back");
    assert_eq!(got.len(), want.len());
    for ((gn, gp), (wn, wp)) in got.iter().zip(&want) {
        assert_eq!(gn, wn);
        assert_eq!(
            gp.translation_m(),
            wp.translation_m(),
            "translations are exact"
        );
        // Rotation → quaternion → rotation: a few ulps per element.
        for (gr, wr) in gp.rotation().iter().zip(wp.rotation()) {
            for (g, w) in gr.iter().zip(wr) {
                assert!((g - w).abs() < 1e-14, "{gn}: {g} vs {w}");
            }
        }
    }
}

#[test]
fn openptrack_top_level_layout_and_bad_input() {
    let top = "cam0:\n  translation: {x: 1, y: 2, z: 3}\n  rotation: {x: 0, y: 0, z: 0, w: 1}\n";
    let poses = parse_openptrack_poses(top, Path::new("p.yaml")).expect("top-level layout");
    assert_eq!(
        poses,
        vec![(
            "cam0".to_string(),
            Pose::from_quaternion_wxyz([1.0, 0.0, 0.0, 0.0], [1.0, 2.0, 3.0]).expect("valid")
        )]
    );

    let text = fixture_text("openptrack_camera_poses.yaml");
    let file = Path::new("bad_poses.yaml");
    let err = parse_openptrack_poses(&text.replace("w: 0.497571048", "w: 1.497571048"), file)
        .expect_err("not a unit quaternion");
    assert_names(&err, "poses.kinect2_head.rotation", "bad_poses.yaml");
    let err =
        parse_openptrack_poses(&text.replace("      z: 1.95\n", ""), file).expect_err("missing z");
    assert_eq!(
        err.to_string(),
        "missing key poses.kinect2_far.translation.z: bad_poses.yaml"
    );
    let err = parse_openptrack_poses(&text.replace("y: 3.0", "y: three"), file)
        .expect_err("not a number");
    assert_names(
        &err,
        "poses.kinect2_far.translation.y: must be a number",
        "bad_poses.yaml",
    );
    let err = parse_openptrack_poses("calibration_id: 3\n", file).expect_err("no sensors");
    assert!(matches!(err, CalibError::MissingKey { .. }), "{err}");
}

// ---------------------------------------------------------------- Azure Kinect

#[test]
fn azure_fixture_converts_normalised_intrinsics() {
    let cal = read_azure_kinect_json(
        &data("azure_kinect_calibration.json"),
        "k4a",
        AzureKinectMode::default(),
    )
    .expect("valid fixture");
    let cam = &cal.camera;
    assert_eq!(cam.name, "k4a");
    assert_eq!((cam.depth.width, cam.depth.height), (1024, 1024));
    assert_eq!((cam.color.width, cam.color.height), (4096, 3072));
    // Same arithmetic as the reader, so exact: cx = cx_n · W − 0.5, fx = fx_n · W.
    assert_eq!(cam.depth.cx, 0.50114387273788452 * 1024.0 - 0.5);
    assert_eq!(cam.depth.cy, 0.50732219219207764 * 1024.0 - 0.5);
    assert_eq!(cam.depth.fx, 0.49273908138275146 * 1024.0);
    assert_eq!(cam.color.fy, 0.63674253225326538 * 3072.0);
    assert_eq!(cam.color.cx, 0.49896752834320068 * 4096.0 - 0.5);
    // k1 k2 p1 p2 k3 k4 k5 k6 from k1 k2 k3 k4 k5 k6 codx cody p2 p1.
    let Distortion::Rational(d) = cam.color.distortion else {
        panic!("the SDK's model is rational: {:?}", cam.color.distortion);
    };
    assert_eq!(
        d[..5],
        [
            0.58426177501678467,
            -2.8537509441375732,
            -0.00017838436178863049,
            0.00075648567872121930,
            1.6613825559616089
        ]
    );
    assert_eq!(
        cam.color_from_depth.translation_m(),
        [
            -0.032025460153818130,
            -0.0019204617710784078,
            0.0040113222785294056
        ]
    );
    assert_eq!(cam.color_from_depth.rotation()[1][2], -0.09915872701782413);
    assert_eq!(cam.world_from_depth, Pose::identity());
    // k4, k5, k6 are kept: nothing dropped, nothing to note.
    assert!(cal.notes.is_empty(), "{:?}", cal.notes);
}

#[test]
fn azure_write_then_read_round_trips() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("calibration.json");
    let want = camera();
    write_azure_kinect_json(&path, &want).expect("writes");
    let cal =
        read_azure_kinect_json(&path, "cam7", AzureKinectMode::default()).expect("reads back");
    assert!(cal.notes.is_empty(), "{:?}", cal.notes);
    let got = &cal.camera;
    assert_eq!(got.name, want.name);
    assert_eq!(
        got.color_from_depth, want.color_from_depth,
        "poses are exact"
    );
    for (g, w) in [(&got.depth, &want.depth), (&got.color, &want.color)] {
        assert_eq!((g.width, g.height), (w.width, w.height));
        // Brown-Conrady is written as the rational model with k4 = k5 = k6 = 0.
        assert_eq!(
            g.distortion.rational_coefficients(),
            w.distortion.rational_coefficients(),
            "coefficients are exact"
        );
        // (cx + 0.5) / W · W − 0.5 and fx / W · W: a few ulps of ~1000 px.
        for (a, b) in [(g.fx, w.fx), (g.fy, w.fy), (g.cx, w.cx), (g.cy, w.cy)] {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }
    let mut scaled = camera();
    scaled.depth_scale = 500.0;
    let err = azure_kinect_json_to_string(&scaled).expect_err("depth scale not representable");
    assert!(err.to_string().starts_with("depth_scale"), "{err}");
}

#[test]
fn azure_bad_input_names_file_and_key() {
    let text = fixture_text("azure_kinect_calibration.json");
    let parse = |text: &str| {
        parse_azure_kinect_json(
            text,
            "k",
            Path::new("bad_k4a.json"),
            AzureKinectMode::default(),
        )
    };
    // (edit of the fixture, what is wrong, the key the error must name)
    let cases = [
        (
            (
                "\"ModelParameters\": [0.50114387273788452, ",
                "\"ModelParameters\": [",
            ),
            "13 parameters",
            "CalibrationInformation.Cameras[0].Intrinsics.ModelParameters: needs 14 values",
        ),
        (
            ("LocationPV0", "LocationPV1"),
            "no colour camera",
            "CameraLocationPV0",
        ),
        (
            ("0.9999832459018021", "0.9"),
            "not a rotation",
            "Cameras[1].Rt.Rotation",
        ),
        (
            ("\"SensorWidth\": 1024", "\"SensorWidth\": 0"),
            "zero width",
            "Cameras[0].SensorWidth",
        ),
    ];
    for ((from, to), what, key) in cases {
        let err = parse(&text.replace(from, to)).expect_err(what);
        assert_names(&err, key, "bad_k4a.json");
    }
    let err = parse("{\"CalibrationInformation\": [").expect_err("syntax");
    assert!(matches!(err, CalibError::Syntax { .. }), "{err}");
}

// ---------------------------------------------------------------- iai_kinect2 writer

/// The shared calibration folder; CI checks out `shared/` beside the repository.
fn kinect_dir() -> PathBuf {
    bodyseg_calib::testing::kinect_v2_test_dir()
}

#[test]
fn iai_kinect2_write_then_read_is_bit_exact() {
    let original = read_iai_kinect2(&kinect_dir()).expect("shared folder is valid");
    let tmp = tempfile::tempdir().expect("temp dir");
    let dir = tmp.path().join("196605135147");
    write_iai_kinect2(&dir, &original).expect("writes");
    // Bit-exact: every double is printed with 17 significant digits.
    assert_eq!(read_iai_kinect2(&dir).expect("reads back"), original);
    // The written files are the tool's: same keys and, for the intrinsics, the same text.
    for file in ["calib_color.yaml", "calib_ir.yaml", "calib_depth.yaml"] {
        let ours = std::fs::read_to_string(dir.join(file)).expect("written");
        let theirs = std::fs::read_to_string(kinect_dir().join(file)).expect("shared");
        assert_eq!(ours, theirs, "{file}");
    }

    // A non-Kinect camera (sizes written explicitly, a shift) also round-trips exactly.
    let mut cam = camera();
    cam.depth_shift_mm = -13.354_238_655_403_018;
    let dir = tmp.path().join("cam7");
    write_iai_kinect2(&dir, &cam).expect("writes");
    let mut back = read_iai_kinect2(&dir).expect("reads back");
    assert_eq!(back.name, "cam7");
    back.world_from_depth = cam.world_from_depth;
    assert_eq!(back, cam);

    cam.depth_scale = 1.0;
    let err = write_iai_kinect2(&tmp.path().join("x"), &cam).expect_err("scale");
    assert!(err.to_string().starts_with("depth_scale"), "{err}");
}

#[test]
fn iai_kinect2_pose_file_matches_the_tools_stereo_matrices() {
    let original = read_iai_kinect2(&kinect_dir()).expect("shared folder is valid");
    let tmp = tempfile::tempdir().expect("temp dir");
    write_iai_kinect2(tmp.path(), &original).expect("writes");
    let parse = |path: &Path, key: &str| -> Vec<f64> {
        let text = std::fs::read_to_string(path).expect("readable");
        let start = text.find(&format!("{key}: ")).expect("key present");
        let data = &text[start..];
        let open = data.find('[').expect("data");
        let close = data.find(']').expect("data end");
        data[open + 1..close]
            .split(',')
            .map(|s| s.trim().parse().expect("number"))
            .collect()
    };
    for key in ["essential", "fundamental"] {
        let ours = parse(&tmp.path().join("calib_pose.yaml"), key);
        let theirs = parse(&kinect_dir().join("calib_pose.yaml"), key);
        let scale = theirs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (o, t) in ours.iter().zip(&theirs) {
            // The tool computed these from its own (unrounded) state; 1e-6 of the largest
            // entry is far below anything that matters and above float noise.
            assert!((o - t).abs() <= 1e-6 * scale, "{key}: {o} vs {t}");
        }
    }
}
