//! RGB-D cameras (a depth sensor and a colour sensor) and rigs of them.

use crate::{CalibError, Intrinsics, Pose};

/// Default `depth_scale`: raw depth units per metre, 1000 = millimetres (Kinect, RealSense
/// in their default modes).
pub const DEFAULT_DEPTH_SCALE: f64 = 1000.0;

/// One RGB-D camera: a depth (IR) sensor and a colour sensor with their intrinsics, the
/// stereo extrinsic between them and the depth sensor's place in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdCamera {
    /// Name, unique in a rig; also the camera's folder name in a recording.
    pub name: String,
    /// Depth (IR) sensor intrinsics, depth image pixels.
    pub depth: Intrinsics,
    /// Colour sensor intrinsics, colour image pixels.
    pub color: Intrinsics,
    /// Maps a point of the depth sensor frame into the colour sensor frame (metres).
    pub color_from_depth: Pose,
    /// Maps a point of the depth sensor frame into the world frame (z up, metres).
    pub world_from_depth: Pose,
    /// Raw depth units per metre (default [`DEFAULT_DEPTH_SCALE`]).
    pub depth_scale: f64,
    /// Added to every measured depth, millimetres (iai_kinect2's `depthShift`; default 0).
    pub depth_shift_mm: f64,
}

impl RgbdCamera {
    /// A camera with identity extrinsics, scale 1000 and no shift.
    pub fn new(name: impl Into<String>, depth: Intrinsics, color: Intrinsics) -> Self {
        RgbdCamera {
            name: name.into(),
            depth,
            color,
            color_from_depth: Pose::identity(),
            world_from_depth: Pose::identity(),
            depth_scale: DEFAULT_DEPTH_SCALE,
            depth_shift_mm: 0.0,
        }
    }

    /// Checks both intrinsics, `depth_scale` finite and > 0, `depth_shift_mm` finite.
    /// The error's field has its table as prefix (`depth.fx`, `color.cy`).
    pub fn validate(&self) -> Result<(), CalibError> {
        let prefix = |table: &str, e: CalibError| match e {
            CalibError::Invalid { field, reason } => CalibError::Invalid {
                field: format!("{table}.{field}"),
                reason,
            },
            other => other,
        };
        self.depth.validate().map_err(|e| prefix("depth", e))?;
        self.color.validate().map_err(|e| prefix("color", e))?;
        if !(self.depth_scale.is_finite() && self.depth_scale > 0.0) {
            return Err(CalibError::invalid(
                "depth_scale",
                format!("must be finite and > 0, got {}", self.depth_scale),
            ));
        }
        if !self.depth_shift_mm.is_finite() {
            return Err(CalibError::invalid(
                "depth_shift_mm",
                format!("must be finite, got {}", self.depth_shift_mm),
            ));
        }
        Ok(())
    }

    /// [`Self::validate`], then `depth_scale` must be [`DEFAULT_DEPTH_SCALE`]: for writers
    /// of formats that store depth in millimetres with no scale; `why` ends the message
    /// after "must be 1000" (the format and its reason).
    pub(crate) fn validate_millimetre_depth(&self, why: &str) -> Result<(), CalibError> {
        self.validate()?;
        if self.depth_scale != DEFAULT_DEPTH_SCALE {
            return Err(CalibError::invalid(
                "depth_scale",
                format!(
                    "must be {DEFAULT_DEPTH_SCALE} {why}, got {}",
                    self.depth_scale
                ),
            ));
        }
        Ok(())
    }

    /// Depth in metres of a raw depth value: `raw / depth_scale + depth_shift_mm / 1000`.
    /// `None` for 0 (no measurement).
    pub fn depth_m(&self, raw: u16) -> Option<f64> {
        (raw != 0).then(|| f64::from(raw) / self.depth_scale + self.depth_shift_mm / 1000.0)
    }
}

/// A set of RGB-D cameras in one world frame. The order is the rig order: camera index
/// `i` of a [`bodyseg_core::PointOrigin`] is `cameras[i]`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Rig {
    /// The cameras, in rig order.
    pub cameras: Vec<RgbdCamera>,
}

impl Rig {
    /// Most cameras a rig may hold: a point's origin stores the camera index in a `u8`.
    pub const MAX_CAMERAS: usize = 256;

    /// Checks every camera, unique non-empty names and at most [`Rig::MAX_CAMERAS`].
    pub fn validate(&self) -> Result<(), CalibError> {
        if self.cameras.len() > Self::MAX_CAMERAS {
            return Err(CalibError::invalid(
                "camera",
                format!(
                    "a rig holds at most {} cameras, got {}",
                    Self::MAX_CAMERAS,
                    self.cameras.len()
                ),
            ));
        }
        for (i, cam) in self.cameras.iter().enumerate() {
            if cam.name.is_empty() {
                return Err(CalibError::invalid(
                    format!("camera[{i}].name"),
                    "must not be empty",
                ));
            }
            if self.cameras[..i].iter().any(|c| c.name == cam.name) {
                return Err(CalibError::invalid(
                    format!("camera[{i}].name"),
                    format!("{:?} is used by an earlier camera", cam.name),
                ));
            }
            cam.validate().map_err(|e| match e {
                CalibError::Invalid { field, reason } => CalibError::Invalid {
                    field: format!("camera {}: {field}", cam.name),
                    reason,
                },
                other => other,
            })?;
        }
        Ok(())
    }

    /// The camera with this name and its index, if any.
    pub fn camera(&self, name: &str) -> Option<(usize, &RgbdCamera)> {
        self.cameras
            .iter()
            .enumerate()
            .find(|(_, c)| c.name == name)
    }
}

/// A camera read from another tool's calibration files, with what the reader assumed
/// or left out (one line each, naming the file and the key), for the caller to show.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedCamera {
    /// The camera.
    pub camera: RgbdCamera,
    /// Notes: defaults taken for what the files do not hold (an iai_kinect2 folder
    /// without `calib_depth.yaml` → depth shift 0), values the model cannot hold.
    pub notes: Vec<String>,
}
