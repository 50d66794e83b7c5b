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

/// Creates `path` and its missing parents.
///
/// # Errors
/// [`IoError::Write`] naming `path`.
pub fn create_folder(path: &Path) -> Result<(), IoError> {
    std::fs::create_dir_all(path).map_err(|cause| IoError::Write {
        cause,
        path: path.to_path_buf(),
    })
}

/// A fresh, empty staging folder beside `dest` (`.<name>.partial-<pid>`), where a
/// multi-file output is written before [`publish_folder`] moves it into place. A stale
/// staging folder of an earlier crashed run of the same process id is removed first.
///
/// # Errors
/// [`IoError::Write`] naming the staging folder.
pub fn staging_folder(dest: &Path) -> Result<std::path::PathBuf, IoError> {
    let name = dest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
    if staging.exists() {
        std::fs::remove_dir_all(&staging).map_err(|cause| IoError::Write {
            cause,
            path: staging.clone(),
        })?;
    }
    create_folder(&staging)?;
    Ok(staging)
}

/// Moves the finished `staging` folder to `dest`. An existing `dest` is replaced only
/// when `replace` is true (it is removed just before the rename); otherwise it is an
/// error and `staging` is removed.
///
/// # Errors
/// [`IoError::Write`] naming `dest` (`AlreadyExists` when it exists and `replace` is
/// false).
pub fn publish_folder(staging: &Path, dest: &Path, replace: bool) -> Result<(), IoError> {
    let write_err = |cause| IoError::Write {
        cause,
        path: dest.to_path_buf(),
    };
    if dest.exists() {
        if !replace {
            let _ = std::fs::remove_dir_all(staging);
            return Err(write_err(std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "it already exists (use --force to replace it)",
            )));
        }
        if dest.is_dir() {
            std::fs::remove_dir_all(dest).map_err(write_err)?;
        } else {
            std::fs::remove_file(dest).map_err(write_err)?;
        }
    }
    std::fs::rename(staging, dest).map_err(write_err)
}

/// Removes a staging folder after a failure (best effort: errors are ignored because the
/// caller is already reporting the failure that matters).
pub fn discard_folder(staging: &Path) {
    let _ = std::fs::remove_dir_all(staging);
}

/// The PNG and JPEG files of a folder (by extension, any case: `.png`, `.jpg`, `.jpeg`),
/// sorted by name; sub-folders and other files are ignored.
///
/// # Errors
/// [`IoError::MissingFolder`] when `dir` is not a folder (`what` says what it should hold);
/// [`IoError::Read`] when it cannot be listed.
pub fn image_files(dir: &Path, what: &str) -> Result<Vec<std::path::PathBuf>, IoError> {
    require_folder(dir, what)?;
    let read_err = |cause| IoError::Read {
        cause,
        path: dir.to_path_buf(),
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(read_err)? {
        let path = entry.map_err(read_err)?.path();
        let is_image = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .is_some_and(|e| matches!(e.as_str(), "png" | "jpg" | "jpeg"));
        if is_image && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}
