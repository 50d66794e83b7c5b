//! OpenPTrack `camera_poses.yaml` (written by `opt_calibration`): the pose of each sensor
//! with respect to the world, reader and writer.
//!
//! ```yaml
//! kinect2_head:                 # one mapping per sensor (its frame id)
//!   translation: {x: 0.1, y: -2.0, z: 1.8}        # metres
//!   rotation: {x: 0.0, y: 0.0, z: 0.0, w: 1.0}    # unit quaternion (Hamilton)
//! ```
//!
//! Each entry is `world_from_sensor`: `p_world = R(q) · p_sensor + t` (the file's
//! `inverse_poses:` section holds the inverses; the reader does not need them). The
//! sensor frame is the one `opt_calibration` calibrated, a colour camera's optical frame:
//! for a Kinect v2, OpenPTrack's TF chain `/<sensor>` → `<sensor>_link` →
//! `<sensor>_rgb_frame` → `<sensor>_rgb_optical_frame` (`detection_initializer.py`, its
//! iai_kinect2 fork's `kinect2_frames.launch`) composes to the identity, so a depth
//! sensor's pose is `world_from_sensor · color_from_depth`. The reader accepts
//! the sensors either as top-level keys (the layout above, which the writer produces) or
//! nested under a top-level `poses:` mapping, as `opt_calibration` writes them next to a
//! `calibration_id`; other top-level scalars (`calibration_id`) are ignored. Sensors come
//! out in file order. Quaternions are normalised; a norm farther than
//! [`crate::QUATERNION_NORM_TOLERANCE`] from 1 is an error naming the sensor's `rotation`.

use std::path::Path;

use yaml_rust2::Yaml;

use crate::files::{float_text, read_text, write_atomic};
use crate::yaml::{Doc, join, load, type_name};
use crate::{CalibError, Pose};

/// Reads an OpenPTrack `camera_poses.yaml`: `(sensor name, world_from_sensor)` in file
/// order.
pub fn read_openptrack_poses(path: &Path) -> Result<Vec<(String, Pose)>, CalibError> {
    parse_openptrack_poses(&read_text(path)?, path)
}

/// Parses the text of an OpenPTrack `camera_poses.yaml`; `path` is used in error messages.
pub fn parse_openptrack_poses(text: &str, path: &Path) -> Result<Vec<(String, Pose)>, CalibError> {
    let doc = Doc { path };
    let root = load(text, path)?;
    let (sensors, parent) = match &root["poses"] {
        poses @ Yaml::Hash(_) => (poses, "poses"),
        _ => (&root, ""),
    };
    let Yaml::Hash(map) = sensors else {
        return Err(doc.bad(
            if parent.is_empty() {
                "document"
            } else {
                parent
            },
            format!("must be a mapping of sensors, got {}", type_name(sensors)),
        ));
    };
    let mut out = Vec::new();
    for (key, value) in map {
        let name = match key {
            Yaml::String(s) => s.clone(),
            Yaml::Integer(i) => i.to_string(),
            other => {
                return Err(doc.bad(
                    parent,
                    format!("sensor names must be strings, got {}", type_name(other)),
                ));
            }
        };
        // Top-level scalars such as `calibration_id` are not sensors.
        if !matches!(value, Yaml::Hash(_)) {
            continue;
        }
        let sensor_key = join(parent, &name);
        let t_key = join(&sensor_key, "translation");
        let r_key = join(&sensor_key, "rotation");
        let t_node = doc.get(value, &sensor_key, "translation")?;
        let r_node = doc.get(value, &sensor_key, "rotation")?;
        let component = |node: &Yaml, parent: &str, c: &str| {
            doc.number(doc.get(node, parent, c)?, &join(parent, c))
        };
        let t = [
            component(t_node, &t_key, "x")?,
            component(t_node, &t_key, "y")?,
            component(t_node, &t_key, "z")?,
        ];
        let q_wxyz = [
            component(r_node, &r_key, "w")?,
            component(r_node, &r_key, "x")?,
            component(r_node, &r_key, "y")?,
            component(r_node, &r_key, "z")?,
        ];
        let pose = Pose::from_quaternion_wxyz(q_wxyz, t).map_err(|e| match e {
            CalibError::Invalid { field, reason } => doc.bad(&r_key, format!("{field} {reason}")),
            other => other,
        })?;
        out.push((name, pose));
    }
    if out.is_empty() {
        return Err(doc.missing(&join(
            parent,
            "<sensor> (a mapping with translation and rotation)",
        )));
    }
    Ok(out)
}

/// The text of a `camera_poses.yaml` for these `(sensor name, world_from_sensor)` poses,
/// sensors as top-level keys in the given order. Names must be non-empty and unique.
///
/// Rotations are written as quaternions ([`Pose::quaternion_wxyz`]), so a round trip
/// reproduces each rotation matrix to about 1e-15 per element, not bit for bit;
/// translations are exact.
pub fn openptrack_poses_to_string(poses: &[(String, Pose)]) -> Result<String, CalibError> {
    let mut out = String::from(
        "# world_from_sensor poses: translation in metres, rotation as a unit quaternion\n",
    );
    for (i, (name, pose)) in poses.iter().enumerate() {
        if name.is_empty() {
            return Err(CalibError::invalid(
                format!("poses[{i}].name"),
                "must not be empty",
            ));
        }
        if poses[..i].iter().any(|(n, _)| n == name) {
            return Err(CalibError::invalid(
                format!("poses[{i}].name"),
                format!("{name:?} is used by an earlier sensor"),
            ));
        }
        // A JSON string is a valid YAML double-quoted scalar: safe for any name.
        let key = serde_json::to_string(name)
            .map_err(|e| CalibError::invalid(format!("poses[{i}].name"), e.to_string()))?;
        let t = pose.translation_m();
        let [w, x, y, z] = pose.quaternion_wxyz();
        out += &format!(
            "{key}:\n  translation:\n    x: {}\n    y: {}\n    z: {}\n  rotation:\n    x: {}\n    y: {}\n    z: {}\n    w: {}\n",
            float_text(t[0]),
            float_text(t[1]),
            float_text(t[2]),
            float_text(x),
            float_text(y),
            float_text(z),
            float_text(w),
        );
    }
    Ok(out)
}

/// Writes a `camera_poses.yaml` (through a temporary file and a rename).
pub fn write_openptrack_poses(path: &Path, poses: &[(String, Pose)]) -> Result<(), CalibError> {
    write_atomic(path, &openptrack_poses_to_string(poses)?)
}
