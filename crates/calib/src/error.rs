//! The crate's one error type.

use std::path::{Path, PathBuf};

/// Why a camera model, a rig or a calibration file is not usable.
///
/// Variants that concern a file carry its path, and their messages end with it. An I/O
/// cause is part of the message and deliberately not exposed as `source()` (the field is
/// `cause`, not `source`), so an error chain (`{:#}`) prints it once.
#[derive(Debug, thiserror::Error)]
pub enum CalibError {
    /// A value (intrinsics, pose, option) is out of its valid range; no file involved.
    #[error("{field} {reason}")]
    Invalid {
        /// Name of the field, e.g. `fx` or `rotation`.
        field: String,
        /// What is wrong with it, with the offending value.
        reason: String,
    },
    /// A file or folder could not be read.
    #[error("cannot read ({cause}): {path}")]
    Read {
        /// The underlying I/O error.
        cause: std::io::Error,
        /// The file that could not be read.
        path: PathBuf,
    },
    /// A file could not be written (nothing is left half-written).
    #[error("cannot write ({cause}): {path}")]
    Write {
        /// The underlying I/O error.
        cause: std::io::Error,
        /// The file that could not be written.
        path: PathBuf,
    },
    /// A file is not valid in its syntax (TOML, OpenCV FileStorage YAML).
    #[error("line {line}: {reason}: {path}")]
    Syntax {
        /// 1-based line of the problem (0 when the parser does not say).
        line: usize,
        /// What is wrong.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A key a format requires is missing.
    #[error("missing key {key}: {path}")]
    MissingKey {
        /// The key, with its parents (`camera.depth.fx`).
        key: String,
        /// The file.
        path: PathBuf,
    },
    /// A key's value has the wrong type, shape or range.
    #[error("{key}: {reason}: {path}")]
    BadValue {
        /// The key, with its parents.
        key: String,
        /// What is wrong, with the offending value.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A camera of a rig file has a missing or invalid field.
    #[error("camera {camera}: {field} {reason}: {path}")]
    CameraField {
        /// The camera's name (or `#index` when it has no name).
        camera: String,
        /// The field with its table (`depth.fx`, `color_from_depth.rotation`).
        field: String,
        /// What is wrong, with the offending value.
        reason: String,
        /// The rig file.
        path: PathBuf,
    },
    /// An OpenCV call failed (feature `opencv`).
    #[error("OpenCV {operation}: {cause}")]
    OpenCv {
        /// The OpenCV function or step, e.g. `calibrateCamera`.
        operation: String,
        /// OpenCV's message.
        cause: String,
    },
    /// A depth image does not have the size of the camera's depth sensor.
    #[error("camera {camera}: depth image has {got} pixels, calibration says {want_w}x{want_h}")]
    DepthSize {
        /// The camera's name.
        camera: String,
        /// Number of pixels given.
        got: usize,
        /// Width of the depth sensor, pixels.
        want_w: u32,
        /// Height of the depth sensor, pixels.
        want_h: u32,
    },
}

impl CalibError {
    /// An [`Intrinsics::validate`](crate::Intrinsics::validate) error of intrinsics read
    /// from `path`, as an error naming the file and the key its field came from:
    /// `distortion_key` for the distortion, `matrix_key` for the pinhole values.
    pub(crate) fn intrinsics_in_file(
        self,
        matrix_key: &str,
        distortion_key: &str,
        path: &Path,
    ) -> CalibError {
        match self {
            CalibError::Invalid { field, reason } => CalibError::BadValue {
                key: if field == "distortion" {
                    distortion_key
                } else {
                    matrix_key
                }
                .to_string(),
                reason: format!("{field} {reason}"),
                path: path.to_path_buf(),
            },
            other => other,
        }
    }

    /// Shorthand for [`CalibError::Invalid`].
    pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        CalibError::Invalid {
            field: field.into(),
            reason: reason.into(),
        }
    }
}
