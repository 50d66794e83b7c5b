//! Checks on folders of a recording.

use crate::IoError;
use std::path::Path;

/// Succeeds when `path` is an existing folder (following links).
///
/// # Errors
/// [`IoError::MissingFolder`] naming `path` and `what` it is (`camera`):
/// `rec/cam1: camera folder is missing`.
pub fn require_folder(path: &Path, what: &str) -> Result<(), IoError> {
    if path.is_dir() {
        Ok(())
    } else {
        Err(IoError::MissingFolder {
            what: what.to_string(),
            path: path.to_path_buf(),
        })
    }
}
