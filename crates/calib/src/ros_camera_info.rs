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
//! ROS pixel coordinates follow OpenCV (integer = pixel centre) and ROS hands `D` to
//! OpenCV as it is, so values map 1:1 onto [`Intrinsics`]:
//! - `distortion_model` `plumb_bob` or `rational_polynomial`; a file without the key is
//!   read as `plumb_bob`, as `camera_calibration_parsers` does for old files (with a
//!   note). Other models (`equidistant`, ...) are an error naming the key.
//! - `distortion_coefficients` is read the way OpenCV reads `D`, by its length (see
//!   [`Distortion::from_opencv`]): 0, 4 or 5 values are Brown-Conrady, 8 the rational
//!   model; other lengths are an error. A length that disagrees with the model's name
//!   (e.g. a `rational_polynomial` with 5 values, which phone tools write) is read as
//!   OpenCV would, with a note.
//! - `binning_x`/`binning_y` above 1 (the driver publishes binned images with scaled
//!   intrinsics) are refused; `roi` is ignored.
//! - `rectification_matrix` and `projection_matrix` describe stereo rectification,
//!   which bodyseg does not use: the reader ignores them and the writer writes the
//!   identity and `[K | 0]` (what a monocular calibration holds).

use std::path::Path;

use yaml_rust2::Yaml;

use crate::files::{float_text, read_text, write_atomic};
use crate::yaml::{Doc, load, type_name};
use crate::{CalibError, Distortion, Intrinsics};

/// ROS' name of the Brown-Conrady model (k1 k2 p1 p2 k3).
pub const ROS_PLUMB_BOB: &str = "plumb_bob";
/// ROS' name of the rational model (k1 k2 p1 p2 k3 k4 k5 k6).
pub const ROS_RATIONAL_POLYNOMIAL: &str = "rational_polynomial";

/// The content of a ROS `camera_info` file that bodyseg uses.
#[derive(Debug, Clone, PartialEq)]
pub struct RosCameraInfo {
    /// `camera_name` (empty when the file has none).
    pub camera_name: String,
    /// Image size, pinhole and distortion of the camera, pixels.
    pub intrinsics: Intrinsics,
    /// What the reader assumed, one line each naming the key and the file (a missing
    /// `distortion_model`, a coefficient count that disagrees with the model's name).
    pub notes: Vec<String>,
}

/// Reads and validates a ROS `camera_info` YAML file.
pub fn read_ros_camera_info(path: &Path) -> Result<RosCameraInfo, CalibError> {
    parse_ros_camera_info(&read_text(path)?, path)
}

/// Parses the text of a ROS `camera_info` YAML file; `path` is used in error messages.
///
/// Errors name the file and the key: a missing key, a matrix of the wrong shape, a
/// non-zero skew (`camera_matrix.data[1]`), a last row other than `0 0 1`, a
/// `distortion_model` other than `plumb_bob` or `rational_polynomial`, a coefficient
/// count OpenCV's pinhole models do not have, binning, or intrinsics that fail
/// [`Intrinsics::validate`] (NaN, focal length ≤ 0).
pub fn parse_ros_camera_info(text: &str, path: &Path) -> Result<RosCameraInfo, CalibError> {
    let doc = Doc { path };
    let root = load(text, path)?;
    let mut notes = Vec::new();
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
    for key in ["binning_x", "binning_y"] {
        match &root[key] {
            Yaml::Integer(0 | 1) | Yaml::BadValue | Yaml::Null => {}
            other => {
                return Err(doc.bad(
                    key,
                    format!(
                        "binning is not supported (give the calibration of the images as \
                         published, binning 0 or 1), got {}",
                        match other {
                            Yaml::Integer(i) => i.to_string(),
                            _ => type_name(other).to_string(),
                        }
                    ),
                ));
            }
        }
    }
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
    let model = match &root["distortion_model"] {
        Yaml::String(s) => s.as_str(),
        Yaml::BadValue => {
            notes.push(format!(
                "distortion_model: missing, read as {ROS_PLUMB_BOB} (as ROS does): {}",
                path.display()
            ));
            ROS_PLUMB_BOB
        }
        other => {
            return Err(doc.bad(
                "distortion_model",
                format!("must be a string, got {}", type_name(other)),
            ));
        }
    };
    if model != ROS_PLUMB_BOB && model != ROS_RATIONAL_POLYNOMIAL {
        return Err(doc.bad(
            "distortion_model",
            format!(
                "{model:?} is not supported: bodyseg reads {ROS_PLUMB_BOB:?} (k1 k2 p1 p2 k3) \
                 and {ROS_RATIONAL_POLYNOMIAL:?} (k1 k2 p1 p2 k3 k4 k5 k6)"
            ),
        ));
    }
    let d = doc.vector(
        doc.get(&root, "", "distortion_coefficients")?,
        "distortion_coefficients",
    )?;
    let distortion = Distortion::from_opencv(&d).ok_or_else(|| {
        doc.bad(
            "distortion_coefficients",
            Distortion::unsupported_count(d.len()),
        )
    })?;
    if distortion.is_rational() != (model == ROS_RATIONAL_POLYNOMIAL) {
        notes.push(format!(
            "distortion_coefficients: {} values under distortion_model {model}, read as \
             OpenCV reads them ({}): {}",
            d.len(),
            if distortion.is_rational() {
                "rational"
            } else {
                "Brown-Conrady"
            },
            path.display()
        ));
    }
    let intrinsics =
        Intrinsics::pinhole(width, height, k[0], k[4], k[2], k[5]).with_distortion(distortion);
    intrinsics
        .validate()
        .map_err(|e| e.intrinsics_in_file("camera_matrix", "distortion_coefficients", path))?;
    Ok(RosCameraInfo {
        camera_name,
        intrinsics,
        notes,
    })
}

/// The text of a ROS `camera_info` YAML file for these intrinsics (`plumb_bob` with 5
/// coefficients or `rational_polynomial` with 8, as the model is). Floats are written
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
    let (model, d) = match &i.distortion {
        Distortion::BrownConrady(d) => (ROS_PLUMB_BOB, &d[..]),
        Distortion::Rational(d) => (ROS_RATIONAL_POLYNOMIAL, &d[..]),
    };
    out += &format!("distortion_model: {model}\n");
    out += &matrix("distortion_coefficients", 1, d.len() as u32, d);
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
        Intrinsics::pinhole(640, 480, 525.123_456_789_012_3, 524.5, 319.5, 239.25)
            .with_distortion(Distortion::BrownConrady([0.1, -0.25, 1e-7, -3.5e-4, 0.0]))
    }

    #[test]
    fn string_round_trip_is_exact() {
        let text = ros_camera_info_to_string("cam \"0\"", &intrinsics()).expect("valid");
        let info = parse_ros_camera_info(&text, Path::new("c.yaml")).expect("reads back");
        assert_eq!(info.camera_name, "cam \"0\"");
        assert_eq!(info.intrinsics, intrinsics());
    }

    #[test]
    fn rational_round_trip_is_exact() {
        let want = Intrinsics {
            distortion: Distortion::Rational([
                0.5, -0.02, 2e-5, -7e-5, -0.003, 0.89, 0.086, -0.014,
            ]),
            ..intrinsics()
        };
        let text = ros_camera_info_to_string("k4a", &want).expect("valid");
        assert!(
            text.contains("distortion_model: rational_polynomial\n"),
            "{text}"
        );
        assert!(text.contains("cols: 8\n"), "{text}");
        let info = parse_ros_camera_info(&text, Path::new("c.yaml")).expect("reads back");
        assert_eq!(info.intrinsics, want);
        assert!(info.notes.is_empty(), "{:?}", info.notes);
    }

    #[test]
    fn other_models_and_skew_are_rejected() {
        let text = ros_camera_info_to_string("c", &intrinsics()).expect("valid");
        let error_of = |text: &str, what: &str| {
            parse_ros_camera_info(text, Path::new("c.yaml"))
                .expect_err(what)
                .to_string()
        };
        let assert_starts = |msg: &str, prefix: &str| assert!(msg.starts_with(prefix), "{msg}");
        let fisheye = text.replace("plumb_bob", "equidistant");
        let msg = error_of(&fisheye, "fisheye");
        assert!(
            msg.starts_with("distortion_model: \"equidistant\" is not supported")
                && msg.ends_with("c.yaml"),
            "{msg}"
        );
        let skewed = text.replacen(
            "data: [525.1234567890123, 0.0",
            "data: [525.1234567890123, 0.5",
            1,
        );
        let msg = error_of(&skewed, "skew");
        assert_starts(&msg, "camera_matrix.data[1]: skew");
        let binned = format!("{text}binning_x: 2\n");
        let msg = error_of(&binned, "binning");
        assert_starts(&msg, "binning_x: binning is not supported");
        let twelve = text.replace(
            "cols: 5\n  data: [0.1, -0.25, 1e-7, -0.00035, 0.0]",
            "cols: 12\n  data: [0.1, -0.25, 1e-7, -0.00035, 0.0, 0, 0, 0, 0, 0, 0, 0]",
        );
        assert_ne!(twelve, text, "the replacement applies");
        let msg = error_of(&twelve, "thin prism");
        assert_starts(&msg, "distortion_coefficients: has 12 values");
    }

    #[test]
    fn missing_model_is_plumb_bob_and_count_decides() {
        let text = ros_camera_info_to_string("c", &intrinsics()).expect("valid");
        let old = text.replace("distortion_model: plumb_bob\n", "");
        let info = parse_ros_camera_info(&old, Path::new("old.yaml")).expect("old file reads");
        assert_eq!(info.intrinsics, intrinsics());
        assert_eq!(info.notes.len(), 1, "{:?}", info.notes);
        assert!(info.notes[0].starts_with("distortion_model: missing, read as plumb_bob"));
        // rational_polynomial with 5 values: OpenCV (and so ROS) uses the 5 values.
        let five = text.replace("plumb_bob", "rational_polynomial");
        let info = parse_ros_camera_info(&five, Path::new("p.yaml")).expect("reads");
        assert_eq!(info.intrinsics, intrinsics());
        assert!(info.notes[0].contains("5 values under distortion_model rational_polynomial"));
    }
}
