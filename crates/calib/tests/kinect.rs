//! The real iai_kinect2 calibration in `../shared/data` (read with its exact values, bad
//! copies of it rejected with clear errors), the projection round trip over whole images
//! with its distortion, and depth back-projection.

use std::path::{Path, PathBuf};

mod common;
use common::{Rng, assert_round_trip, outer_corners, seed};

use bodyseg_calib::{
    BackProjectOptions, CalibError, CloudFrame, DepthBackProjector, Distortion, Intrinsics, Pose,
    RgbdCamera, back_project, read_iai_kinect2, testing,
};

/// The shared calibration folder; CI checks out `shared/` beside the repository.
fn kinect_dir() -> PathBuf {
    let dir = testing::kinect_v2_test_dir();
    assert!(
        dir.is_dir(),
        "test data missing: {} (the shared/ folder must sit beside the repository)",
        dir.display()
    );
    dir
}

fn kinect() -> RgbdCamera {
    read_iai_kinect2(&kinect_dir()).expect("the shared iai_kinect2 folder is valid")
}

/// Exact equality of one sensor's fx fy cx cy, Brown-Conrady coefficients and size.
fn assert_sensor(s: &Intrinsics, fx_fy_cx_cy: [f64; 4], brown_conrady: [f64; 5], size: (u32, u32)) {
    assert_eq!([s.fx, s.fy, s.cx, s.cy], fx_fy_cx_cy);
    assert_eq!(s.distortion, Distortion::BrownConrady(brown_conrady));
    assert_eq!((s.width, s.height), size);
}

#[test]
// The expected values are copied digit for digit from the files, as OpenCV printed them.
#[allow(clippy::excessive_precision)]
fn iai_kinect2_folder_loads_with_the_files_exact_values() {
    let cam = kinect();
    assert_eq!(cam.name, "196605135147");
    // Exact equality: Rust and OpenCV both print/parse f64 with correct rounding.
    assert_sensor(
        &cam.color,
        [
            1.0599465578241038e+03,
            1.0539326808799726e+03,
            9.5488326677588441e+02,
            5.2373858291060583e+02,
        ],
        [
            5.6268441170930321e-02,
            -7.4199141308694802e-02,
            1.4250797540545752e-03,
            -1.6951722389720336e-03,
            2.4107681263086548e-02,
        ],
        (1920, 1080),
    );
    assert_sensor(
        &cam.depth,
        [
            3.6694757270064110e+02,
            3.6479117165721783e+02,
            2.4298551682775121e+02,
            2.0769853575457685e+02,
        ],
        [
            9.6558110377123016e-02,
            -2.8298244017989416e-01,
            1.5889951609432634e-04,
            -5.0751483524871712e-04,
            1.0523948765859192e-01,
        ],
        (512, 424),
    );
    assert_eq!(
        cam.color_from_depth.translation_m(),
        [
            -5.2052476112081990e-02,
            -4.6313865353939110e-04,
            8.8806735554907584e-04
        ]
    );
    let r = cam.color_from_depth.rotation();
    assert_eq!(
        r[0],
        [
            9.9979883926593693e-01,
            -1.6871335541758126e-02,
            -1.0846153213119176e-02
        ]
    );
    assert_eq!(
        r[1],
        [
            1.6891097527572209e-02,
            9.9985583336600126e-01,
            1.7330055664057141e-03
        ]
    );
    assert_eq!(
        r[2],
        [
            1.0815351441312036e-02,
            -1.9158603854556545e-03,
            9.9993967700666042e-01
        ]
    );
    assert_eq!(cam.depth_shift_mm, -1.3354238655403018e+01);
    assert_eq!(cam.depth_scale, 1000.0);
    assert_eq!(cam.world_from_depth, Pose::identity());
    // X_c = R·X_ir + T: the IR origin sits at T in the colour frame (≈ 5.2 cm baseline).
    assert_eq!(
        cam.color_from_depth.transform_point([0.0; 3]),
        cam.color_from_depth.translation_m()
    );
}

/// Copies the shared folder to a temporary one, replacing `file` by `contents`
/// (`None`: deleting it).
fn broken_copy(file: &str, contents: Option<&str>) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().expect("temporary folder");
    for name in [
        "calib_color.yaml",
        "calib_ir.yaml",
        "calib_pose.yaml",
        "calib_depth.yaml",
    ] {
        std::fs::copy(kinect_dir().join(name), tmp.path().join(name)).expect("copy");
    }
    match contents {
        Some(text) => std::fs::write(tmp.path().join(file), text).expect("write"),
        None => std::fs::remove_file(tmp.path().join(file)).expect("remove"),
    }
    tmp
}

fn load_error(file: &str, contents: Option<&str>) -> (CalibError, String) {
    let tmp = broken_copy(file, contents);
    let err = read_iai_kinect2(tmp.path()).expect_err("broken folder must not load");
    let msg = err.to_string();
    assert!(
        msg.ends_with(file),
        "message must end with the file {file}: {msg}"
    );
    (err, msg)
}

fn assert_starts(msg: &str, prefix: &str) {
    assert!(msg.starts_with(prefix), "{msg}");
}

/// [`load_error`]'s message for the test camera's `file` with its first `from` replaced
/// by `to` (which must be there).
fn edited_error(file: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(kinect_dir().join(file)).expect("read");
    let broken = text.replacen(from, to, 1);
    assert_ne!(text, broken, "{from} is not in {file}");
    load_error(file, Some(&broken)).1
}

#[test]
fn missing_file_is_named() {
    let (err, msg) = load_error("calib_pose.yaml", None);
    assert!(matches!(err, CalibError::Read { .. }), "{msg}");
}

#[test]
fn missing_folder_is_named() {
    let err = read_iai_kinect2(Path::new("/nonexistent/kinect")).expect_err("no folder");
    assert!(err.to_string().ends_with("/nonexistent/kinect"), "{err}");
}

#[test]
fn matrix_with_wrong_number_of_values_is_named() {
    let msg = edited_error("calib_pose.yaml", "8.8806735554907584e-04 ]", "]");
    assert_starts(&msg, "translation: a 3x1 matrix needs 3 values, data has 2");
}

#[test]
fn non_numeric_entry_is_named() {
    let msg = edited_error("calib_color.yaml", "1.0599465578241038e+03", "1.05e+O3");
    assert_starts(
        &msg,
        "cameraMatrix: data[0] = \"1.05e+O3\" is not a finite number",
    );
    let (_, msg) = load_error("calib_depth.yaml", Some("%YAML:1.0\ndepthShift: abc\n"));
    assert_starts(&msg, "depthShift: \"abc\" is not a finite number");
}

#[test]
fn bad_values_are_named() {
    let msg = edited_error(
        "calib_ir.yaml",
        "3.6694757270064110e+02",
        "-3.6694757270064110e+02",
    );
    assert_starts(&msg, "cameraMatrix: fx must be finite and > 0");
    let msg = edited_error(
        "calib_pose.yaml",
        "9.9979883926593693e-01",
        "1.9979883926593693e-01",
    );
    assert_starts(&msg, "rotation: rotation is not orthonormal");
    let (_, msg) = load_error("calib_depth.yaml", Some("%YAML:1.0\nshift: 1\n"));
    assert_eq!(msg.split(':').next(), Some("missing key depthShift"));
}

/// Largest |project(unproject(u, v)·z) − (u, v)|, pixels, over the given pixels.
fn worst_round_trip(cam: &Intrinsics, pixels: impl Iterator<Item = ([f64; 2], f64)>) -> f64 {
    let mut worst = 0.0_f64;
    for ([u, v], z) in pixels {
        let ray = cam
            .unproject(u, v)
            .unwrap_or_else(|| panic!("({u}, {v}) must undistort"));
        let uv = cam
            .project(ray.map(|c| c * z))
            .expect("z > 0 is in front of the camera");
        worst = worst.max((uv[0] - u).abs()).max((uv[1] - v).abs());
    }
    worst
}

#[test]
fn round_trip_every_pixel_centre_of_both_kinect_sensors() {
    let cam = kinect();
    for (name, intr) in [("depth", cam.depth), ("color", cam.color)] {
        let pixels = (0..intr.height)
            .flat_map(move |v| (0..intr.width).map(move |u| ([f64::from(u), f64::from(v)], 1.7)));
        assert_round_trip(worst_round_trip(&intr, pixels), name);
    }
}

#[test]
fn round_trip_random_subpixel_points_and_depths() {
    let seed = seed();
    let mut rng = Rng::new(seed);
    let cam = kinect();
    for (name, intr) in [("depth", cam.depth), ("color", cam.color)] {
        let (w, h) = (f64::from(intr.width), f64::from(intr.height));
        // The image's outer edges (pixel borders at -0.5 and size - 0.5) are included.
        let corners = outer_corners(&intr);
        let mut samples: Vec<([f64; 2], f64)> = corners.iter().map(|&c| (c, 2.0)).collect();
        for _ in 0..50_000 {
            let uv = [rng.range_f64(-0.5, w - 0.5), rng.range_f64(-0.5, h - 0.5)];
            samples.push((uv, rng.range_f64(0.3, 10.0)));
        }
        assert_round_trip(
            worst_round_trip(&intr, samples.into_iter()),
            &format!("{name} (seed {seed}, BODYSEG_TEST_SEED to rerun)"),
        );
    }
}

/// A camera 2.2 m above the floor (world z up), looking forward and 35° down.
fn floor_camera() -> RgbdCamera {
    let mut cam = kinect();
    let tilt = 35f64.to_radians();
    let (s, c) = tilt.sin_cos();
    // Columns: the depth frame's x (right), y (down), z (forward) in world coordinates.
    // Optical z forward = (0, c, -s); y down = (0, -s, -c); x right = (1, 0, 0).
    let rotation = [[1.0, 0.0, 0.0], [0.0, -s, c], [0.0, -c, -s]];
    cam.world_from_depth =
        Pose::from_rotation_translation(rotation, [0.0, 0.0, 2.2]).expect("a rotation");
    cam
}

#[test]
fn floor_plane_back_projects_onto_the_floor() {
    let cam = floor_camera();
    let intr = cam.depth;
    let mut depth = vec![0u16; intr.num_pixels()];
    let mut expected = 0;
    for v in 0..intr.height {
        for u in 0..intr.width {
            let ray = intr
                .unproject(f64::from(u), f64::from(v))
                .expect("undistorts");
            // Ray in the world: R·ray; hits z = 0 at depth s = -2.2 / (R·ray)_z.
            let dir = cam.world_from_depth.transform_point(ray);
            let dz = dir[2] - 2.2;
            if dz >= 0.0 {
                continue;
            }
            // Raw depth is the metric depth minus the shift, in millimetres.
            let raw_mm = (-2.2 / dz) * 1000.0 - cam.depth_shift_mm;
            if raw_mm < 65535.0 {
                depth[(v * intr.width + u) as usize] = raw_mm.round() as u16;
                expected += 1;
            }
        }
    }
    let opts = BackProjectOptions::default();
    let out = back_project(&depth, &cam, 3, &opts).expect("valid input");
    assert_eq!(out.points_m.len(), expected);
    assert_eq!(out.origins.len(), expected);
    for (p, o) in out.points_m.iter().zip(&out.origins) {
        assert_eq!(o.camera, 3);
        assert_ne!(depth[o.pixel as usize], 0);
        // Raw depth is rounded to 0.5 mm; along a ray that is at most 0.5 mm·|ray| of
        // height (|ray| < 1.6 here), plus f32 rounding.
        assert!(
            p[2].abs() < 1e-3,
            "point {p:?} of pixel {} is off the floor",
            o.pixel
        );
    }
    // Origins are row-major and strictly increasing.
    assert!(out.origins.windows(2).all(|w| w[0].pixel < w[1].pixel));
}

#[test]
fn back_projected_pixels_project_back_to_themselves() {
    let seed = seed();
    let mut rng = Rng::new(seed ^ 0xBAC4);
    let cam = kinect();
    let projector = DepthBackProjector::new(&cam, 0).expect("valid camera");
    let opts = BackProjectOptions {
        frame: CloudFrame::Depth,
        ..BackProjectOptions::default()
    };
    let mut depth = vec![0u16; cam.depth.num_pixels()];
    for _ in 0..2_000 {
        let u = (rng.unit_f64() * f64::from(cam.depth.width)) as u32;
        let v = (rng.unit_f64() * f64::from(cam.depth.height)) as u32;
        let raw = rng.range_f64(500.0, 8000.0) as u16;
        let pixel = (v * cam.depth.width + u) as usize;
        depth[pixel] = raw;
        let out = projector.back_project(&depth, &opts).expect("valid input");
        depth[pixel] = 0;
        assert_eq!(out.points_m.len(), 1);
        assert_eq!(out.origins[0].pixel as usize, pixel);
        let p = out.points_m[0].map(f64::from);
        // z is the raw depth plus the shift (f32 storage: ~1e-7 relative).
        let z_want = f64::from(raw) / 1000.0 + cam.depth_shift_mm / 1000.0;
        assert!((p[2] - z_want).abs() < 1e-6, "z {} vs {z_want}", p[2]);
        let uv = cam.depth.project(p).expect("in front");
        // f32 positions (~6e-8 relative) move the projection by < 1e-4 px at f ≈ 367.
        assert!(
            (uv[0] - f64::from(u)).abs() < 1e-3 && (uv[1] - f64::from(v)).abs() < 1e-3,
            "pixel ({u}, {v}) came back at {uv:?} (seed {seed})"
        );
    }
}

/// A 4×3 pinhole depth camera without distortion, f = 2 px, centre (1.5, 1).
fn tiny_camera() -> RgbdCamera {
    let intr = Intrinsics::pinhole(4, 3, 2.0, 2.0, 1.5, 1.0);
    RgbdCamera::new("tiny", intr, intr)
}

#[test]
fn range_zero_stride_scale_and_shift() {
    let mut cam = tiny_camera();
    #[rustfmt::skip]
    let depth: Vec<u16> = vec![
        0,    1000, 2000, 3000,
        400,  500,  6000, 1500,
        1000, 0,    1000, 9000,
    ];
    let opts = BackProjectOptions {
        depth_min_m: 0.5,
        depth_max_m: 5.0,
        stride: 1,
        frame: CloudFrame::Depth,
    };
    let out = back_project(&depth, &cam, 1, &opts).expect("valid");
    let pixels: Vec<u32> = out.origins.iter().map(|o| o.pixel).collect();
    // 0 (no measurement), 0.4 m (< min), 6 m and 9 m (> max) give no point; 0.5 is kept.
    assert_eq!(pixels, vec![1, 2, 3, 5, 7, 8, 10]);
    // Pixel 5 = (u 1, v 1) at 0.5 m: x = (1 - 1.5) / 2 · 0.5.
    assert_eq!(out.points_m[3], [-0.125, 0.0, 0.5]);

    let strided = BackProjectOptions { stride: 2, ..opts };
    let out = back_project(&depth, &cam, 1, &strided).expect("valid");
    let pixels: Vec<u32> = out.origins.iter().map(|o| o.pixel).collect();
    // Rows 0 and 2, columns 0 and 2: pixels 0, 2, 8, 10 of which 0 has no depth.
    assert_eq!(pixels, vec![2, 8, 10]);

    // depth_scale 2000 units per metre (0.5 mm units) and a -100 mm shift.
    cam.depth_scale = 2000.0;
    cam.depth_shift_mm = -100.0;
    let out = back_project(&depth, &cam, 1, &opts).expect("valid");
    let z: Vec<f32> = out.points_m.iter().map(|p| p[2]).collect();
    // raw / 2000 - 0.1: 1000 → 0.4 (dropped), 2000 → 0.9, 3000 → 1.4, 6000 → 2.9,
    // 1500 → 0.65, 1000 → 0.4 (dropped), 9000 → 4.4; 400 and 500 → ≤ 0.15 (dropped).
    assert_eq!(z, vec![0.9, 1.4, 2.9, 0.65, 4.4]);
}

#[test]
fn wrong_depth_size_and_bad_options_are_errors() {
    let cam = tiny_camera();
    let err = back_project(&[1000; 11], &cam, 0, &BackProjectOptions::default())
        .expect_err("11 pixels for 4x3");
    assert_eq!(
        err.to_string(),
        "camera tiny: depth image has 11 pixels, calibration says 4x3"
    );
    let bad = BackProjectOptions {
        stride: 0,
        ..BackProjectOptions::default()
    };
    let err = back_project(&[1000; 12], &cam, 0, &bad).expect_err("stride 0");
    assert!(err.to_string().starts_with("stride "), "{err}");
    let bad = BackProjectOptions {
        depth_min_m: 2.0,
        depth_max_m: 1.0,
        ..BackProjectOptions::default()
    };
    let err = back_project(&[1000; 12], &cam, 0, &bad).expect_err("max < min");
    assert!(err.to_string().starts_with("depth_max_m "), "{err}");
}
