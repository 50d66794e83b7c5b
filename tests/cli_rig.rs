//! `bodyseg rig import` of the real iai_kinect2 calibration in `../shared/data`, then
//! `bodyseg rig show`; bad input: a folder missing a file, repeated camera names.

use crate::common::{assert_ok, bodyseg, files_in, stderr, stdout, tempdir};
use bodyseg_pipeline::read_rig;
use std::path::{Path, PathBuf};

/// The real iai_kinect2 folder of a Kinect v2 (serial 196605135147).
fn kinect2_folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/iai_kinect2/196605135147")
}

/// Copies the real folder's files into `dir/name`.
fn copy_folder(dir: &Path, name: &str) -> PathBuf {
    let to = dir.join(name);
    std::fs::create_dir(&to).expect("create camera folder");
    for entry in std::fs::read_dir(kinect2_folder()).expect("read ../shared/data/iai_kinect2") {
        let from = entry.expect("dir entry").path();
        let file = from.file_name().expect("a file name");
        std::fs::copy(&from, to.join(file)).expect("copy calibration file");
    }
    to
}

/// Exit status 1, one `error:` line holding every needle, and no rig.toml written.
fn assert_fails(out: &std::process::Output, d: &Path, before: &[String], needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "want one error line:\n{err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for needle in needles {
        assert!(lines[0].contains(needle), "{needle:?} not in: {err}");
    }
    assert_eq!(files_in(d), before, "files changed after: {err}");
}

#[test]
fn import_two_cameras_then_show() {
    let dir = tempdir();
    let d = dir.path();
    copy_folder(d, "kinect_a");
    copy_folder(d, "kinect_b");
    let out = bodyseg(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "kinect_a",
            "kinect_b",
            "--out",
            "rig.toml",
        ],
    );
    assert_ok(&out, "bodyseg rig import");
    let err = stderr(&out);
    assert!(
        err.lines()
            .any(|l| l.starts_with("import ") && l.contains(" ms  2 cameras → rig.toml")),
        "{err}"
    );
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

    let out = bodyseg(d, &["rig", "show", "rig.toml"]);
    assert_ok(&out, "bodyseg rig show");
    let text = stdout(&out);
    for needle in [
        "2 cameras",
        "kinect_a",
        "kinect_b",
        "fx 1059.95",
        "baseline 52.1 mm",
    ] {
        assert!(text.contains(needle), "{needle:?} not in:\n{text}");
    }
}

#[test]
fn names_and_no_note_with_world_from_depth_identity() {
    let dir = tempdir();
    let d = dir.path();
    copy_folder(d, "k");
    let out = bodyseg(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "k",
            "--name",
            "front",
            "--world-from-depth-identity",
            "--out",
            "rig.toml",
        ],
    );
    assert_ok(&out, "bodyseg rig import --name");
    assert!(!stderr(&out).contains("note:"), "{}", stderr(&out));
    let rig = read_rig(&d.join("rig.toml")).expect("rig.toml reads back");
    assert_eq!(rig.cameras.len(), 1);
    assert_eq!(rig.cameras[0].name, "front");
}

#[test]
fn folder_without_calib_pose_names_the_file() {
    let dir = tempdir();
    let d = dir.path();
    copy_folder(d, "good");
    let bad = copy_folder(d, "bad");
    std::fs::remove_file(bad.join("calib_pose.yaml")).expect("remove calib_pose.yaml");
    let before = files_in(d);
    let out = bodyseg(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "good",
            "bad",
            "--out",
            "rig.toml",
        ],
    );
    assert_fails(&out, d, &before, &["calib_pose.yaml"]);
    // The cause once, not also chained as a source.
    let err = stderr(&out);
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

#[test]
fn repeated_camera_names_are_named() {
    let dir = tempdir();
    let d = dir.path();
    copy_folder(d, "a");
    copy_folder(d, "b");
    let before = files_in(d);
    let out = bodyseg(
        d,
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "a",
            "b",
            "--name",
            "cam0",
            "--name",
            "cam0",
            "--out",
            "rig.toml",
        ],
    );
    assert_fails(&out, d, &before, &["\"cam0\"", "used twice"]);
}

#[test]
fn show_of_a_missing_rig_names_the_file() {
    let dir = tempdir();
    let d = dir.path();
    let out = bodyseg(d, &["rig", "show", "nope.toml"]);
    assert_fails(&out, d, &[], &["nope.toml"]);
}

#[test]
fn import_help_names_the_flags_and_the_world_pose_gap() {
    let dir = tempdir();
    let out = bodyseg(dir.path(), &["rig", "import", "--help"]);
    assert_ok(&out, "bodyseg rig import --help");
    let text = stdout(&out);
    for needle in [
        "--from",
        "iai_kinect2",
        "--name",
        "--world-from-depth-identity",
        "--out",
        "identity",
        "bodyseg calibrate world",
        "Examples:",
    ] {
        assert!(text.contains(needle), "{needle:?} not in:\n{text}");
    }
}
