//! An advisory lock on an output folder, so that two processes do not write one batch
//! into one folder at once (the second one's frames would clash with the first's).

use crate::IoError;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Holds `<folder>/<name>` locked (`flock`, exclusive) with this process's id in it;
/// dropping it removes the file and releases the lock.
#[derive(Debug)]
pub struct FolderLock {
    /// Open while the lock is held (closing it releases the lock).
    _file: File,
    path: PathBuf,
    /// Removed by [`crate::remove_temporaries`] when a signal ends the process.
    _registered: crate::atomic::InFlight,
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while still locked: a process that opened it meanwhile finds it locked,
        // fails, and a later one creates a new file.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Why [`lock_folder`] failed.
#[derive(Debug)]
pub enum LockError {
    /// Another process holds the lock; its id as it wrote it (empty when unreadable).
    Held {
        /// The lock file.
        path: PathBuf,
        /// The holder's process id, as written in the file.
        pid: String,
    },
    /// The lock file cannot be created, locked or written.
    Io(IoError),
}

impl std::fmt::Display for LockError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LockError::Held { path, pid } => write!(
                f,
                "{}: another bodyseg (pid {}) is writing into this folder: wait for it to \
                 end or write elsewhere",
                path.display(),
                if pid.is_empty() { "unknown" } else { pid }
            ),
            LockError::Io(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for LockError {}

/// Locks `folder/name` (created if missing) for this process, writing its id into it.
///
/// # Errors
/// [`LockError::Held`] when another process holds it (naming its pid);
/// [`LockError::Io`] when the file cannot be created or locked.
pub fn lock_folder(folder: &Path, name: &str) -> Result<FolderLock, LockError> {
    let path = folder.join(name);
    let wrap = |cause: std::io::Error| {
        LockError::Io(IoError::Write {
            cause,
            path: path.clone(),
        })
    };
    // A few tries: the file may be removed by its holder between our open and our lock.
    for _ in 0..8 {
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(wrap)?;
        if let Err(e) =
            rustix::fs::flock(&file, rustix::fs::FlockOperation::NonBlockingLockExclusive)
        {
            if e == rustix::io::Errno::WOULDBLOCK {
                let mut pid = String::new();
                let _ = file.read_to_string(&mut pid);
                return Err(LockError::Held {
                    path,
                    pid: pid.trim().to_string(),
                });
            }
            return Err(wrap(e.into()));
        }
        // Locked: still the file at `path` (not one its holder removed meanwhile)?
        let same = match (file.metadata(), std::fs::metadata(&path)) {
            #[cfg(unix)]
            (Ok(a), Ok(b)) => {
                use std::os::unix::fs::MetadataExt;
                a.dev() == b.dev() && a.ino() == b.ino()
            }
            #[cfg(not(unix))]
            (Ok(_), Ok(_)) => true,
            _ => false,
        };
        if !same {
            continue;
        }
        file.set_len(0).map_err(wrap)?;
        file.seek(SeekFrom::Start(0)).map_err(wrap)?;
        file.write_all(format!("{}\n", std::process::id()).as_bytes())
            .map_err(wrap)?;
        let _registered = crate::atomic::InFlight::new(&path);
        return Ok(FolderLock {
            _file: file,
            path,
            _registered,
        });
    }
    Err(wrap(std::io::Error::other(
        "the lock file keeps being replaced",
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_naming_the_holder_and_the_file_goes_with_the_lock() {
        let dir = tempfile::tempdir().expect("temp dir");
        let lock = lock_folder(dir.path(), ".bodyseg.lock").expect("first");
        let e = lock_folder(dir.path(), ".bodyseg.lock").expect_err("second");
        let pid = std::process::id().to_string();
        assert!(
            matches!(&e, LockError::Held { pid: p, .. } if *p == pid),
            "{e}"
        );
        assert!(e.to_string().contains(&format!("(pid {pid})")), "{e}");
        // Another name (another shard) is another lock.
        let other = lock_folder(dir.path(), ".bodyseg.shard-0-of-2.lock").expect("other");
        drop(lock);
        drop(other);
        assert!(!dir.path().join(".bodyseg.lock").exists());
        let again = lock_folder(dir.path(), ".bodyseg.lock").expect("after release");
        drop(again);
    }
}
