//! A cloud file read by its extension into a [`CloudFile`] (apart from the type, so that
//! the readers it calls do not import the file that imports them).

use crate::{CloudFile, IoError};
use std::path::Path;

/// Reads a PLY or PCD file by its extension (`.ply`, `.pcd`, any case) with
/// [`crate::parse_ply_file`] or [`crate::parse_pcd_file`].
///
/// # Errors
/// [`IoError::UnknownCloudFormat`] for another extension, [`IoError::Read`] when the file
/// cannot be read, otherwise the parser's errors.
pub fn read_cloud_file(path: &Path) -> Result<CloudFile, IoError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let parse = match ext.as_deref() {
        Some("pcd") => crate::parse_pcd_file,
        Some("ply") => crate::parse_ply_file,
        _ => {
            return Err(IoError::UnknownCloudFormat {
                path: path.to_path_buf(),
            });
        }
    };
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    parse(&bytes, path)
}
