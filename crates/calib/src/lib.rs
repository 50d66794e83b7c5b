//! bodyseg-calib: camera models, RGB-D rigs, calibration files and depth back-projection.
//!
//! Place in the pipeline: the first stage after reading a recording. A [`Rig`] (read from
//! `rig.toml` or assembled from vendor calibration files) turns
//! each camera's depth image into points with their origins ([`back_project`]; a whole
//! rig into one world-frame cloud with [`RigBackProjector`], rayon across cameras and
//! rows); the
//! projection stage (`bodyseg-project`) then uses the same cameras to look each point up
//! in the colour image ([`Intrinsics::project`] after `color_from_depth`). Depth image →
//! points; depends only on `bodyseg-core`. ALGORITHM.md §1.
//!
//! # Calibration files
//! Each format has a reader and a writer (writers go through a temporary file and a rename;
//! reader errors name the file and the key):
//! - `rig.toml` ⇄ [`Rig`]: [`read_rig_toml`], [`write_rig_toml`];
//! - iai_kinect2 folders ⇄ [`RgbdCamera`]: [`read_iai_kinect2`] (or [`import_iai_kinect2`],
//!   which returns its notes: a folder without `calib_depth.yaml` has depth shift 0),
//!   [`write_iai_kinect2`];
//! - ROS `camera_info` YAML ⇄ [`Intrinsics`]: [`read_ros_camera_info`],
//!   [`write_ros_camera_info`] (`plumb_bob` and `rational_polynomial`; a file without
//!   `distortion_model` is `plumb_bob`, as in ROS);
//! - OpenPTrack `camera_poses.yaml` ⇄ `(name, world_from_sensor)`:
//!   [`read_openptrack_poses`], [`write_openptrack_poses`];
//! - OpenCV FileStorage YAML of one sensor → [`Intrinsics`], in pure Rust:
//!   [`read_opencv_yaml_intrinsics`];
//! - one sensor's intrinsics TOML (the fields of a rig.toml `[camera.depth]` table at the
//!   top level) ⇄ [`Intrinsics`]: [`read_intrinsics_toml`], [`write_intrinsics_toml`];
//! - with the `opencv` feature, OpenCV FileStorage YAML/XML through OpenCV ⇄
//!   [`Intrinsics`]: `read_opencv_intrinsics`, `write_opencv_intrinsics`;
//! - Azure Kinect factory calibration JSON ⇄ [`RgbdCamera`]: [`read_azure_kinect_json`]
//!   (the SDK's mapping, rational model, intrinsics for a capture mode's images:
//!   [`AzureKinectMode`]), [`write_azure_kinect_json`].
//!
//! Text files may start with a UTF-8 byte order mark; every reader ignores it.
//!
//! # Calibration (feature `opencv`)
//! Chessboard calibration through OpenCV (`bodyseg calibrate`): [`Board`] and the canonical
//! corner order ([`canonical_corner_order`], pure Rust) are always built; with the
//! feature, `find_board_corners` (detection, sub-pixel refinement), `calibrate_intrinsics`
//! (`calibrateCamera`), `calibrate_stereo` (`stereoCalibrate`, intrinsics fixed) and
//! `board_pose` (`solvePnP`). Views and images come in memory ([`GrayImage`]); reading
//! image files is the caller's.
//!
//! # Conventions
//! - Camera frames: OpenCV optical frame of each sensor, x right, y down, z forward.
//! - Pixels: (u, v) = (column, row); integer coordinates are pixel centres, so an image
//!   spans `[-0.5, width - 0.5) × [-0.5, height - 0.5)`. A pixel index is `v * width + u`.
//! - Units: metres for all geometry; millimetres only for raw depth and `depth_shift_mm`;
//!   focal lengths and principal points in pixels; distortion coefficients unitless.
//! - Transforms are named `a_from_b` and map points of frame b into frame a:
//!   `p_color = color_from_depth · p_depth`, `p_world = world_from_depth · p_depth`.
//! - Distortion ([`Distortion`]): OpenCV's models in OpenCV's coefficient order
//!   (`cv::projectPoints`), applied to normalised coordinates (x/z, y/z): Brown-Conrady
//!   `[k1, k2, p1, p2, k3]` or the rational model `[k1, k2, p1, p2, k3, k4, k5, k6]`.
//! - World frame: right-handed, z up (ALGORITHM.md §0).
//! - Depth: raw `u16`, 0 = no measurement; metres = `raw / depth_scale + depth_shift_mm / 1000`.
//!
//! # Example
//! ```
//! use bodyseg_calib::{
//!     BackProjectOptions, CloudFrame, Distortion, Intrinsics, RgbdCamera, back_project,
//! };
//!
//! let depth = Intrinsics {
//!     width: 4, height: 3, fx: 2.0, fy: 2.0, cx: 1.5, cy: 1.0, distortion: Distortion::NONE,
//! };
//! let camera = RgbdCamera::new("cam0", depth, depth);
//! let image = [0, 1000, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2000_u16];
//! let opts = BackProjectOptions { frame: CloudFrame::Depth, ..Default::default() };
//! let cloud = back_project(&image, &camera, 0, &opts)?;
//! assert_eq!(cloud.origins.iter().map(|o| o.pixel).collect::<Vec<_>>(), [1, 11]);
//! // Pixel 11 is (u 3, v 2) at 2 m: x = (3 - 1.5) / 2 · 2, y = (2 - 1) / 2 · 2.
//! assert_eq!(cloud.points_m[1], [1.5, 1.0, 2.0]);
//! let uv = camera.depth.project([1.5, 1.0, 2.0]).expect("in front of the camera");
//! assert_eq!(uv, [3.0, 2.0]);
//! # Ok::<(), bodyseg_calib::CalibError>(())
//! ```

mod azure_kinect;
mod back_project;
mod board;
#[cfg(feature = "opencv")]
mod calibrate;
mod camera;
mod distortion;
mod error;
mod files;
mod iai_kinect2;
mod intrinsics;
mod opencv_yaml;
mod openptrack;
mod pose;
mod pose_fit;
mod rig_toml;
mod ros_camera_info;
mod yaml;

#[doc(hidden)]
pub mod testing;

pub use azure_kinect::{
    AZURE_COLOR_LOCATION, AZURE_DEPTH_LOCATION, AzureColorResolution, AzureDepthMode,
    AzureKinectMode, azure_kinect_json_to_string, parse_azure_kinect_json, read_azure_kinect_json,
    write_azure_kinect_json,
};
pub use back_project::{
    BackProjectOptions, BackProjected, CloudFrame, DepthBackProjector, PIXELS_PER_CHUNK, RayTable,
    RigBackProjector, back_project, back_project_rig,
};
pub use board::{Board, BoardZ, GrayImage, MAX_INNER_CORNERS, canonical_corner_order};
#[cfg(feature = "opencv")]
pub use calibrate::{
    CornerPair, IntrinsicsFit, MIN_INTRINSICS_VIEWS, StereoFit, board_pose, calibrate_intrinsics,
    calibrate_stereo, find_board_corners, read_opencv_intrinsics, reprojection_rms_px,
    write_opencv_intrinsics,
};
pub use camera::{DEFAULT_DEPTH_SCALE, ImportedCamera, RgbdCamera, Rig};
pub use distortion::Distortion;
pub use error::CalibError;
pub use iai_kinect2::{
    KINECT2_COLOR_SIZE, KINECT2_DEPTH_SIZE, import_iai_kinect2, read_iai_kinect2, write_iai_kinect2,
};
pub use intrinsics::Intrinsics;
pub use opencv_yaml::{parse_opencv_yaml_intrinsics, read_opencv_yaml_intrinsics};
pub use openptrack::{
    openptrack_poses_to_string, parse_openptrack_poses, read_openptrack_poses,
    write_openptrack_poses,
};
pub use pose::{Pose, QUATERNION_NORM_TOLERANCE, ROTATION_TOLERANCE};
pub use pose_fit::{SensorCorners, refine_board_pose};
pub use rig_toml::{
    intrinsics_to_toml_string, parse_intrinsics_toml, parse_rig_toml, read_intrinsics_toml,
    read_rig_toml, rig_to_toml_string, write_intrinsics_toml, write_rig_toml,
};
pub use ros_camera_info::{
    ROS_PLUMB_BOB, ROS_RATIONAL_POLYNOMIAL, RosCameraInfo, parse_ros_camera_info,
    read_ros_camera_info, ros_camera_info_to_string, write_ros_camera_info,
};
