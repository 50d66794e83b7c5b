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
    write_atomic_with(path, Durability::Synced, write)
}

/// How far a finished file is pushed to disk before [`write_atomic_with`] returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Durability {
    /// The file is fsynced before the rename and its folder after it: the new file
    /// survives a power loss once the call returns (the default).
    #[default]
    Synced,
    /// Rename only, no fsync: readers still see the old file or the whole new one, and a
    /// killed process loses nothing (the data is in the OS's cache), but after an OS
    /// crash or a power loss the file may be missing, empty or short. For many small
    /// outputs whose completeness is checked otherwise and that are synced in bulk
    /// ([`sync_file_system`]): `bodyseg run` and `convert` keep each frame output's
    /// size in the frame's record, and a size that does not match redoes the frame. Two
    /// fsyncs per file cost ~10% of `bodyseg run`'s throughput (six files per frame).
    Renamed,
}

/// [`write_atomic`] with a choice of [`Durability`].
///
/// # Errors
/// As [`write_atomic`].
pub fn write_atomic_with<F>(path: &Path, durability: Durability, write: F) -> Result<(), IoError>
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
    // Dropping `tmp` on any early return deletes the temporary file. Created and
    // registered in one step, so `remove_temporaries` (a signal handler) sees every
    // temporary until it is renamed or deleted, and none is created after it ran.
    let (mut tmp, _in_flight) = tempfile_registered(&builder, dir).map_err(wrap)?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        write(&mut w).map_err(wrap)?;
        w.flush().map_err(wrap)?;
    }
    let synced = durability == Durability::Synced;
    if synced {
        tmp.as_file().sync_all().map_err(wrap)?;
    }
    // On failure the PersistError owns the temporary file and deletes it when dropped.
    tmp.persist(path).map_err(|e| wrap(e.error))?;
    if synced {
        sync_dir(dir);
    }
    Ok(())
}

/// Pushes every file written so far on the file system holding `folder` to disk (one
/// `syncfs` on Linux; elsewhere the whole system's `sync` is not available from std, so
/// it only syncs `folder` itself): what [`Durability::Renamed`] writes leave to the end of
/// a batch.
///
/// # Errors
/// [`IoError::Write`] naming `folder` when it cannot be opened or synced.
pub fn sync_file_system(folder: &Path) -> Result<(), IoError> {
    let wrap = |cause| IoError::Write {
        cause,
        path: folder.to_path_buf(),
    };
    let dir = std::fs::File::open(folder).map_err(wrap)?;
    #[cfg(target_os = "linux")]
    {
        rustix::fs::syncfs(&dir).map_err(|e| wrap(e.into()))
    }
    #[cfg(not(target_os = "linux"))]
    {
        dir.sync_all().map_err(wrap)
    }
}

/// The temporary files of [`write_atomic_with`] being written now, process-wide, and
/// whether [`remove_temporaries`] has run (then no new temporary is created).
static IN_FLIGHT: std::sync::Mutex<InFlightFiles> = std::sync::Mutex::new(InFlightFiles {
    paths: Vec::new(),
    closed: false,
});

/// What [`IN_FLIGHT`] guards.
#[derive(Debug)]
struct InFlightFiles {
    paths: Vec<std::path::PathBuf>,
    closed: bool,
}

fn in_flight() -> std::sync::MutexGuard<'static, InFlightFiles> {
    match IN_FLIGHT.lock() {
        Ok(v) => v,
        Err(poisoned) => poisoned.into_inner(),
    }
}

/// Creates a temporary file in `dir` and registers it, under the registry's lock: a
/// signal handler's [`remove_temporaries`] either sees it or runs before it is created,
/// and after that handler no temporary is created at all (the write fails instead: the
/// process is about to exit).
fn tempfile_registered(
    builder: &tempfile::Builder<'_, '_>,
    dir: &Path,
) -> std::io::Result<(tempfile::NamedTempFile, InFlight)> {
    let mut state = in_flight();
    if state.closed {
        return Err(std::io::Error::new(
            std::io::ErrorKind::Interrupted,
            "interrupted: the process is ending, no new file is written",
        ));
    }
    let tmp = builder.tempfile_in(dir)?;
    let path = tmp.path().to_path_buf();
    state.paths.push(path.clone());
    Ok((tmp, InFlight(path)))
}

/// Registers a temporary file in [`IN_FLIGHT`] while it lives (also a folder's lock file,
/// which [`remove_temporaries`] removes too).
#[derive(Debug)]
pub(crate) struct InFlight(std::path::PathBuf);

impl InFlight {
    pub(crate) fn new(path: &Path) -> InFlight {
        let path = path.to_path_buf();
        in_flight().paths.push(path.clone());
        InFlight(path)
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        let mut state = in_flight();
        if let Some(i) = state.paths.iter().position(|p| *p == self.0) {
            state.paths.swap_remove(i);
        }
    }
}

/// Removes the temporary files of the atomic writes in flight (from a SIGINT/SIGTERM
/// handler, just before the process exits): an interrupted command leaves no hidden
/// `.bodyseg-*.tmp` behind. Returns how many were removed. A write that finishes
/// meanwhile is unaffected (its file was renamed: nothing to remove).
pub fn remove_temporaries() -> usize {
    in_flight().closed = true;
    remove_temporaries_where(|_| true)
}

/// [`remove_temporaries`] for the paths `which` selects (the others stay registered).
fn remove_temporaries_where(which: impl Fn(&Path) -> bool) -> usize {
    let paths: Vec<std::path::PathBuf> = {
        let mut state = in_flight();
        let (take, keep) = std::mem::take(&mut state.paths)
            .into_iter()
            .partition(|p| which(p));
        state.paths = keep;
        take
    };
    paths
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_in_flight_are_removed_on_request() {
        let dir = tempfile::tempdir().expect("temp dir");
        let d = dir.path().to_path_buf();
        let path = d.join("out.txt");
        let err = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            // What the signal handler does while this write is in flight (only this
            // folder's: other tests write at the same time).
            assert_eq!(remove_temporaries_where(|p| p.starts_with(&d)), 1);
            Ok(())
        });
        // The temporary is gone, so the rename fails; nothing is left.
        assert!(err.is_err());
        let left: Vec<_> = std::fs::read_dir(&d).expect("list").collect();
        assert!(left.is_empty(), "{left:?}");
        write_bytes_atomic(&path, b"x").expect("a later write");
        assert_eq!(remove_temporaries_where(|p| p.starts_with(&d)), 0);
        assert_eq!(std::fs::read(&path).expect("read"), b"x");
    }
}
