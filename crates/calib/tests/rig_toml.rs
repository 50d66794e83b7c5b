//! `rig.toml` (FORMATS.md): the documented example reads, a rig writes and re-reads without
//! loss, bad files give errors naming camera, field and file.

use std::path::Path;

use bodyseg_calib::{
    Intrinsics, Pose, RgbdCamera, Rig, parse_rig_toml, read_iai_kinect2, read_rig_toml,
    rig_to_toml_string, write_rig_toml,
};

/// FORMATS.md's example, with a concrete world rotation (camera looking along world +y,
/// level) given as a quaternion, and an unknown key that readers must ignore.
const EXAMPLE: &str = r#"
comment = "unknown top-level keys are ignored"

[[camera]]
name = "cam0"
depth_scale = 1000.0          # raw depth units per metre
depth_shift_mm = 0.0          # added to raw depth (iai_kinect2 depthShift)
serial = "ignored too"

[camera.depth]                # depth (IR) sensor
width = 512
height = 424
fx = 366.9
fy = 364.8
cx = 243
cy = 207.7
distortion = [0.0966, -0.283, 0.000159, -0.000508, 0.105]   # k1 k2 p1 p2 k3

[camera.color]                # colour sensor, same fields
width = 1920
height = 1080
fx = 1059.9
fy = 1053.9
cx = 954.9
cy = 523.7
distortion = [0.0563, -0.0742, 0.00143, -0.00170, 0.0241]

[camera.color_from_depth]     # maps a point in the depth frame into the colour frame
rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
translation_m = [-0.052, 0.0, 0.0]

[camera.world_from_depth]     # maps a point in the depth frame into the world frame (z up)
quaternion_wxyz = [0.7071067811865476, -0.7071067811865476, 0.0, 0.0]
translation_m = [0.0, -3.0, 2.2]

[[camera]]
name = "cam1"

[camera.depth]
width = 512
height = 424
fx = 366.9
fy = 364.8
cx = 243.0
cy = 207.7
distortion = [0.0, 0.0, 0.0, 0.0, 0.0]

[camera.color]
width = 1920
height = 1080
fx = 1059.9
fy = 1053.9
cx = 954.9
cy = 523.7
distortion = [0.0, 0.0, 0.0, 0.0, 0.0]

[camera.color_from_depth]
rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
translation_m = [-0.052, 0.0, 0.0]

[camera.world_from_depth]
rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
translation_m = [0.0, 0.0, 0.0]
"#;

fn example() -> Rig {
    parse_rig_toml(EXAMPLE, Path::new("rig.toml")).expect("FORMATS.md example is valid")
}

#[test]
fn formats_md_example_reads() {
    let rig = example();
    assert_eq!(rig.cameras.len(), 2);
    let cam = &rig.cameras[0];
    assert_eq!(cam.name, "cam0");
    assert_eq!(cam.depth.cx, 243.0, "integers are accepted as numbers");
    assert_eq!(cam.color.fx, 1059.9);
    assert_eq!(cam.depth.distortion.coefficients()[4], 0.105);
    assert_eq!(cam.color_from_depth.translation_m(), [-0.052, 0.0, 0.0]);
    // Rotation of -90° about x: optical z (forward) becomes world +y, optical y (down)
    // becomes world -z. Tolerance: products of 0.7071…, exact to ~1e-16.
    let forward = cam.world_from_depth.transform_point([0.0, 0.0, 1.0]);
    let down = cam.world_from_depth.transform_point([0.0, 1.0, 0.0]);
    for (got, want) in forward.iter().zip([0.0, -2.0, 2.2]) {
        assert!((got - want).abs() < 1e-12, "{forward:?}");
    }
    for (got, want) in down.iter().zip([0.0, -3.0, 1.2]) {
        assert!((got - want).abs() < 1e-12, "{down:?}");
    }
    // Defaults of the second camera.
    assert_eq!(rig.cameras[1].depth_scale, 1000.0);
    assert_eq!(rig.cameras[1].depth_shift_mm, 0.0);
    assert_eq!(rig.camera("cam1").map(|(i, _)| i), Some(1));
}

#[test]
fn rig_writes_and_rereads_without_loss() {
    let mut rig = example();
    // Add the real Kinect (17-digit values, non-trivial rotation, negative shift).
    let kinect_dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/iai_kinect2/196605135147");
    assert!(
        kinect_dir.is_dir(),
        "test data missing: {}",
        kinect_dir.display()
    );
    let mut kinect = read_iai_kinect2(&kinect_dir).expect("valid folder");
    kinect.depth_scale = 999.5;
    kinect.world_from_depth =
        Pose::from_quaternion_wxyz([0.5, 0.5, -0.5, 0.5], [1.0 / 3.0, -2.0e-7, 1e20])
            .expect("unit quaternion");
    rig.cameras.push(kinect);

    let tmp = tempfile::tempdir().expect("temporary folder");
    let path = tmp.path().join("rig.toml");
    write_rig_toml(&rig, &path).expect("writable");
    let back = read_rig_toml(&path).expect("what was written reads back");
    assert_eq!(back, rig, "bit-exact round trip");
    // Writing again gives the same text.
    assert_eq!(
        rig_to_toml_string(&back).expect("valid"),
        std::fs::read_to_string(&path).expect("read")
    );
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(tmp.path())
        .expect("list")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("rig.toml")]);
}

#[test]
fn writer_refuses_an_invalid_rig() {
    let intr = Intrinsics::pinhole(4, 3, 2.0, 2.0, 1.5, 1.0);
    let cam = RgbdCamera::new("a", intr, intr);
    let rig = Rig {
        cameras: vec![cam.clone(), cam],
    };
    let tmp = tempfile::tempdir().expect("temporary folder");
    let path = tmp.path().join("rig.toml");
    let err = write_rig_toml(&rig, &path).expect_err("duplicate names");
    assert!(
        err.to_string().contains("used by an earlier camera"),
        "{err}"
    );
    assert!(!path.exists(), "nothing written");
}

/// Parses `EXAMPLE` with `from` replaced by `to` and returns the error message.
fn error_for(from: &str, to: &str) -> String {
    assert!(EXAMPLE.contains(from), "test edit {from:?} does not apply");
    let text = EXAMPLE.replacen(from, to, 1);
    parse_rig_toml(&text, Path::new("calib/rig.toml"))
        .expect_err("broken rig must not load")
        .to_string()
}

#[test]
fn errors_name_camera_field_and_file() {
    let cases = [
        (
            "fx = 366.9",
            "fx = \"366.9\"",
            "camera cam0: depth.fx must be a number, got string: calib/rig.toml",
        ),
        (
            "fx = 366.9",
            "fx = -366.9",
            "camera cam0: depth.fx must be finite and > 0, got -366.9: calib/rig.toml",
        ),
        (
            "fy = 364.8\n",
            "",
            "camera cam0: depth.fy is missing: calib/rig.toml",
        ),
        (
            "width = 1920",
            "width = 1920.0",
            "camera cam0: color.width must be an integer, got float: calib/rig.toml",
        ),
        (
            "distortion = [0.0563, -0.0742, 0.00143, -0.00170, 0.0241]",
            "distortion = [0.0563, -0.0742, 0.00143, -0.00170]",
            "camera cam0: color.distortion must have 5 numbers (k1 k2 p1 p2 k3) or 8 (rational model: k1 k2 p1 p2 k3 k4 k5 k6), got 4 values: calib/rig.toml",
        ),
        (
            "rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
            "rotation = [[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
            "camera cam0: color_from_depth.rotation is not orthonormal",
        ),
        (
            "quaternion_wxyz = [0.7071067811865476, -0.7071067811865476, 0.0, 0.0]",
            "quaternion_wxyz = [0.7, -0.6, 0.0, 0.0]",
            "camera cam0: world_from_depth.quaternion_wxyz must have norm 1",
        ),
        (
            "quaternion_wxyz = [0.7071067811865476, -0.7071067811865476, 0.0, 0.0]",
            "",
            "camera cam0: world_from_depth.rotation is missing (give rotation or quaternion_wxyz): calib/rig.toml",
        ),
        (
            "translation_m = [0.0, -3.0, 2.2]",
            "",
            "camera cam0: world_from_depth.translation_m is missing: calib/rig.toml",
        ),
        (
            "depth_scale = 1000.0",
            "depth_scale = 0.0",
            "camera cam0: depth_scale must be finite and > 0, got 0: calib/rig.toml",
        ),
        (
            "name = \"cam1\"",
            "name = \"cam0\"",
            "camera[1].name: \"cam0\" is used by an earlier camera: calib/rig.toml",
        ),
        (
            "name = \"cam1\"",
            "",
            "camera #1: name is missing: calib/rig.toml",
        ),
        (
            "[camera.world_from_depth]\nrotation",
            "[camera.world_from_depth_]\nrotation",
            "camera cam1: world_from_depth is missing: calib/rig.toml",
        ),
    ];
    for (from, to, want) in cases {
        let msg = error_for(from, to);
        assert!(
            msg.starts_with(want),
            "editing {from:?} → {to:?}:\n got  {msg}\n want {want}"
        );
        assert!(msg.ends_with("calib/rig.toml"), "{msg}");
    }
}

#[test]
fn syntax_errors_and_empty_rigs_name_the_file() {
    let err = parse_rig_toml("[[camera]\nname = 1", Path::new("r.toml")).expect_err("bad TOML");
    assert!(err.to_string().starts_with("line 1: "), "{err}");
    assert!(err.to_string().ends_with("r.toml"), "{err}");
    let err = parse_rig_toml("title = \"no cameras\"\n", Path::new("r.toml")).expect_err("empty");
    assert!(
        err.to_string().starts_with("missing key [[camera]]"),
        "{err}"
    );
    let err = read_rig_toml(Path::new("/nonexistent/rig.toml")).expect_err("no file");
    assert!(err.to_string().ends_with("/nonexistent/rig.toml"), "{err}");
}
