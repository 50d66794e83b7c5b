//! [`RrdFile`]: a run's `.rrd` file, written by the threads that log, and [`RrdFileSink`],
//! the Rerun SDK's sink that writes into it.
//!
//! The SDK's `FileSink` queues every chunk for a writer thread of its own, behind the SDK's
//! batcher thread: a frame's ~11 MB (3 cameras) went through two more threads, was freed by
//! another thread than the one that made it, and a run that logged faster than the writer
//! wrote queued frames in memory until the logger waited for the queue to drain
//! (docs/notes/2026-12-02-rerun.md, 2026-12-04 and 2026-12-04b). Here a frame's images and
//! clouds are encoded by the frame worker that made them ([`RrdFile::append_chunk`]: Arrow
//! IPC and LZ4 into buffers of that thread, outside any lock) and written under the file's
//! lock, and so are the small rows (boxes, scores), gathered over many frames
//! (`crate::rows`); the static data (cameras, palette, blueprint) still go through the SDK,
//! whose sink [`RrdFileSink`] writes them into the same file. Nothing is queued: memory does not
//! grow with a run's speed. A write error is kept and reported when the file is closed.
//!
//! The file is a [`bodyseg_io::DirectFile`]: on Linux `O_DIRECT` writes from an aligned
//! buffer instead of copying ~11 MB a frame into the page cache, and the stream is encoded by
//! [`RrdEncoder`], the SDK encoder's format with buffers kept from one message to the next.

use crate::encoder::{Lz4, RrdEncoder, Scratch, encode_chunk};
use bodyseg_io::DirectFile;
use re_sdk::external::re_log_types::{ArrowMsg, StoreId};
use re_sdk::log::LogMsg;
use re_sdk::sink::{LogSink, SinkFlushError};
use std::cell::RefCell;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;

thread_local! {
    /// Each logging thread's buffers for encoding chunks (a frame worker's: about twice
    /// the largest chunk it has compressed, ~1-2 MB).
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// A `.rrd` file written by several threads (see the module documentation).
pub(crate) struct RrdFile {
    state: Mutex<State>,
}

struct State {
    /// `None` once closed.
    encoder: Option<RrdEncoder<DirectFile>>,
    /// The first write error: every later write and flush answers with it.
    failed: Option<String>,
    /// How closing went, once closed.
    closed: Option<Result<(), String>>,
}

impl RrdFile {
    /// Creates `path` and writes the stream header.
    pub(crate) fn create(path: &Path) -> Result<Arc<RrdFile>, String> {
        let file = DirectFile::create(path).map_err(|e| e.to_string())?;
        // LZ4 where it shrinks a chunk (without it the file is ~40 % larger and no faster).
        let encoder = RrdEncoder::new(re_sdk::build_info().version, file)?;
        Ok(Arc::new(RrdFile {
            state: Mutex::new(State {
                encoder: Some(encoder),
                failed: None,
                closed: None,
            }),
        }))
    }

    /// Runs `f` on the encoder under the lock; its error is the file's from then on.
    fn with_encoder<T>(
        &self,
        f: impl FnOnce(&mut RrdEncoder<DirectFile>) -> Result<T, String>,
    ) -> Result<T, String> {
        let mut state = self
            .state
            .lock()
            .map_err(|_| "a thread panicked while writing the file".to_string())?;
        if let Some(e) = &state.failed {
            return Err(e.clone());
        }
        let encoder = state
            .encoder
            .as_mut()
            .ok_or_else(|| "the file is already closed".to_string())?;
        let result = f(encoder);
        if let Err(e) = &result {
            state.failed = Some(format!("writing the file: {e}"));
        }
        result.map_err(|e| format!("writing the file: {e}"))
    }

    /// Writes a message as the SDK sends it (store info, static data, batched rows).
    pub(crate) fn append(&self, msg: &LogMsg) -> Result<(), String> {
        self.with_encoder(|e| e.append(msg))
    }

    /// Encodes a chunk of `store_id` in this thread (its buffers, no lock held; LZ4 as
    /// `lz4` allows), then writes it under the file's lock. Errs only when the chunk cannot
    /// be encoded: a write error is kept by the file and reported by [`RrdFile::close`]
    /// (as the SDK's own file sink does: a frame's other outputs are not lost for it), and
    /// after `close` chunks are dropped.
    pub(crate) fn append_chunk(
        &self,
        store_id: &StoreId,
        msg: &ArrowMsg,
        lz4: Lz4,
    ) -> Result<(), String> {
        SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            let chunk = encode_chunk(store_id, msg, lz4, &mut scratch)
                .map_err(|e| format!("encoding a chunk: {e}"))?;
            self.with_encoder(|e| e.write_chunk(&chunk)).ok();
            Ok(())
        })
    }

    /// Writes out what the file buffers (whole blocks; the last partial block stays until
    /// [`RrdFile::close`]).
    pub(crate) fn flush(&self) -> Result<(), String> {
        self.with_encoder(RrdEncoder::flush)
    }

    /// Ends the file (end-of-stream marker, footer, last block) and closes it; later calls
    /// answer how the first went. Chunks given after it are dropped.
    pub(crate) fn close(&self) -> Result<(), String> {
        let mut state = self
            .state
            .lock()
            .map_err(|_| "a thread panicked while writing the file".to_string())?;
        if let Some(closed) = &state.closed {
            return closed.clone();
        }
        let result = match (state.encoder.take(), &state.failed) {
            (_, Some(e)) => Err(e.clone()),
            (None, None) => Err("the file was never opened".to_string()),
            (Some(encoder), None) => encoder
                .finish()
                .and_then(|file| file.finish().map_err(|e| e.to_string()))
                .map_err(|e| format!("ending the file: {e}")),
        };
        state.closed = Some(result.clone());
        result
    }
}

/// The Rerun SDK's sink for an [`RrdFile`]: writes each message it is sent, in the SDK's
/// thread that sends it. Closing the file is [`RrdFile::close`]'s (the SDK drops a sink it
/// replaces without a way to answer).
pub(crate) struct RrdFileSink {
    file: Arc<RrdFile>,
}

impl RrdFileSink {
    pub(crate) fn new(file: Arc<RrdFile>) -> RrdFileSink {
        RrdFileSink { file }
    }
}

impl LogSink for RrdFileSink {
    fn send(&self, msg: LogMsg) {
        // A failure is kept by the file: the next flush, chunk or close reports it.
        self.file.append(&msg).ok();
    }

    fn flush_blocking(&self, _timeout: Duration) -> Result<(), SinkFlushError> {
        self.file.flush().map_err(SinkFlushError::failed)
    }

    fn defers_finalization_to_shutdown(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_protos::log_msg::v1alpha1::log_msg::Msg;
    use re_sdk::RecordingStreamBuilder;
    use re_sdk::external::re_log_encoding::{Decodable, DecoderApp, MessageHeader};
    use re_sdk::log::{Chunk, ChunkId, RowId};
    use re_sdk::time::Timeline;
    use re_sdk_types::archetypes::{Points3D, Scalars};
    use std::collections::BTreeMap;

    /// `n` points of noise (LZ4 leaves them as they are: such chunks go uncompressed).
    fn noise_points(n: usize, seed: u32) -> Vec<[f32; 3]> {
        let mut x = seed.wrapping_mul(2_654_435_761) | 1;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    /// Chunks encoded by four threads at once, and the SDK's rows and static data between
    /// them, land whole in one file: the SDK's decoder reads every chunk back once, equal
    /// to what was sent, and the footer's manifest points at each chunk's own bytes.
    #[test]
    fn chunks_from_many_threads_and_the_sdk_read_back_whole() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("t.rrd");
        let file = RrdFile::create(&path).expect("create");
        let rec = RecordingStreamBuilder::new("sink_test")
            .buffered()
            .expect("stream");
        rec.set_sink(Box::new(RrdFileSink::new(file.clone())));
        let store_id = rec.store_info().expect("enabled").store_id;
        rec.log_static("world", &Scalars::single(1.0))
            .expect("static");
        rec.flush_blocking().expect("flush");
        let sent: BTreeMap<ChunkId, Chunk> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..4_u32)
                .map(|t| {
                    let (file, rec, store_id) = (&file, &rec, &store_id);
                    s.spawn(move || {
                        let mut sent = Vec::new();
                        for frame in 0..12_u32 {
                            // Small (LZ4) and large noise (uncompressed) chunks.
                            let n = [10, 9000, 300][frame as usize % 3];
                            let points = Points3D::new(noise_points(n, t * 100 + frame))
                                .with_class_ids((0..n).map(|i| (i % 7) as u16));
                            let chunk = Chunk::builder(format!("world/t{t}"))
                                .with_archetype(
                                    RowId::new(),
                                    [(Timeline::new_sequence("frame"), i64::from(frame))],
                                    &points,
                                )
                                .build()
                                .expect("chunk");
                            let msg = chunk.to_arrow_msg().expect("message");
                            file.append_chunk(store_id, &msg, Lz4::WhereWorth)
                                .expect("append");
                            rec.set_time_sequence("frame", i64::from(frame));
                            rec.log(format!("scores/t{t}"), &Scalars::single(f64::from(frame)))
                                .expect("log");
                            sent.push((chunk.id(), chunk));
                        }
                        sent
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().expect("worker"))
                .collect()
        });
        rec.flush_blocking().expect("flush");
        rec.disconnect();
        file.close().expect("close");
        let length = std::fs::metadata(&path).expect("file").len();
        let (_, any) = sent.iter().next().expect("chunks");
        let late = any.to_arrow_msg().expect("message");
        file.append_chunk(&store_id, &late, Lz4::WhereWorth)
            .expect("dropped after close");
        assert!(file.close().is_ok(), "a second close answers the first");
        assert_eq!(std::fs::metadata(&path).expect("file").len(), length);

        let bytes = std::fs::read(&path).expect("read");
        let mut decoder =
            DecoderApp::decode_eager(std::io::BufReader::new(&bytes[..])).expect("an .rrd");
        let mut got: BTreeMap<ChunkId, usize> = BTreeMap::new();
        let mut sdk_rows = 0;
        for msg in decoder.by_ref() {
            if let LogMsg::ArrowMsg(_, arrow) = msg.expect("message") {
                let chunk = Chunk::from_arrow_msg(&arrow).expect("chunk");
                match sent.get(&chunk.id()) {
                    Some(want) => {
                        assert!(chunk.are_equal(want), "chunk {} differs", chunk.id());
                        *got.entry(chunk.id()).or_default() += 1;
                    }
                    None if chunk.entity_path().to_string().starts_with("/scores") => {
                        sdk_rows += chunk.num_rows();
                    }
                    None => {}
                }
            }
        }
        assert_eq!(got.len(), sent.len(), "every chunk read back");
        assert!(got.values().all(|&n| n == 1), "each once");
        assert_eq!(sdk_rows, 4 * 12, "the SDK's rows too");

        // The footer: each chunk's span holds that chunk's message.
        let manifests = decoder.rrd_manifests().expect("footer");
        let manifest = manifests
            .iter()
            .find(|m| m.store_id == store_id)
            .expect("the recording's manifest");
        let ids: Vec<ChunkId> = manifest.col_chunk_id().expect("ids").collect();
        let offsets: Vec<u64> = manifest.col_chunk_byte_offset().expect("offsets").collect();
        let sizes: Vec<u64> = manifest.col_chunk_byte_size().expect("sizes").collect();
        let mut listed = 0;
        for ((id, offset), size) in ids.iter().zip(&offsets).zip(&sizes) {
            let start = *offset as usize - MessageHeader::ENCODED_SIZE_BYTES;
            let end = (*offset + *size) as usize;
            let Some(Msg::ArrowMsg(msg)) =
                Option::<Msg>::from_rrd_bytes(&bytes[start..end]).expect("a message")
            else {
                panic!("chunk {id}: not an Arrow message at its span");
            };
            let want: re_protos::common::v1alpha1::Tuid = id.as_tuid().into();
            assert_eq!(msg.chunk_id, Some(want), "the span of chunk {id}");
            listed += usize::from(sent.contains_key(id));
        }
        assert_eq!(listed, sent.len(), "the manifest lists every chunk");
    }
}
