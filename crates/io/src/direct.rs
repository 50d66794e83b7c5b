//! [`DirectFile`]: a large file streamed once, written past the page cache.
//!
//! On Linux an ordinary `write(2)` copies every byte into the page cache, and on the
//! 2-core VM this project is measured on that costs ~2 s of system time per GB (`dd
//! bs=8M count=64` of zeros: 1.05 s system time buffered, 0.07 s with `oflag=direct`).
//! A `.rrd` of `run --rerun` is ~11 MB a frame, written once and not read back by the
//! run: [`DirectFile`] writes it with `O_DIRECT` from aligned buffers of its own
//! (docs/notes/2026-12-02-rerun.md, 2026-12-04). An `O_DIRECT` write returns when the
//! device has the data, so full buffers are written by a thread of its own while the
//! caller fills another (up to [`MAX_BLOCKS`] buffers): the caller waits for the device
//! only when it is that many buffers ahead of it. The `.rrd` is written by the
//! frame workers under a lock: waiting there for each 8 MB write made `run --rerun` ~7 %
//! slower (docs/notes/2026-12-02-rerun.md, 2026-12-04b).
//! Where the file system refuses `O_DIRECT` (tmpfs, some network file systems), and on
//! other systems, it writes through the page cache as any file.

use crate::IoError;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

/// Alignment of `O_DIRECT` buffers, file offsets and lengths: 4096, the page size and the
/// largest logical block size of common devices.
const ALIGN: usize = 4096;

/// Bytes gathered before each write: large writes keep the device busy with few calls.
const BUFFER_BYTES: usize = 8 << 20;

/// Buffers at most: the one being filled and up to three with the writer thread. A buffer
/// is made only when every other is still being written: a writer that keeps up uses two.
/// With two at most, the frame workers of `run --rerun` waited for the device in bursts
/// (~12 MB a frame from two workers at once): 76-150 ms per 96 frames, under the file's
/// lock (docs/notes/2026-12-02-rerun.md, 2026-12-04c).
const MAX_BLOCKS: usize = 4;

/// A buffer of [`BUFFER_BYTES`] aligned to [`ALIGN`].
#[derive(Debug)]
struct Block {
    /// `ALIGN` bytes more than [`BUFFER_BYTES`]: the aligned window starts at `start`.
    buf: Vec<u8>,
    start: usize,
}

impl Block {
    fn new() -> Block {
        let buf = vec![0; BUFFER_BYTES + ALIGN];
        let start = buf.as_ptr().align_offset(ALIGN).min(ALIGN);
        Block { buf, start }
    }

    fn bytes(&self) -> &[u8] {
        &self.buf[self.start..self.start + BUFFER_BYTES]
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.buf[self.start..self.start + BUFFER_BYTES]
    }
}

/// The thread that writes full buffers (their first `n` bytes, in the order sent) and
/// hands each back with the outcome; after a failed write it writes nothing more.
#[derive(Debug)]
struct BlockWriter {
    to: Option<SyncSender<(Block, usize)>>,
    back: Receiver<(Block, std::io::Result<()>)>,
    thread: Option<JoinHandle<()>>,
}

impl BlockWriter {
    /// Starts the thread on `file` (a handle sharing the caller's file offset).
    fn start(mut file: File) -> std::io::Result<BlockWriter> {
        let (to, blocks) = sync_channel::<(Block, usize)>(MAX_BLOCKS);
        let (done, back) = sync_channel(MAX_BLOCKS);
        let thread = std::thread::Builder::new()
            .name("direct_write".into())
            .spawn(move || {
                let mut failed = false;
                for (block, n) in blocks {
                    let result = if failed {
                        Err(std::io::Error::other("an earlier write to the file failed"))
                    } else {
                        file.write_all(&block.bytes()[..n])
                    };
                    failed |= result.is_err();
                    if done.send((block, result)).is_err() {
                        break;
                    }
                }
            })?;
        Ok(BlockWriter {
            to: Some(to),
            back,
            thread: Some(thread),
        })
    }

    /// Waits for every buffer sent to be written and ends the thread; the first error.
    fn finish(mut self) -> std::io::Result<()> {
        self.to.take();
        let mut first_error = None;
        for (_, result) in self.back.iter() {
            if let Err(e) = result {
                first_error.get_or_insert(e);
            }
        }
        if let Some(thread) = self.thread.take() {
            thread
                .join()
                .map_err(|_| std::io::Error::other("the file's writer thread panicked"))?;
        }
        first_error.map_or(Ok(()), Err)
    }
}

/// The writer thread is gone (it ends only when told to, or by a panic).
fn writer_gone() -> std::io::Error {
    std::io::Error::other("the file's writer thread has stopped")
}

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
    /// The buffer being filled (`None` once writing through the page cache).
    block: Option<Block>,
    /// Buffers written and handed back by the writer thread, ready to be filled.
    spare: Vec<Block>,
    /// Buffers made so far (at most [`MAX_BLOCKS`]).
    made: usize,
    /// Bytes waiting in `block`'s first bytes.
    pending: usize,
    /// Bytes written or handed to the writer thread so far (a multiple of `ALIGN` while
    /// direct).
    written: u64,
    /// Writes full buffers after the first (which is written here: a file system may
    /// refuse `O_DIRECT` only at the first write).
    writer: Option<BlockWriter>,
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
        Ok(DirectFile {
            file,
            path: path.to_path_buf(),
            direct,
            block: direct.then(Block::new),
            spare: Vec::new(),
            made: 1,
            pending: 0,
            written: 0,
            writer: None,
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
        // Every full buffer first: the writer thread shares the file's offset.
        if let Some(writer) = self.writer.take() {
            writer.finish()?;
        }
        if self.direct
            && self.pending > 0
            && let Some(block) = &mut self.block
        {
            let length = self.written + self.pending as u64;
            let padded = self.pending.div_ceil(ALIGN) * ALIGN;
            block.bytes_mut()[self.pending..padded].fill(0);
            self.pending = padded;
            self.write_blocks()?;
            self.file.set_len(length)?;
        }
        self.file.flush()
    }

    /// Writes the whole blocks of the pending bytes here and now; the rest (under `ALIGN`)
    /// stays. The first write, and the last.
    fn write_blocks(&mut self) -> std::io::Result<()> {
        let whole = self.pending / ALIGN * ALIGN;
        let Some(block) = &mut self.block else {
            return Ok(());
        };
        if whole == 0 {
            return Ok(());
        }
        match self.file.write_all(&block.bytes()[..whole]) {
            Ok(()) => {}
            // Refused at the first write (the open succeeded, the file system does not
            // do direct I/O after all): go on through the page cache.
            Err(e) if self.written == 0 && e.kind() == std::io::ErrorKind::InvalidInput => {
                self.file = std::fs::OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(&self.path)?;
                self.direct = false;
                self.file.write_all(&block.bytes()[..self.pending])?;
                self.written = self.pending as u64;
                self.pending = 0;
                self.block = None;
                return Ok(());
            }
            Err(e) => return Err(e),
        }
        self.written += whole as u64;
        block.bytes_mut().copy_within(whole..self.pending, 0);
        self.pending -= whole;
        Ok(())
    }

    /// Hands the whole blocks of the pending bytes to the writer thread (the first write
    /// is made here, see [`DirectFile::writer`]) and goes on in another buffer: one the
    /// thread has written, else a new one (up to [`MAX_BLOCKS`]), else the next the thread
    /// hands back (the only wait).
    fn hand_off(&mut self) -> std::io::Result<()> {
        let whole = self.pending / ALIGN * ALIGN;
        if whole == 0 || self.block.is_none() {
            return Ok(());
        }
        if self.written == 0 {
            return self.write_blocks();
        }
        if self.writer.is_none() {
            self.writer = Some(BlockWriter::start(self.file.try_clone()?)?);
        }
        let (Some(writer), Some(block)) = (&mut self.writer, &mut self.block) else {
            return Ok(());
        };
        // The buffers written meanwhile, and their errors.
        while let Ok((returned, result)) = writer.back.try_recv() {
            result?;
            self.spare.push(returned);
        }
        let mut next = match self.spare.pop() {
            Some(spare) => spare,
            None if self.made < MAX_BLOCKS => {
                self.made += 1;
                Block::new()
            }
            None => {
                let (returned, result) = writer.back.recv().map_err(|_| writer_gone())?;
                result?;
                returned
            }
        };
        let rest = self.pending - whole;
        next.bytes_mut()[..rest].copy_from_slice(&block.bytes()[whole..self.pending]);
        let full = std::mem::replace(block, next);
        writer
            .to
            .as_ref()
            .ok_or_else(writer_gone)?
            .send((full, whole))
            .map_err(|_| writer_gone())?;
        self.written += whole as u64;
        self.pending = rest;
        Ok(())
    }
}

impl Write for DirectFile {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        let mut rest = data;
        while !rest.is_empty() {
            let Some(block) = &mut self.block else {
                // Through the page cache (never direct, or fell back to it).
                self.file.write_all(rest)?;
                break;
            };
            let n = (BUFFER_BYTES - self.pending).min(rest.len());
            block.bytes_mut()[self.pending..self.pending + n].copy_from_slice(&rest[..n]);
            self.pending += n;
            rest = &rest[n..];
            if self.pending == BUFFER_BYTES {
                self.hand_off()?;
            }
        }
        Ok(data.len())
    }

    /// Hands the whole blocks gathered so far to be written (they are on disk once
    /// [`DirectFile::finish`] returns); up to `ALIGN - 1` bytes stay in memory until then
    /// (an `O_DIRECT` write cannot end mid-block).
    fn flush(&mut self) -> std::io::Result<()> {
        if self.block.is_some() {
            self.hand_off()
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
            5 * BUFFER_BYTES + 4097,
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
