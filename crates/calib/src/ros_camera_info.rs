//! ROS `camera_info` YAML, the layout of `camera_calibration_parsers` (written by
//! `camera_calibration` and read by every ROS camera driver): reader and writer.
//!
//! ```yaml
//! image_width: 640
//! image_height: 480
//! camera_name: narrow_stereo
//! camera_matrix: {rows: 3, cols: 3, data: [fx, 0, cx, 0, fy, cy, 0, 0, 1]}
//! distortion_model: plumb_bob
//! distortion_coefficients: {rows: 1, cols: 5, data: [k1, k2, p1, p2, k3]}
//! rectification_matrix: {rows: 3, cols: 3, data: [...]}
//! projection_matrix: {rows: 3, cols: 4, data: [...]}
//! ```
//!
//! ROS' `plumb_bob` is OpenCV's 5-coefficient Brown-Conrady model in OpenCV's order, and
//! ROS pixel coordinates follow OpenCV (integer = pixel centre), so values map 1:1 onto
//! [`Intrinsics`]. Only `plumb_bob` is accepted: any other `distortion_model`
//! (`rational_polynomial`, `equidistant`, ...) is an error, since silently dropping
//! coefficients would misplace pixels. `rectification_matrix` and `projection_matrix`
//! describe stereo rectification, which bodyseg does not use: the reader ignores them and
//! the writer writes the identity and `[K | 0]` (what a monocular calibration holds).

use std::path::Path;

use yaml_rust2::Yaml;

use crate::files::{float_text, read_text, write_atomic};
use crate::yaml::{Doc, load, type_name};
use crate::{CalibError, Intrinsics};

/// The only `distortion_model` bodyseg reads and writes.
pub const ROS_PLUMB_BOB: &str = "plumb_bob";

/// The content of a ROS `camera_info` file that bodyseg uses.
#[derive(Debug, Clone, PartialEq)]
pub struct RosCameraInfo {
    /// `camera_name` (empty when the file has none).
    pub camera_name: String,
    /// Image size, pinhole and distortion of the camera, pixels.
    pub intrinsics: Intrinsics,
}

/// Reads and validates a ROS `camera_info` YAML file.
pub fn read_ros_camera_info(path: &Path) -> Result<RosCameraInfo, CalibError> {
    parse_ros_camera_info(&read_text(path)?, path)
}

/// Parses the text of a ROS `camera_info` YAML file; `path` is used in error messages.
///
/// Errors name the file and the key: a missing key, a matrix of the wrong shape, a
/// non-zero skew (`camera_matrix.data[1]`), a last row other than `0 0 1`, a
/// `distortion_model` other than `plumb_bob`, or intrinsics that fail
/// [`Intrinsics::validate`] (NaN, focal length ≤ 0).
pub fn parse_ros_camera_info(text: &str, path: &Path) -> Result<RosCameraInfo, CalibError> {
    let doc = Doc { path };
    let root = load(text, path)?;
    let width = doc.count(doc.get(&root, "", "image_width")?, "image_width")?;
    let height = doc.count(doc.get(&root, "", "image_height")?, "image_height")?;
    let camera_name = match &root["camera_name"] {
        Yaml::String(s) => s.clone(),
        Yaml::BadValue | Yaml::Null => String::new(),
        Yaml::Integer(i) => i.to_string(),
        other => {
            return Err(doc.bad(
                "camera_name",
                format!("must be a string, got {}", type_name(other)),
            ));
        }
    };
    let k = doc.matrix(doc.get(&root, "", "camera_matrix")?, "camera_matrix", 3, 3)?;
    if k[1] != 0.0 {
        return Err(doc.bad(
            "camera_matrix.data[1]",
            format!(
                "skew must be 0 (bodyseg's pinhole has no skew), got {}",
                k[1]
            ),
        ));
    }
    if [k[3], k[6], k[7], k[8]] != [0.0, 0.0, 0.0, 1.0] {
        return Err(doc.bad(
            "camera_matrix",
            format!(
                "must be [fx 0 cx; 0 fy cy; 0 0 1], got rows 2-3 = [{} {} {}; {} {} {}]",
                k[3], k[4], k[5], k[6], k[7], k[8]
            ),
        ));
    }
    let model = match doc.get(&root, "", "distortion_model")? {
        Yaml::String(s) => s.as_str(),
        other => {
            return Err(doc.bad(
                "distortion_model",
                format!("must be a string, got {}", type_name(other)),
            ));
        }
    };
    if model != ROS_PLUMB_BOB {
        return Err(doc.bad(
            "distortion_model",
            format!(
                "{model:?} is not supported: bodyseg reads only {ROS_PLUMB_BOB:?} \
                 (k1 k2 p1 p2 k3); recalibrate with plumb_bob or convert the file"
            ),
        ));
    }
    let d = doc.matrix(
        doc.get(&root, "", "distortion_coefficients")?,
        "distortion_coefficients",
        1,
        5,
    )?;
    let intrinsics = Intrinsics::from_camera_matrix(width, height, &k, &d);
    intrinsics.validate().map_err(|e| match e {
        CalibError::Invalid { field, reason } => doc.bad(
            if field == "distortion" {
                "distortion_coefficients"
            } else {
                "camera_matrix"
            },
            format!("{field} {reason}"),
        ),
        other => other,
    })?;
    Ok(RosCameraInfo {
        camera_name,
        intrinsics,
    })
}

/// The text of a ROS `camera_info` YAML file for these intrinsics. Floats are written
/// with the shortest text that reads back to the same `f64`, so a round trip is exact.
pub fn ros_camera_info_to_string(
    camera_name: &str,
    intrinsics: &Intrinsics,
) -> Result<String, CalibError> {
    intrinsics.validate()?;
    let i = intrinsics;
    let list = |values: &[f64]| {
        values
            .iter()
            .map(|&v| float_text(v))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let matrix = |key: &str, rows: u32, cols: u32, values: &[f64]| {
        format!(
            "{key}:\n  rows: {rows}\n  cols: {cols}\n  data: [{}]\n",
            list(values)
        )
    };
    // A JSON string is a valid YAML double-quoted scalar: safe for any name.
    let name = serde_json::to_string(camera_name)
        .map_err(|e| CalibError::invalid("camera_name", format!("cannot be written: {e}")))?;
    let mut out = format!(
        "image_width: {}\nimage_height: {}\ncamera_name: {name}\n",
        i.width, i.height
    );
    out += &matrix(
        "camera_matrix",
        3,
        3,
        &[i.fx, 0.0, i.cx, 0.0, i.fy, i.cy, 0.0, 0.0, 1.0],
    );
    out += &format!("distortion_model: {ROS_PLUMB_BOB}\n");
    out += &matrix("distortion_coefficients", 1, 5, &i.distortion);
    out += &matrix(
        "rectification_matrix",
        3,
        3,
        &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    );
    out += &matrix(
        "projection_matrix",
        3,
        4,
        &[
            i.fx, 0.0, i.cx, 0.0, 0.0, i.fy, i.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
        ],
    );
    Ok(out)
}

/// Writes a ROS `camera_info` YAML file (through a temporary file and a rename).
pub fn write_ros_camera_info(
    path: &Path,
    camera_name: &str,
    intrinsics: &Intrinsics,
) -> Result<(), CalibError> {
    write_atomic(path, &ros_camera_info_to_string(camera_name, intrinsics)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn intrinsics() -> Intrinsics {
        Intrinsics {
            width: 640,
            height: 480,
            fx: 525.123_456_789_012_3,
            fy: 524.5,
            cx: 319.5,
            cy: 239.25,
            distortion: [0.1, -0.25, 1e-7, -3.5e-4, 0.0],
        }
    }

    #[test]
    fn string_round_trip_is_exact() {
        let text = ros_camera_info_to_string("cam \"0\"", &intrinsics()).expect("valid");
        let info = parse_ros_camera_info(&text, Path::new("c.yaml")).expect("reads back");
        assert_eq!(info.camera_name, "cam \"0\"");
        assert_eq!(info.intrinsics, intrinsics());
    }

    #[test]
    fn other_models_and_skew_are_rejected() {
        let text = ros_camera_info_to_string("c", &intrinsics()).expect("valid");
        let rational = text.replace("plumb_bob", "rational_polynomial");
        let msg = parse_ros_camera_info(&rational, Path::new("c.yaml"))
            .expect_err("rational")
            .to_string();
        assert!(
            msg.starts_with("distortion_model: \"rational_polynomial\" is not supported")
                && msg.ends_with("c.yaml"),
            "{msg}"
        );
        let skewed = text.replacen(
            "data: [525.1234567890123, 0.0",
            "data: [525.1234567890123, 0.5",
            1,
        );
        let msg = parse_ros_camera_info(&skewed, Path::new("c.yaml"))
            .expect_err("skew")
            .to_string();
        assert!(msg.starts_with("camera_matrix.data[1]: skew"), "{msg}");
    }
}
