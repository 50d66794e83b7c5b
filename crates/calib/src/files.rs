//! Small file helpers shared by the writers.

use std::path::{Path, PathBuf};

use crate::CalibError;

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so a
/// failed write never leaves a half-written file behind.
pub(crate) fn write_atomic(path: &Path, text: &str) -> Result<(), CalibError> {
    let tmp = temporary_path(path);
    let write_err = |cause| CalibError::Write {
        cause,
        path: path.to_path_buf(),
    };
    if let Err(e) = std::fs::write(&tmp, text) {
        // Best effort: the temporary may not exist at all.
        let _ = std::fs::remove_file(&tmp);
        return Err(write_err(e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        write_err(e)
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

fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "calib".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// `{:?}` of a finite `f64`: the shortest text that parses back to the same bits, and
/// always with a `.` or an exponent, so YAML and JSON readers see a float.
pub(crate) fn float_text(v: f64) -> String {
    format!("{v:?}")
}
