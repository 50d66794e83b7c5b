//! Folder listings for dataset readers that discover their files (3DPeople).

use crate::IoError;
use std::path::Path;

/// One entry of a folder.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct FolderEntry {
    /// The entry's file name (no folder).
    pub name: String,
    /// True for a folder (links are followed), false for anything else.
    pub is_folder: bool,
}

/// The entries of folder `path`, sorted by name (byte order), links followed.
///
/// # Errors
/// [`IoError::MissingFolder`] (`what` names the folder's role) when `path` is not an
/// existing folder; [`IoError::Read`] naming `path` when it cannot be listed or an
/// entry's name is not UTF-8.
pub fn list_folder(path: &Path, what: &str) -> Result<Vec<FolderEntry>, IoError> {
    crate::require_folder(path, what)?;
    let read_err = |cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    };
    let mut entries = Vec::new();
    for entry in std::fs::read_dir(path).map_err(read_err)? {
        let entry = entry.map_err(read_err)?;
        let name = entry.file_name().into_string().map_err(|name| {
            read_err(std::io::Error::other(format!(
                "entry name {name:?} is not UTF-8"
            )))
        })?;
        // `Path::is_dir` follows links, unlike `DirEntry::file_type`.
        let is_folder = entry.path().is_dir();
        entries.push(FolderEntry { name, is_folder });
    }
    entries.sort();
    Ok(entries)
}
