//! Real calibration files of other tools (`tests/fixtures/calib/`, sources and licences in
//! its `SOURCES.md`) import with the values those tools use: iai_kinect2 folders of other
//! serials (one without `calib_depth.yaml`), OpenPTrack `camera_poses.yaml` outputs, ROS
//! `camera_info` files, Azure Kinect factory JSON. Values are typed from the files; the
//! Azure Kinect cameras are checked against the SDK's own projection, written out here
//! from its source, and against projections the SDK computed (recorded in its tests and in
//! pyk4a's).

// Expected values are typed digit for digit from the files.
#![allow(clippy::excessive_precision)]

use std::path::{Path, PathBuf};

use bodyseg_calib::{
    AzureColorResolution, AzureDepthMode, AzureKinectMode, CalibError, Distortion, Intrinsics,
    Pose, RgbdCamera, import_iai_kinect2, parse_azure_kinect_json, parse_openptrack_poses,
    parse_ros_camera_info, read_azure_kinect_json, read_openptrack_poses, read_ros_camera_info,
};

fn fixture(rel: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/fixtures/calib")
        .join(rel);
    assert!(path.exists(), "fixture missing: {}", path.display());
    path
}

fn text(rel: &str) -> String {
    std::fs::read_to_string(fixture(rel)).expect("fixture reads")
}

// ---------------------------------------------------------------- iai_kinect2

#[test]
fn iai_kinect2_upstream_folder_without_depth_file_has_shift_0_and_a_note() {
    let imported = import_iai_kinect2(&fixture("iai_kinect2/299150235147")).expect("imports");
    let cam = &imported.camera;
    assert_eq!(cam.name, "299150235147");
    // kinect2_bridge: no calib_depth.yaml → "using defaults for depth shift", 0.
    assert_eq!(cam.depth_shift_mm, 0.0);
    assert_eq!(imported.notes.len(), 1, "{:?}", imported.notes);
    assert!(
        imported.notes[0].starts_with("no calib_depth.yaml: depth shift 0 mm")
            && imported.notes[0].ends_with("299150235147"),
        "{}",
        imported.notes[0]
    );
    // calib_ir.yaml: cameraMatrix data[0], data[2]; distortionCoefficients data[0], [4].
    assert_eq!(cam.depth.fx, 3.6638346288148574e+02);
    assert_eq!(cam.depth.cx, 2.5564531890330468e+02);
    let k = cam.depth.distortion.coefficients();
    assert_eq!(
        (k[0], k[4]),
        (1.0952761399998089e-01, 1.2565382780717374e-01)
    );
    assert!(!cam.depth.distortion.is_rational());
    // calib_pose.yaml: rotation data[1] (row 0, column 1).
    assert_eq!(
        cam.color_from_depth.rotation()[0][1],
        1.1418659978192800e-03
    );
    assert_eq!((cam.depth.width, cam.color.width), (512, 1920));
}

#[test]
fn iai_kinect2_user_folder_reads_its_values() {
    let imported = import_iai_kinect2(&fixture("iai_kinect2/019469645147")).expect("imports");
    assert!(imported.notes.is_empty(), "{:?}", imported.notes);
    let cam = &imported.camera;
    // calib_depth.yaml: depthShift.
    assert_eq!(cam.depth_shift_mm, -1.7729753302207246e+01);
    // calib_color.yaml: cameraMatrix data[0], data[5].
    assert_eq!(cam.color.fx, 1.0572316570237249e+03);
    assert_eq!(cam.color.cy, 5.4862386238809040e+02);
    // calib_ir.yaml: distortionCoefficients data[4] = k3.
    assert_eq!(
        cam.depth.distortion.coefficients()[4],
        9.4840977067938342e-02
    );
    // calib_pose.yaml: translation data[0], metres.
    assert_eq!(
        cam.color_from_depth.translation_m()[0],
        -5.1298279314998606e-02
    );
}

// ---------------------------------------------------------------- OpenPTrack

fn assert_matrix_close(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], tol: f64, what: &str) {
    for r in 0..3 {
        for c in 0..3 {
            assert!(
                (a[r][c] - b[r][c]).abs() <= tol,
                "{what}: [{r}][{c}] {} vs {}",
                a[r][c],
                b[r][c]
            );
        }
    }
}

/// `opt_calibration` also writes `inverse_poses:` (sensor_from_world); read them as a
/// `poses:` document.
fn inverse_poses(rel: &str) -> Vec<(String, Pose)> {
    let t = text(rel);
    let (_, inverse) = t
        .split_once("inverse_poses:")
        .expect("opt_calibration writes both");
    parse_openptrack_poses(&format!("poses:{inverse}"), Path::new(rel)).expect("parses")
}

#[test]
fn openptrack_outputs_read_world_from_sensor_poses() {
    let rel = "openptrack/open_ptrack_v2/camera_poses.yaml";
    let poses = read_openptrack_poses(&fixture(rel)).expect("reads");
    let names: Vec<&str> = poses.iter().map(|(n, _)| n.as_str()).collect();
    // `poses:` only, in file order; `inverse_poses:` and `calibration_id` are not sensors.
    assert_eq!(names, ["kinect01", "kinect02", "kinect03"]);
    // kinect01: translation x y z, rotation x y z w as printed.
    let (_, p) = &poses[0];
    assert_eq!(p.translation_m(), [-2.67177, -2.76412, 3.77764]);
    let want = Pose::from_quaternion_wxyz([-0.411678, 0.875625, -0.247839, 0.0487522], [0.0; 3])
        .expect("the file's quaternion, w first");
    assert_matrix_close(&p.rotation(), &want.rotation(), 0.0, "kinect01 rotation");

    // Each pose is world_from_sensor: it inverts the file's own inverse_poses, to the 6
    // significant digits opt_calibration prints (≤ 1e-5 m at ~5 m, ≤ 1e-5 per entry).
    for rel in [
        rel,
        "openptrack/hgse-schneider/camera_poses.yaml",
        "openptrack/prarobo/camera_poses.yaml",
    ] {
        let poses = read_openptrack_poses(&fixture(rel)).expect("reads");
        let inverse = inverse_poses(rel);
        assert_eq!(poses.len(), inverse.len(), "{rel}");
        for ((name, world_from_sensor), (inv_name, sensor_from_world)) in poses.iter().zip(&inverse)
        {
            assert_eq!(name, inv_name);
            let id = world_from_sensor.compose(sensor_from_world);
            assert_matrix_close(
                &id.rotation(),
                &Pose::identity().rotation(),
                2e-5,
                &format!("{rel} {name}"),
            );
            for t in id.translation_m() {
                assert!(t.abs() < 2e-5, "{rel} {name}: {:?}", id.translation_m());
            }
        }
    }
}

#[test]
fn openptrack_integers_and_negative_zero_read() {
    let poses =
        read_openptrack_poses(&fixture("openptrack/prarobo/camera_poses.yaml")).expect("reads");
    assert_eq!(poses.len(), 5);
    // k2 is the reference sensor: `x: 0` ... `w: 1`, integers in YAML.
    let (name, k2) = &poses[1];
    assert_eq!(name, "k2");
    assert_eq!(*k2, Pose::identity());
    let poses = read_openptrack_poses(&fixture("openptrack/hgse-schneider/camera_poses.yaml"))
        .expect("reads");
    assert_eq!(poses.len(), 6);
    assert_eq!(poses[5].0, "kinectFF");
    assert_eq!(poses[5].1.translation_m(), [-1.00802, -2.81149, 1.97277]);
}

// ---------------------------------------------------------------- ROS camera_info

#[test]
fn ros_camera_info_manager_file_reads_its_values() {
    let info = read_ros_camera_info(&fixture("ros/test_calibration.yaml")).expect("reads");
    assert!(info.notes.is_empty(), "{:?}", info.notes);
    assert_eq!(info.camera_name, "08144361026320a0");
    let i = info.intrinsics;
    assert_eq!((i.width, i.height), (640, 480));
    // camera_matrix data [1168.68, 0, 295.015, 0, 1169.01, 252.247, 0, 0, 1].
    assert_eq!(
        (i.fx, i.cx, i.fy, i.cy),
        (1168.68, 295.015, 1169.01, 252.247)
    );
    assert_eq!(
        i.distortion,
        Distortion::BrownConrady([-1.04482, 1.59252, -0.0196308, 0.0287906, 0.0])
    );

    // The same file as old ROS versions wrote it, without distortion_model: plumb_bob.
    let old = text("ros/test_calibration.yaml").replace("distortion_model: plumb_bob\n", "");
    let info_old = parse_ros_camera_info(&old, Path::new("old.yaml")).expect("reads");
    assert_eq!(info_old.intrinsics, i);
    assert_eq!(info_old.notes.len(), 1, "{:?}", info_old.notes);
    assert!(info_old.notes[0].contains("read as plumb_bob"));
}

/// What the SDK makes of a calibration for a mode, in f32: the pixel parameters
/// `[cx, cy, fx, fy, k1, k2, k3, k4, k5, k6, codx, cody, p2, p1]`
/// (`transformation_get_mode_specific_camera_calibration` with
/// `pixelized_zero_centered_output`, after the 16:9 → 4:3 step for old colour files).
fn sdk_mode_params(
    json_params: &[f64],
    stored: [u32; 2],
    binned: [f32; 2],
    crop: [f32; 2],
    color: bool,
) -> [f32; 14] {
    let mut p: [f32; 14] = std::array::from_fn(|i| json_params[i] as f32);
    let [w, h] = stored;
    if color && w * 9 / 16 == h {
        // Legacy 16:9 colour: {4096x2304, crop (0, -384), 4096x3072}, normalised output.
        let (cx, cy) = (p[0] * 4096.0 - 0.0, p[1] * 2304.0 - (-384.0));
        let (fx, fy) = (p[2] * 4096.0, p[3] * 2304.0);
        p[0] = cx / 4096.0;
        p[1] = cy / 3072.0;
        p[2] = fx / 4096.0;
        p[3] = fy / 3072.0;
    }
    let mut cx = p[0] * binned[0];
    let mut cy = p[1] * binned[1];
    let fx = p[2] * binned[0];
    let fy = p[3] * binned[1];
    cx -= crop[0];
    cy -= crop[1];
    p[0] = cx - 0.5;
    p[1] = cy - 0.5;
    p[2] = fx;
    p[3] = fy;
    p
}

/// The SDK's `transformation_project_internal` for the BrownConrady model, in f32 as it
/// runs, of normalised coordinates `xy` (its source, `intrinsic_transformation.c`).
fn sdk_project(params: &[f32; 14], xy: [f32; 2]) -> [f32; 2] {
    let [cx, cy, fx, fy, k1, k2, k3, k4, k5, k6, codx, cody, p2, p1] = *params;
    let xp = xy[0] - codx;
    let yp = xy[1] - cody;
    let xp2 = xp * xp;
    let yp2 = yp * yp;
    let xyp = xp * yp;
    let rs = xp2 + yp2;
    let rss = rs * rs;
    let rsc = rss * rs;
    let a = 1.0 + k1 * rs + k2 * rss + k3 * rsc;
    let b = 1.0 + k4 * rs + k5 * rss + k6 * rsc;
    let bi = if b != 0.0 { 1.0 / b } else { 1.0 };
    let d = a * bi;
    let mut xp_d = xp * d;
    let mut yp_d = yp * d;
    let rs_2xp2 = rs + 2.0 * xp2;
    let rs_2yp2 = rs + 2.0 * yp2;
    xp_d += rs_2xp2 * p2 + 2.0 * xyp * p1;
    yp_d += rs_2yp2 * p1 + 2.0 * xyp * p2;
    [(xp_d + codx) * fx + cx, (yp_d + cody) * fy + cy]
}

/// `ModelParameters` of a camera of an Azure Kinect JSON.
fn model_parameters(json_text: &str, location: &str) -> (Vec<f64>, [u32; 2]) {
    let root: serde_json::Value =
        serde_json::from_str(json_text.trim_start_matches('\u{feff}')).expect("JSON");
    let cam = root["CalibrationInformation"]["Cameras"]
        .as_array()
        .expect("cameras")
        .iter()
        .find(|c| c["Location"] == location)
        .expect("camera");
    let params = cam["Intrinsics"]["ModelParameters"]
        .as_array()
        .expect("parameters")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect();
    let size = ["SensorWidth", "SensorHeight"].map(|k| cam[k].as_u64().expect("size") as u32);
    (params, size)
}

/// Largest distance, pixels, between `ours` and the SDK's f32 projection over rays
/// through a 41×41 grid of the image. Grid points outside the lens' image circle (the
/// corners of the WFOV depth image, which the SDK marks invalid) have no ray and are
/// skipped; at least 3/4 of the grid must be compared.
fn worst_vs_sdk(ours: &Intrinsics, sdk: &[f32; 14]) -> f64 {
    let mut worst = 0.0f64;
    let mut compared = 0;
    for j in 0..=40 {
        for i in 0..=40 {
            let u = -0.5 + f64::from(ours.width) * f64::from(i) / 40.0;
            let v = -0.5 + f64::from(ours.height) * f64::from(j) / 40.0;
            let Some(ray) = ours.unproject(u, v) else {
                continue;
            };
            compared += 1;
            let uv = ours.project(ray).expect("in front");
            let s = sdk_project(sdk, [ray[0] as f32, ray[1] as f32]);
            worst = worst
                .max((uv[0] - f64::from(s[0])).abs())
                .max((uv[1] - f64::from(s[1])).abs());
        }
    }
    assert!(
        compared * 4 >= 41 * 41 * 3,
        "{compared} grid points with a ray"
    );
    worst
}

/// The check of issue 28: our projection against the SDK's, < 0.01 px.
const SDK_TOL_PX: f64 = 0.01;

#[test]
fn azure_kinect_matches_the_sdk_projection_in_every_mode() {
    use {AzureColorResolution as C, AzureDepthMode as D};
    let json = text("azure_kinect/pyk4a_calibration.json");
    let (depth_p, depth_size) = model_parameters(&json, "CALIBRATION_CameraLocationD0");
    let (color_p, color_size) = model_parameters(&json, "CALIBRATION_CameraLocationPV0");
    // (mode, binned, crop) as in the SDK's tables.
    let depth_modes = [
        (None, [1024.0, 1024.0], [0.0, 0.0]),
        (Some(D::NfovUnbinned), [1024.0, 1024.0], [192.0, 180.0]),
        (Some(D::Nfov2x2Binned), [512.0, 512.0], [96.0, 90.0]),
        (Some(D::Wfov2x2Binned), [512.0, 512.0], [0.0, 0.0]),
    ]
    .map(|(depth, b, c)| (AzureKinectMode { depth, color: None }, b, c, false));
    let color_modes = [
        (None, [4096.0, 3072.0], [0.0, 0.0]),
        (Some(C::R720p), [1280.0, 960.0], [0.0, 120.0]),
        (Some(C::R1080p), [1920.0, 1440.0], [0.0, 180.0]),
        (Some(C::R1536p), [2048.0, 1536.0], [0.0, 0.0]),
    ]
    .map(|(color, b, c)| (AzureKinectMode { depth: None, color }, b, c, true));
    // Our intrinsics of the depth (or colour) sensor in `mode` against the SDK's.
    let mut worst_all = 0.0f64;
    for (mode, binned, crop, is_color) in depth_modes.into_iter().chain(color_modes) {
        let cam = parse_azure_kinect_json(&json, "k", Path::new("c.json"), mode)
            .expect("reads")
            .camera;
        let (params, size, ours) = if is_color {
            (&color_p, color_size, &cam.color)
        } else {
            (&depth_p, depth_size, &cam.depth)
        };
        let worst = worst_vs_sdk(ours, &sdk_mode_params(params, size, binned, crop, is_color));
        assert!(worst < SDK_TOL_PX, "{mode:?}: {worst:e} px");
        worst_all = worst_all.max(worst);
    }
    eprintln!("Azure Kinect: largest difference to the SDK's f32 projection {worst_all:e} px");
}

/// The camera of pyk4a's test calibration in pyk4a's test modes (NFOV unbinned, 720P).
fn pyk4a_camera() -> RgbdCamera {
    let mode = AzureKinectMode {
        depth: Some(AzureDepthMode::NfovUnbinned),
        color: Some(AzureColorResolution::R720p),
    };
    let imported =
        read_azure_kinect_json(&fixture("azure_kinect/pyk4a_calibration.json"), "k", mode)
            .expect("reads");
    assert!(imported.notes.is_empty(), "{:?}", imported.notes);
    imported.camera
}

/// Projects `p_camera` (the sensor's frame, any length unit the SDK used: the projection
/// is scale-free) through `sensor` and checks it lands within `SDK_TOL_PX` of the pixel the
/// SDK computed; returns the error, pixels.
fn assert_projects(sensor: &Intrinsics, p_camera: [f64; 3], want: [f64; 2], what: &str) -> f64 {
    let got = sensor.project(p_camera).expect("in front");
    let err = (got[0] - want[0]).abs().max((got[1] - want[1]).abs());
    assert!(err < SDK_TOL_PX, "{what}: {got:?} vs the SDK's {want:?}");
    err
}

#[test]
fn azure_kinect_reproduces_projections_the_sdk_computed_for_pyk4a() {
    let cam = pyk4a_camera();
    assert_eq!((cam.depth.width, cam.depth.height), (640, 576));
    assert_eq!((cam.color.width, cam.color.height), (1280, 720));
    // pyk4a tests/unit/test_calibration.py, values the SDK returned (mm, pixels):
    // convert_3d_to_2d((-154.5365753173828, -26.12171173095703, 250.0), COLOR) = (250, 300).
    let p_color_mm = [-154.5365753173828, -26.12171173095703, 250.0];
    let e1 = assert_projects(&cam.color, p_color_mm, [250.0, 300.0], "colour 3D → 2D");
    // convert_3d_to_2d((-122.29087829589844, -45.17741394042969, 243.19528198242188),
    // DEPTH, COLOR) = (250, 300): through color_from_depth (metres).
    let p_depth_m = [-122.29087829589844, -45.17741394042969, 243.19528198242188].map(|v| v / 1e3);
    let p_color_m = cam.color_from_depth.transform_point(p_depth_m);
    let e2 = assert_projects(
        &cam.color,
        p_color_m,
        [250.0, 300.0],
        "depth 3D → colour 2D",
    );
    // color_to_depth_3d((1000, 1500, 2000)) = (1031.4664306640625, 1325.8529052734375,
    // 2117.6611328125) mm: f32 of ~2000 mm is good to ~1e-4 mm.
    let p_depth = cam
        .color_from_depth
        .inverse()
        .transform_point([1.0, 1.5, 2.0]);
    let want = [1031.4664306640625, 1325.8529052734375, 2117.6611328125];
    for (g, w) in p_depth.iter().zip(want) {
        assert!((g * 1e3 - w).abs() < 1e-3, "{p_depth:?} vs {want:?} mm");
    }
    // convert_2d_to_3d((250, 300), 250 mm, COLOR): our back-projection of that pixel.
    let ray = cam.color.unproject(250.0, 300.0).expect("in the image");
    for (g, w) in [ray[0] * 250.0, ray[1] * 250.0]
        .iter()
        .zip([-154.5365753173828, -26.12171173095703])
    {
        // 0.01 px at 250 mm and fx 612 px is 0.004 mm.
        assert!((g - w).abs() < 4e-3, "{ray:?}");
    }
    eprintln!("pyk4a/SDK points: {e1:e} px, {e2:e} px");
}

#[test]
fn azure_kinect_reproduces_the_sdk_test_projections() {
    // The SDK's tests/Transformation/transformation.cpp: g_test_json in
    // K4A_DEPTH_MODE_WFOV_2X2BINNED and K4A_COLOR_RESOLUTION_2160P (a 16:9 calibration).
    let mode = AzureKinectMode {
        depth: Some(AzureDepthMode::Wfov2x2Binned),
        color: Some(AzureColorResolution::R2160p),
    };
    let cam = read_azure_kinect_json(&fixture("azure_kinect/sdk_ut_calibration.json"), "k", mode)
        .expect("reads")
        .camera;
    assert_eq!((cam.color.width, cam.color.height), (3840, 2160));
    // m_depth_point2d_reference (256, 256) ↔ m_depth_point3d_reference.
    let depth_3d = [-2.45376134, -1.66107690, 1000.0];
    let e1 = assert_projects(&cam.depth, depth_3d, [256.0, 256.0], "depth");
    // m_color_point2d_reference ↔ m_color_point3d_reference.
    let color_3d = [-37.6291695, 63.3947754, 1001.46521];
    let e2 = assert_projects(&cam.color, color_3d, [1835.689453, 1206.290039], "colour");
    // Depth 3D → colour 3D (transformation_3d_to_3d; the SDK's tolerance 1e-3 mm).
    let got = cam
        .color_from_depth
        .transform_point(depth_3d.map(|v| v / 1e3))
        .map(|v| v * 1e3);
    for (g, w) in got.iter().zip(color_3d) {
        assert!((g - w).abs() < 1e-3, "{got:?} vs {color_3d:?}");
    }
    eprintln!("SDK test points: {e1:e} px, {e2:e} px");
}

#[test]
fn azure_kinect_sdk_test_file_with_bom_is_refused_for_its_model_not_its_bom() {
    let path = fixture("azure_kinect/sdk_TestCalibration.json");
    let bytes = std::fs::read(&path).expect("reads");
    assert_eq!(
        bytes[..3],
        [0xEF, 0xBB, 0xBF],
        "the SDK's file starts with a BOM"
    );
    let err =
        read_azure_kinect_json(&path, "k", AzureKinectMode::default()).expect_err("Rational6KT");
    assert!(matches!(err, CalibError::BadValue { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.starts_with("CalibrationInformation.Cameras[0].Intrinsics.ModelType: \"CALIBRATION_LensDistortionModelRational6KT\" is the SDK's deprecated model")
            && msg.ends_with("sdk_TestCalibration.json"),
        "{msg}"
    );
    // The BOM alone is no error: a factory file behind one reads as without.
    let json = text("azure_kinect/pyk4a_calibration.json");
    let with_bom = format!("\u{feff}{json}");
    let a = parse_azure_kinect_json(&json, "k", Path::new("a.json"), AzureKinectMode::default())
        .expect("reads");
    let b = parse_azure_kinect_json(
        &with_bom,
        "k",
        Path::new("b.json"),
        AzureKinectMode::default(),
    )
    .expect("a BOM is ignored");
    assert_eq!(a, b);
}

#[test]
fn azure_kinect_depth_mode_needs_the_device_resolution() {
    // The SDK refuses depth modes for a calibration that is not 1024x1024; so does the
    // reader, naming the key.
    let json = text("azure_kinect/pyk4a_calibration.json")
        .replacen("\"SensorWidth\": 1024", "\"SensorWidth\": 640", 1)
        .replacen("\"SensorHeight\": 1024", "\"SensorHeight\": 576", 1);
    let mode = AzureKinectMode {
        depth: Some(AzureDepthMode::NfovUnbinned),
        color: None,
    };
    let err = parse_azure_kinect_json(&json, "k", Path::new("c.json"), mode).expect_err("640x576");
    assert!(
        err.to_string().starts_with(
            "CalibrationInformation.Cameras[0].SensorWidth: depth mode NFOV_UNBINNED needs"
        ),
        "{err}"
    );
    // A centre of distortion off the axis cannot be held by OpenCV's model: refused.
    let mut root: serde_json::Value =
        serde_json::from_str(&text("azure_kinect/pyk4a_calibration.json")).expect("JSON");
    root["CalibrationInformation"]["Cameras"][1]["Intrinsics"]["ModelParameters"][10] =
        serde_json::json!(0.001);
    let err = parse_azure_kinect_json(
        &root.to_string(),
        "k",
        Path::new("c.json"),
        AzureKinectMode::default(),
    )
    .expect_err("codx = 0.001");
    assert!(
        err.to_string().starts_with(
            "CalibrationInformation.Cameras[1].Intrinsics.ModelParameters: [10] (codx"
        ),
        "{err}"
    );
}

#[test]
fn ros_camera_info_of_the_azure_kinect_driver_matches_the_json() {
    // The ROS driver publishes the SDK's mode-specific f32 values with
    // distortion_model rational_polynomial; importing them gives the camera of the JSON
    // to f32 precision.
    let cam = pyk4a_camera();
    for (file, want) in [
        ("ros/azure_kinect_rgb_720p.yaml", cam.color),
        ("ros/azure_kinect_depth_nfov_unbinned.yaml", cam.depth),
    ] {
        let info = read_ros_camera_info(&fixture(file)).expect("reads");
        assert!(info.notes.is_empty(), "{:?}", info.notes);
        let got = info.intrinsics;
        assert!(got.distortion.is_rational(), "{file}");
        assert_eq!((got.width, got.height), (want.width, want.height));
        for (g, w) in [
            (got.fx, want.fx),
            (got.fy, want.fy),
            (got.cx, want.cx),
            (got.cy, want.cy),
        ] {
            // f32 of ~600 px: ulp 6e-5 px.
            assert!((g - w).abs() < 2e-4, "{file}: {g} vs {w}");
        }
        let (g, w) = (
            got.distortion.coefficients(),
            want.distortion.coefficients(),
        );
        for (a, b) in g.iter().zip(w) {
            assert_eq!(
                *a as f32, *b as f32,
                "{file}: coefficients are the file's f32"
            );
        }
    }
}
