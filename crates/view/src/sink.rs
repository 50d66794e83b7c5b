//! [`RrdFileSink`]: the Rerun SDK's file sink, writing past the page cache.
//!
//! The same as the SDK's `FileSink` (one writer thread, a queue of 1024 messages, LZ4 where it
//! shrinks a chunk, the RRD footer), but the file is a [`bodyseg_io::DirectFile`]: on Linux
//! `O_DIRECT` writes from an aligned buffer instead of copying ~11 MB a frame into the page cache,
//! which cost most of the system time that `--rerun` added (docs/notes/2026-12-02-rerun.md,
//! 2026-12-04), and the stream is encoded by [`RrdEncoder`], the SDK encoder's format with
//! buffers kept from one message to the next.

use crate::encoder::RrdEncoder;
use bodyseg_io::DirectFile;
use re_sdk::log::ChunkBatcherConfig;
use re_sdk::log::LogMsg;
use re_sdk::sink::{LogSink, SinkFlushError};
use std::path::Path;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Messages the sink queues for its writer thread before `send` blocks: as the SDK's
/// `FileSink` (its messages are chunks, so this bounds them by count, not bytes; the
/// writer's back-pressure bounds the bytes).
const QUEUE_MESSAGES: usize = 1024;

/// Bytes of pending rows of one entity after which the SDK's batcher makes them a chunk
/// (its default: 2 MiB). A frame's images (~0.4-0.8 MB each) then go out one row per chunk,
/// as the clouds do, instead of two or three frames' rows being concatenated into one
/// chunk: a copy and its fresh memory saved (docs/notes/2026-12-02-rerun.md, 2026-12-04,
/// session 41). `RERUN_FLUSH_NUM_BYTES` still overrides it.
const BATCH_FLUSH_BYTES: u64 = 256 << 10;

enum Command {
    Write(Box<LogMsg>),
    /// Flush the file, then answer.
    Flush(SyncSender<Result<(), String>>),
}

/// How the closing of the file went: `None` until the sink is dropped (and its thread has
/// written the end of the file), then `Some(Ok)` or the error. The SDK drops a sink it
/// replaces without a way to answer, so the writer reads the outcome here.
pub(crate) type Closed = Arc<Mutex<Option<Result<(), String>>>>;

/// Writes the messages it is sent to a `.rrd` file (LZ4 where it shrinks a chunk) on its own
/// thread.
/// Dropping it closes the file (end-of-stream marker, footer, last block) and joins the
/// thread; the outcome goes to its [`Closed`].
pub(crate) struct RrdFileSink {
    tx: Mutex<Option<SyncSender<Command>>>,
    thread: Mutex<Option<JoinHandle<()>>>,
}

impl RrdFileSink {
    /// Creates `path` and writes the stream header; with the handle that will hold how
    /// closing the file went.
    pub(crate) fn create(path: &Path) -> Result<(RrdFileSink, Closed), String> {
        let file = DirectFile::create(path).map_err(|e| e.to_string())?;
        // LZ4 where it shrinks a chunk (without it the file is ~40 % larger and no faster).
        let encoder = RrdEncoder::new(re_sdk::build_info().version, file)?;
        let (tx, rx) = sync_channel(QUEUE_MESSAGES);
        let closed: Closed = Arc::new(Mutex::new(None));
        let outcome = closed.clone();
        let thread = std::thread::Builder::new()
            .name("rrd_writer".into())
            .spawn(move || {
                let result = write_all(encoder, &rx);
                if let Ok(mut o) = outcome.lock() {
                    *o = Some(result);
                }
            })
            .map_err(|e| e.to_string())?;
        let sink = RrdFileSink {
            tx: Mutex::new(Some(tx)),
            thread: Mutex::new(Some(thread)),
        };
        Ok((sink, closed))
    }

    fn sender(&self) -> Option<SyncSender<Command>> {
        self.tx.lock().ok().and_then(|tx| tx.clone())
    }
}

/// The writer thread: encodes and writes each message; on a write error it drops the rest
/// and answers every flush with the error. When the channel closes it ends the file; the
/// first error of all, if any, is the result.
fn write_all(mut encoder: RrdEncoder<DirectFile>, rx: &Receiver<Command>) -> Result<(), String> {
    let mut failed: Option<String> = None;
    while let Ok(command) = rx.recv() {
        match command {
            Command::Write(msg) => {
                if failed.is_none()
                    && let Err(e) = encoder.append(&msg)
                {
                    failed = Some(format!("writing the file: {e}"));
                }
            }
            Command::Flush(done) => {
                let result = match &failed {
                    Some(e) => Err(e.clone()),
                    None => encoder.flush(),
                };
                done.send(result).ok();
            }
        }
    }
    if let Some(e) = failed {
        return Err(e);
    }
    // The channel is closed: end-of-stream marker and footer, the last block, then the
    // file is closed.
    let file = encoder
        .finish()
        .map_err(|e| format!("ending the file: {e}"))?;
    file.finish().map_err(|e| format!("ending the file: {e}"))
}

impl LogSink for RrdFileSink {
    fn send(&self, msg: LogMsg) {
        if let Some(tx) = self.sender() {
            tx.send(Command::Write(Box::new(msg))).ok();
        }
    }

    fn flush_blocking(&self, timeout: Duration) -> Result<(), SinkFlushError> {
        let tx = self
            .sender()
            .ok_or_else(|| SinkFlushError::failed("the file is closed"))?;
        let (done_tx, done_rx) = sync_channel(1);
        tx.send(Command::Flush(done_tx))
            .map_err(|_| SinkFlushError::failed("the file writer thread has stopped"))?;
        match done_rx.recv_timeout(timeout) {
            Ok(result) => result.map_err(SinkFlushError::failed),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => Err(SinkFlushError::Timeout),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                Err(SinkFlushError::failed("the file writer thread has stopped"))
            }
        }
    }

    fn defers_finalization_to_shutdown(&self) -> bool {
        true
    }

    fn default_batcher_config(&self) -> ChunkBatcherConfig {
        ChunkBatcherConfig {
            flush_num_bytes: BATCH_FLUSH_BYTES,
            ..ChunkBatcherConfig::DEFAULT
        }
    }
}

impl Drop for RrdFileSink {
    fn drop(&mut self) {
        // Closing the channel ends the thread's loop; it then finishes the file.
        if let Ok(mut tx) = self.tx.lock() {
            tx.take();
        }
        if let Ok(mut thread) = self.thread.lock()
            && let Some(thread) = thread.take()
        {
            thread.join().ok();
        }
    }
}
