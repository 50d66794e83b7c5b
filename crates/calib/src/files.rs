//! Small file helpers shared by the writers.

use std::path::Path;

use crate::CalibError;

/// Writes `text` to `path` atomically with `bodyseg_io::write_bytes_atomic` (temporary
/// sibling, fsync, rename), so a failed write never leaves a half-written file behind.
pub(crate) fn write_atomic(path: &Path, text: &str) -> Result<(), CalibError> {
    bodyseg_io::write_bytes_atomic(path, text.as_bytes()).map_err(|e| CalibError::Write {
        cause: match e {
            bodyseg_io::IoError::Write { cause, .. } => cause,
            other => std::io::Error::other(other.to_string()),
        },
        path: path.to_path_buf(),
    })
}

/// Reads a whole text file, the error naming it. A leading UTF-8 byte order mark is
/// dropped (Windows tools write one: the Azure Kinect SDK's own test calibration has it).
pub(crate) fn read_text(path: &Path) -> Result<String, CalibError> {
    let mut text = std::fs::read_to_string(path).map_err(|cause| CalibError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    if text.starts_with(BOM) {
        text.drain(..BOM.len_utf8());
    }
    Ok(text)
}

/// The UTF-8 byte order mark, U+FEFF.
const BOM: char = '\u{feff}';

/// `text` without a leading byte order mark: every parser of text calls it, so text read
/// by the caller (not through [`read_text`]) may carry one too.
pub(crate) fn without_bom(text: &str) -> &str {
    text.strip_prefix(BOM).unwrap_or(text)
}

/// `{:?}` of a finite `f64`: the shortest text that parses back to the same bits, and
/// always with a `.` or an exponent, so YAML and JSON readers see a float.
pub(crate) fn float_text(v: f64) -> String {
    format!("{v:?}")
}
