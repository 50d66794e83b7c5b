//! [`DirectFile`]: a large file streamed once, written past the page cache.
//!
//! On Linux an ordinary `write(2)` copies every byte into the page cache, and on the
//! 2-core VM this project is measured on that costs ~2 s of system time per GB (`dd
//! bs=8M count=64` of zeros: 1.05 s system time buffered, 0.07 s with `oflag=direct`).
//! A `.rrd` of `run --rerun` is ~11 MB a frame, written once and not read back by the
//! run: [`DirectFile`] writes it with `O_DIRECT` from an aligned buffer of its own
//! (docs/notes/2026-12-02-rerun.md, 2026-12-04). Where the file system refuses `O_DIRECT`
//! (tmpfs, some network file systems), and on other systems, it writes through the page
//! cache as any file.

use crate::IoError;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Alignment of `O_DIRECT` buffers, file offsets and lengths: 4096, the page size and the
/// largest logical block size of common devices.
const ALIGN: usize = 4096;

/// Bytes gathered before each write: large writes keep the device busy with few calls.
const BUFFER_BYTES: usize = 8 << 20;

/// A file written from the start, once, past the page cache where the system allows it
/// (see the module documentation). [`DirectFile::finish`] writes the last partial block
/// and cuts the file to its length; dropping it unfinished does the same and ignores
/// errors.
#[derive(Debug)]
pub struct DirectFile {
    file: File,
    path: PathBuf,
    /// Whether `file` was opened with `O_DIRECT`.
    direct: bool,
    /// `ALIGN` bytes more than [`BUFFER_BYTES`]: the aligned window starts at `start`.
    buf: Vec<u8>,
    start: usize,
    /// Bytes waiting in `buf[start..start + pending]`.
    pending: usize,
    /// Bytes written to the file so far (a multiple of `ALIGN` while direct).
    written: u64,
    finished: bool,
}

impl DirectFile {
    /// Creates (or truncates) `path` for writing.
    ///
    /// # Errors
    /// [`IoError::Write`] when the file cannot be created.
    pub fn create(path: &Path) -> Result<DirectFile, IoError> {
        let wrap = |cause: std::io::Error| IoError::Write {
            cause,
            path: path.to_path_buf(),
        };
        let (file, direct) = match open_direct(path) {
            Some(file) => (file, true),
            None => (File::create(path).map_err(wrap)?, false),
        };
        let buf = if direct {
            vec![0; BUFFER_BYTES + ALIGN]
        } else {
            Vec::new()
        };
        let start = buf.as_ptr().align_offset(ALIGN).min(buf.len());
        Ok(DirectFile {
            file,
            path: path.to_path_buf(),
            direct,
            buf,
            start,
            pending: 0,
            written: 0,
            finished: false,
        })
    }

    /// Whether the file is written past the page cache (`O_DIRECT`).
    pub fn is_direct(&self) -> bool {
        self.direct
    }

    /// Writes what is left (the last block padded with zeros, then the file cut to its
    /// length) and flushes.
    ///
    /// # Errors
    /// [`IoError::Write`] when a write or the truncation fails.
    pub fn finish(mut self) -> Result<(), IoError> {
        self.finish_inner().map_err(|cause| IoError::Write {
            cause,
            path: self.path.clone(),
        })
    }

    fn finish_inner(&mut self) -> std::io::Result<()> {
        if self.finished {
            return Ok(());
        }
        self.finished = true;
        if self.direct && self.pending > 0 {
            let length = self.written + self.pending as u64;
            let padded = self.pending.div_ceil(ALIGN) * ALIGN;
            self.buf[self.start + self.pending..self.start + padded].fill(0);
            self.pending = padded;
            self.write_blocks()?;
            self.file.set_len(length)?;
        }
        self.file.flush()
    }

    /// Writes the whole blocks of the pending bytes; the rest (under `ALIGN`) stays.
    fn write_blocks(&mut self) -> std::io::Result<()> {
        let whole = self.pending / ALIGN * ALIGN;
        if whole == 0 {
            return Ok(());
        }
        let window = self.start..self.start + whole;
        match self.file.write_all(&self.buf[window.clone()]) {
            Ok(()) => {}
            // Refused at the first write (the open succeeded, the file system does not
            // do direct I/O after all): go on through the page cache.
            Err(e) if self.written == 0 && e.kind() == std::io::ErrorKind::InvalidInput => {
                self.file = std::fs::OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(&self.path)?;
                self.direct = false;
                let all = self.start..self.start + self.pending;
                self.file.write_all(&self.buf[all])?;
                self.written = self.pending as u64;
                self.pending = 0;
                self.buf = Vec::new();
                self.start = 0;
                return Ok(());
            }
            Err(e) => return Err(e),
        }
        self.written += whole as u64;
        self.buf
            .copy_within(window.end..self.start + self.pending, self.start);
        self.pending -= whole;
        Ok(())
    }
}

impl Write for DirectFile {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        if !self.direct {
            return self.file.write(data);
        }
        let mut rest = data;
        while !rest.is_empty() {
            let n = (BUFFER_BYTES - self.pending).min(rest.len());
            let at = self.start + self.pending;
            self.buf[at..at + n].copy_from_slice(&rest[..n]);
            self.pending += n;
            rest = &rest[n..];
            if self.pending == BUFFER_BYTES {
                self.write_blocks()?;
                if !self.direct {
                    // Fell back to the page cache: the rest goes there.
                    self.file.write_all(rest)?;
                    break;
                }
            }
        }
        Ok(data.len())
    }

    /// Writes the whole blocks gathered so far; up to `ALIGN - 1` bytes stay in memory
    /// until [`DirectFile::finish`] (an `O_DIRECT` write cannot end mid-block).
    fn flush(&mut self) -> std::io::Result<()> {
        if self.direct {
            self.write_blocks()
        } else {
            self.file.flush()
        }
    }
}

impl Drop for DirectFile {
    fn drop(&mut self) {
        self.finish_inner().ok();
    }
}

/// `path` created with `O_DIRECT`, or `None` where the system or the file system refuses.
#[cfg(target_os = "linux")]
fn open_direct(path: &Path) -> Option<File> {
    use rustix::fs::{Mode, OFlags};
    let flags = OFlags::WRONLY | OFlags::CREATE | OFlags::TRUNC | OFlags::CLOEXEC | OFlags::DIRECT;
    let mode = Mode::from_raw_mode(0o666);
    rustix::fs::open(path, flags, mode).ok().map(File::from)
}

#[cfg(not(target_os = "linux"))]
fn open_direct(_path: &Path) -> Option<File> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes that differ at every offset, so a misplaced block shows.
    fn pattern(n: usize) -> Vec<u8> {
        (0..n).map(|i| (i * 31 + i / 4096) as u8).collect()
    }

    #[test]
    fn any_lengths_in_any_pieces_read_back_exactly() {
        let dir = tempfile::tempdir().expect("temp dir");
        // Under a block, a block, across the buffer, and an exact multiple of it.
        for total in [
            0,
            1,
            4095,
            4096,
            4097,
            BUFFER_BYTES + 12_345,
            2 * BUFFER_BYTES,
        ] {
            let path = dir.path().join(format!("f{total}.bin"));
            let data = pattern(total);
            let mut file = DirectFile::create(&path).expect("create");
            // Uneven pieces, with a flush between some of them.
            let mut at = 0;
            for (i, piece) in [1, 4095, 7, 3 << 20, 9 << 20].iter().cycle().enumerate() {
                if at >= total {
                    break;
                }
                let end = (at + piece).min(total);
                file.write_all(&data[at..end]).expect("write");
                if i % 2 == 0 {
                    file.flush().expect("flush");
                }
                at = end;
            }
            file.finish().expect("finish");
            assert_eq!(std::fs::read(&path).expect("read"), data, "{total} bytes");
        }
    }

    #[test]
    fn dropping_unfinished_still_leaves_the_whole_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("d.bin");
        let data = pattern(10_000);
        {
            let mut file = DirectFile::create(&path).expect("create");
            file.write_all(&data).expect("write");
        }
        assert_eq!(std::fs::read(&path).expect("read"), data);
    }

    #[test]
    fn a_missing_folder_is_a_write_error_naming_the_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("missing").join("f.bin");
        let e = DirectFile::create(&path)
            .expect_err("no folder")
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{e}");
    }
}
