//! Plain UTF-8 text files (configurations, reports) and opaque binary files (ONNX models):
//! bodyseg-io reads them so that no other crate touches the file system.

use crate::IoError;
use std::path::Path;

/// Reads a whole UTF-8 text file.
///
/// The text is returned as is: a byte-order mark or CRLF line endings are not removed.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read, [`IoError::NotUtf8`] (naming the line
/// and byte offset of the first invalid byte) when it is not UTF-8.
pub fn read_text(path: &Path) -> Result<String, IoError> {
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..offset]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        IoError::NotUtf8 {
            line,
            offset,
            path: path.to_path_buf(),
        }
    })
}

/// Reads a whole file as bytes (an ONNX model), without interpreting them.
///
/// # Errors
/// [`IoError::Read`] naming the file when it cannot be read.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })
}

/// The first of `candidates` that is an existing file (following links), in order; `None`
/// when there is none. Used to find optional files such as the ONNX Runtime library.
pub fn first_existing_file(candidates: &[std::path::PathBuf]) -> Option<std::path::PathBuf> {
    candidates.iter().find(|p| p.is_file()).cloned()
}
