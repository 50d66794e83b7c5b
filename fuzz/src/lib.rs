//! bodyseg's fuzz targets: one function per file format (and the configuration parser)
//! that hands arbitrary bytes to the reader and checks what it returns.
//!
//! A target passes when the reader returns an error or a value that holds its documented
//! invariants (a cloud's arrays agree in length and its points are finite, intrinsics
//! validate). It fails by panicking (a reader that panics, an invariant broken), by
//! taking too long (libFuzzer's `-timeout`), or by asking for more memory than
//! [`alloc_limit::LIMIT_BYTES`] (the limiting allocator here answers such a request with
//! an allocation failure, which aborts; libFuzzer's `-rss_limit_mb` only sees memory that
//! is touched, not a reservation the header asked for).
//!
//! `fuzz_targets/<name>.rs` wraps each target in a libFuzzer binary, which `scripts/fuzz.sh SECONDS [TARGET...]`
//! builds and runs from the committed inputs, `corpus/<name>/` (seeds) and
//! `regressions/<name>/` (every crash found, kept after its fix). A libFuzzer binary given
//! files instead of folders runs just those: `fuzz/target/<triple>/release/pcd FILE`.

pub mod alloc_limit;

use bodyseg_calib::{
    AzureColorResolution, AzureDepthMode, AzureKinectMode, Intrinsics, parse_azure_kinect_json,
    parse_intrinsics_toml, parse_opencv_yaml_intrinsics, parse_openptrack_poses, parse_rig_toml,
    parse_ros_camera_info,
};
use bodyseg_core::LabeledCloud;
use bodyseg_io::{
    parse_boxes, parse_depth_png, parse_label_png, parse_mat_matrix, parse_mat_variable_names,
    parse_pcd, parse_ply, parse_rgb_image,
};
use bodyseg_pipeline::PipelineConfig;
use std::path::Path;

/// The path every error message names.
fn path(name: &str) -> &Path {
    Path::new(name)
}

/// The text readers read UTF-8 files; invalid bytes become U+FFFD so that mutations of
/// the bytes still reach the parser.
fn text(data: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(data)
}

/// A cloud a reader returned holds [`LabeledCloud::validate`].
fn check_cloud(cloud: &LabeledCloud, format: &str) {
    if let Err(e) = cloud.validate() {
        panic!("{format} reader returned an invalid cloud: {e}");
    }
}

/// Intrinsics a reader returned hold [`Intrinsics::validate`].
fn check_intrinsics(intrinsics: &Intrinsics, format: &str) {
    if let Err(e) = intrinsics.validate() {
        panic!("{format} reader returned invalid intrinsics: {e}");
    }
}

/// PLY: [`parse_ply`].
pub fn ply(data: &[u8]) {
    if let Ok(cloud) = parse_ply(data, path("fuzz.ply")) {
        check_cloud(&cloud, "PLY");
    }
}

/// PCD: [`parse_pcd`].
pub fn pcd(data: &[u8]) {
    if let Ok(cloud) = parse_pcd(data, path("fuzz.pcd")) {
        check_cloud(&cloud, "PCD");
    }
}

/// MAT v5: [`parse_mat_variable_names`], then [`parse_mat_matrix`] of the first variable
/// (and of one that is not there).
pub fn mat(data: &[u8]) {
    let at = path("fuzz.mat");
    let first = parse_mat_variable_names(data, at)
        .ok()
        .and_then(|names| names.into_iter().next());
    for name in first.iter().map(String::as_str).chain(["depth"]) {
        if let Ok(m) = parse_mat_matrix(data, name, at) {
            assert_eq!(
                m.values.len(),
                m.rows * m.cols,
                "MAT reader returned {}x{} with {} values",
                m.rows,
                m.cols,
                m.values.len()
            );
        }
    }
}

/// Depth and label PNGs: [`parse_depth_png`] and [`parse_label_png`].
pub fn png(data: &[u8]) {
    let at = path("fuzz.png");
    if let Ok(depth) = parse_depth_png(data, at) {
        assert_eq!(depth.depth_mm.len(), depth.num_pixels(), "depth PNG size");
    }
    if let Ok(labels) = parse_label_png(data, at) {
        assert_eq!(
            labels.labels.len(),
            labels.width as usize * labels.height as usize,
            "label PNG size"
        );
    }
}

/// Colour images, PNG or JPEG: [`parse_rgb_image`].
pub fn color_image(data: &[u8]) {
    if let Ok(image) = parse_rgb_image(data, path("fuzz.jpg")) {
        assert_eq!(
            image.rgb.len(),
            image.width as usize * image.height as usize * 3,
            "colour image size"
        );
    }
}

/// Person boxes JSON: [`parse_boxes`].
pub fn boxes(data: &[u8]) {
    if let Ok(boxes) = parse_boxes(data, path("fuzz.json")) {
        for b in &boxes.boxes {
            assert_eq!(b.invalid_reason(), None, "boxes reader returned a bad box");
        }
    }
}

/// `rig.toml` and one-sensor intrinsics TOML: [`parse_rig_toml`], [`parse_intrinsics_toml`].
pub fn rig_toml(data: &[u8]) {
    let text = text(data);
    if let Ok(rig) = parse_rig_toml(&text, path("rig.toml"))
        && let Err(e) = rig.validate()
    {
        panic!("rig.toml reader returned an invalid rig: {e}");
    }
    if let Ok(intrinsics) = parse_intrinsics_toml(&text, path("intrinsics.toml")) {
        check_intrinsics(&intrinsics, "intrinsics TOML");
    }
}

/// OpenCV FileStorage YAML intrinsics (iai_kinect2's `calib_*.yaml`):
/// [`parse_opencv_yaml_intrinsics`], with and without a default image size.
pub fn opencv_yaml(data: &[u8]) {
    let text = text(data);
    for default_size in [None, Some([512, 424])] {
        if let Ok(intrinsics) =
            parse_opencv_yaml_intrinsics(&text, path("calib_color.yaml"), default_size)
        {
            check_intrinsics(&intrinsics, "OpenCV YAML");
        }
    }
}

/// ROS `camera_info` YAML: [`parse_ros_camera_info`].
pub fn ros_camera_info(data: &[u8]) {
    if let Ok(info) = parse_ros_camera_info(&text(data), path("camera_info.yaml")) {
        check_intrinsics(&info.intrinsics, "ROS camera_info");
    }
}

/// OpenPTrack `camera_poses.yaml`: [`parse_openptrack_poses`].
pub fn openptrack(data: &[u8]) {
    let _ = parse_openptrack_poses(&text(data), path("camera_poses.yaml"));
}

/// Azure Kinect factory calibration JSON: [`parse_azure_kinect_json`], for the full
/// sensor images and for one capture mode picked by the input's length.
pub fn azure_kinect(data: &[u8]) {
    let text = text(data);
    let n = data.len();
    let modes = [
        AzureKinectMode::default(),
        AzureKinectMode {
            depth: Some(AzureDepthMode::ALL[n % AzureDepthMode::ALL.len()]),
            color: Some(AzureColorResolution::ALL[n % AzureColorResolution::ALL.len()]),
        },
    ];
    for mode in modes {
        if let Ok(imported) = parse_azure_kinect_json(&text, "k4a", path("k4a.json"), mode)
            && let Err(e) = imported.camera.validate()
        {
            panic!("Azure Kinect reader returned an invalid camera: {e}");
        }
    }
}

/// The pipeline configuration: [`PipelineConfig::from_toml`] (parse and validate), and
/// the input's lines as `--set` settings ([`PipelineConfig::resolve`]) when there are a
/// few.
pub fn config(data: &[u8]) {
    let text = text(data);
    let _ = PipelineConfig::from_toml(&text, path("config.toml"));
    let settings: Vec<String> = text.lines().map(str::to_string).collect();
    if (1..=4).contains(&settings.len()) {
        let _ = PipelineConfig::resolve(&[], &settings);
    }
}
