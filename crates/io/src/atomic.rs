//! Atomic file replacement: write a temporary sibling, fsync, rename over the destination.

use crate::IoError;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Writes a file atomically: `write` fills a temporary file created in the destination's
/// directory, which is then flushed, fsynced and renamed over `path`.
///
/// Readers see either the old file or the complete new one, never a partial write. On
/// any error (from `write`, from flushing, syncing or renaming) the destination is left
/// exactly as it was and the temporary file is removed. The writer handed to `write` is
/// buffered, so many small writes are fine.
///
/// A new file gets the permissions [`std::fs::File::create`] would give it (`0o666` less
/// the umask on Unix). After the rename the directory is fsynced too, best effort (some
/// file systems refuse to sync a directory; that is not reported as an error).
///
/// # Errors
/// [`IoError::Write`] naming `path`, carrying the first I/O error met (including the one
/// `write` returned).
pub fn write_atomic<F>(path: &Path, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let wrap = |cause| IoError::Write {
        cause,
        path: path.to_path_buf(),
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".bodyseg-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    // Dropping `tmp` on any early return deletes the temporary file.
    let mut tmp = builder.tempfile_in(dir).map_err(wrap)?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        write(&mut w).map_err(wrap)?;
        w.flush().map_err(wrap)?;
    }
    tmp.as_file().sync_all().map_err(wrap)?;
    // On failure the PersistError owns the temporary file and deletes it when dropped.
    tmp.persist(path).map_err(|e| wrap(e.error))?;
    sync_dir(dir);
    Ok(())
}

/// Makes the rename durable where the platform allows it; errors are ignored on purpose
/// (the file itself is already synced and in place).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// Writes `bytes` to `path` atomically; see [`write_atomic`].
///
/// # Errors
/// [`IoError::Write`] naming `path`.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |w| w.write_all(bytes))
}
