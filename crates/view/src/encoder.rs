//! [`RrdEncoder`]: the `.rrd` stream of `re_log_encoding` 0.36.3's `Encoder` (stream
//! header, Arrow IPC messages, end marker, RRD footer with its manifest), written with
//! buffers kept from one message to the next.
//!
//! The SDK's `Encoder::append` encodes each chunk into a new `Vec` grown by doubling, LZ4
//! compresses it into another new `Vec`, then copies the result into a scratch `Vec` before
//! writing it: on this project's 2-core VM the fresh pages of those buffers and the copies
//! were most of the writer thread's time (docs/notes/2026-12-02-rerun.md, 2026-12-04,
//! sessions 41 and 42). Here a chunk's Arrow IPC stream is gathered from the batch's own
//! buffers ([`IpcStream`]) and copied once: into an IPC buffer kept by the encoding thread
//! ([`Scratch`]), then LZ4-compressed into its LZ4 buffer (also kept) and written from there;
//! or, for a chunk that LZ4 would barely shrink (float positions, the colour images' PNG/JPEG
//! files) or that is not to be compressed ([`Lz4::Never`]: depth), straight into the file,
//! uncompressed. The encoding ([`encode_chunk`]) and the writing ([`RrdEncoder::write_chunk`])
//! are apart, so that frame workers encode without holding the file (`crate::sink`). Each
//! message says its compression (`ArrowMsg.compression`,
//! which `re_log_encoding`'s decoder reads per message; the stream header's LZ4 is the
//! default its encoder writes, and its decoder does not decompress by it). The bytes are those
//! of the SDK's encoder (the same framing types, the manifest built by its
//! `RrdManifestBuilder`, fed at the end from a compact record of the chunks: [`Manifest`]) but
//! for that per-chunk choice, and `scripts/check_rrd.py` reads the files back with the Python
//! SDK.

use crate::ipc::IpcStream;
use crate::manifest::Manifest;
use re_protos::common::v1alpha1::Compression as ProtoCompression;
use re_protos::log_msg::v1alpha1::{ArrowMsg as ProtoArrowMsg, Encoding as ProtoEncoding};
use re_sdk::external::arrow::array::RecordBatch;
use re_sdk::external::arrow::ipc::writer::StreamWriter;
use re_sdk::external::re_log_encoding::external::lz4_flex;
use re_sdk::external::re_log_encoding::{
    CrateVersion, Encodable, EncodingOptions, MessageHeader, MessageKind, RRD_FOURCC, RrdFooter,
    StreamFooter, StreamHeader, ToTransport,
};
use re_sdk::external::re_log_types::{ArrowMsg, LogMsg, StoreId};
use std::collections::HashMap;
use std::io::Write;

/// Protobuf key of `ArrowMsg.payload` (field 5, length-delimited): the field written by
/// hand after the rest of the message (a decoder takes fields in any order).
const PAYLOAD_KEY: u8 = (5 << 3) | 2;

/// Chunks shorter than this (bytes of Arrow IPC) are always LZ4-compressed, as the SDK does:
/// too small for the choice to matter.
const ALWAYS_COMPRESS_BELOW: usize = 64 << 10;

/// A chunk is LZ4-compressed when LZ4 is expected to save at least this fraction of it.
/// Measured on handover24 (docs/notes/2026-12-02-rerun.md, 2026-12-04, session 42): LZ4
/// leaves float positions and the colour files as they are (ratio 1.004), shrinks depth to
/// ~0.51, label images and class ids to ~0.03. So the colour files and the unknown points'
/// positions go uncompressed and the file is as large as with LZ4 everywhere; a known
/// layer's chunk (positions and class ids, ~14 % saved) stays compressed: at 1/4 it too went
/// uncompressed, the file grew by 11 % and the CPU time did not measurably drop.
const MIN_SAVING: f64 = 0.125;

/// Bytes of each sample LZ4 compresses to estimate a buffer's ratio, and how many samples
/// (spread over the buffer) a buffer gets; buffers under one sample are compressed whole,
/// buffers under [`IGNORE_BELOW`] not at all (they count as incompressible).
const SAMPLE_BYTES: usize = 16 << 10;
const SAMPLES: usize = 3;
const IGNORE_BELOW: usize = 1 << 10;

/// Buffers kept from one chunk to the next by whoever encodes chunks (the file's own, and
/// each frame worker's: `crate::sink`), so that encoding allocates nothing once warm.
#[derive(Default)]
pub(crate) struct Scratch {
    /// The chunk's Arrow IPC stream (schema and batch), uncompressed.
    ipc: Vec<u8>,
    /// Its LZ4 block; as long as the longest bound needed so far.
    lz4: Vec<u8>,
}

/// A chunk encoded and ready to be written ([`encode_chunk`]): everything but its message
/// header, which needs the file's offset.
pub(crate) struct EncodedChunk<'a> {
    store_id: StoreId,
    /// The chunk, parsed as the SDK's encoder does (static flag, manifest).
    chunk_batch: re_sorbet::ChunkBatch,
    /// The message's protobuf fields, then the payload's key and length.
    fields: Vec<u8>,
    payload: Payload<'a>,
    uncompressed_size: u64,
}

/// A chunk's payload: its Arrow IPC stream as it is, or LZ4-compressed in a [`Scratch`].
enum Payload<'a> {
    Stream(IpcStream),
    Lz4(&'a [u8]),
}

impl Payload<'_> {
    fn len(&self) -> usize {
        match self {
            Payload::Stream(stream) => stream.len(),
            Payload::Lz4(bytes) => bytes.len(),
        }
    }
}

/// Whether a chunk may be LZ4-compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Lz4 {
    /// Where LZ4 is expected to save at least [`MIN_SAVING`] of it.
    WhereWorth,
    /// Never: written as it is. For data that LZ4 shrinks, but slowly for what it saves:
    /// 16-bit depth (~0.51 of its size, and the slowest to compress of a frame's chunks:
    /// without it `run --rerun` spent ~5 % less time, for a file ~6 % larger;
    /// docs/notes/2026-12-02-rerun.md, 2026-12-04b).
    Never,
}

/// Encodes a chunk (`ArrowMsg`) of `store_id` into `scratch`: the CPU work of writing it,
/// done by the caller, before the file's lock (see `crate::sink`). A chunk that LZ4 would
/// barely shrink (float positions, PNG/JPEG files), or not to be compressed (`lz4`), keeps
/// the batch's own buffers, written as they are; any other is gathered and LZ4-compressed.
pub(crate) fn encode_chunk<'a>(
    store_id: &StoreId,
    arrow_msg: &ArrowMsg,
    lz4: Lz4,
    scratch: &'a mut Scratch,
) -> Result<EncodedChunk<'a>, String> {
    let batch = &arrow_msg.batch;
    let chunk_batch = re_sorbet::ChunkBatch::try_from(batch).map_err(|e| e.to_string())?;
    let stream = IpcStream::new(batch).map_err(|e| e.to_string())?;
    let (compression, uncompressed_size, payload) = match stream {
        Some(stream) if lz4 == Lz4::Never || !worth_compressing(&stream) => (
            ProtoCompression::None,
            stream.len(),
            Payload::Stream(stream),
        ),
        stream => {
            encode_ipc(&mut scratch.ipc, batch, stream.as_ref())?;
            let n = compress(&scratch.ipc, &mut scratch.lz4)?;
            (
                ProtoCompression::Lz4,
                scratch.ipc.len(),
                Payload::Lz4(&scratch.lz4[..n]),
            )
        }
    };
    let uncompressed_size = uncompressed_size as u64;
    let proto = ProtoArrowMsg {
        store_id: Some(store_id.clone().into()),
        chunk_id: Some(arrow_msg.chunk_id.into()),
        compression: compression as i32,
        uncompressed_size,
        encoding: ProtoEncoding::ArrowIpc as i32,
        payload: Default::default(),
        is_static: Some(chunk_batch.is_static()),
    };
    let mut fields = Vec::new();
    proto.to_rrd_bytes(&mut fields).map_err(|e| e.to_string())?;
    fields.push(PAYLOAD_KEY);
    push_varint(&mut fields, payload.len() as u64);
    Ok(EncodedChunk {
        store_id: store_id.clone(),
        chunk_batch,
        fields,
        payload,
        uncompressed_size,
    })
}

/// The batch as an Arrow IPC stream into `ipc` (from `stream` where it has one).
fn encode_ipc(
    ipc: &mut Vec<u8>,
    batch: &RecordBatch,
    stream: Option<&IpcStream>,
) -> Result<(), String> {
    ipc.clear();
    match stream {
        Some(stream) => {
            // One copy of each buffer, into a buffer kept from chunk to chunk.
            ipc.reserve(stream.len());
            stream.write_to(ipc).map_err(|e| e.to_string())
        }
        None => {
            let mut writer =
                StreamWriter::try_new(&mut *ipc, batch.schema_ref()).map_err(|e| e.to_string())?;
            writer.write(batch).map_err(|e| e.to_string())?;
            writer.finish().map_err(|e| e.to_string())
        }
    }
}

/// `ipc` LZ4-compressed (block format, as the SDK) into `lz4`; its length.
fn compress(ipc: &[u8], lz4: &mut Vec<u8>) -> Result<usize, String> {
    let bound = lz4_flex::block::get_maximum_output_size(ipc.len());
    if lz4.len() < bound {
        lz4.resize(bound, 0);
    }
    lz4_flex::block::compress_into(ipc, lz4).map_err(|e| e.to_string())
}

/// Writes a `.rrd` stream to `W` (see the module documentation).
pub(crate) struct RrdEncoder<W: Write> {
    out: W,
    /// Bytes written so far.
    written: u64,
    /// Buffers for the chunks given whole to [`RrdEncoder::append`].
    scratch: Scratch,
    /// Message header and the protobuf fields before the payload.
    head: Vec<u8>,
    /// The footer's manifest, per recording, kept compact until the end ([`Manifest`]).
    manifests: HashMap<StoreId, Manifest>,
}

impl<W: Write> RrdEncoder<W> {
    /// Writes the stream header (this SDK's version, LZ4, protobuf) to `out`.
    pub(crate) fn new(version: CrateVersion, mut out: W) -> Result<Self, String> {
        let mut head = Vec::new();
        StreamHeader {
            fourcc: RRD_FOURCC,
            version: version.to_bytes(),
            options: EncodingOptions::PROTOBUF_COMPRESSED,
        }
        .to_rrd_bytes(&mut head)
        .map_err(|e| e.to_string())?;
        out.write_all(&head).map_err(|e| e.to_string())?;
        Ok(RrdEncoder {
            out,
            written: head.len() as u64,
            scratch: Scratch::default(),
            head,
            manifests: HashMap::new(),
        })
    }

    /// Encodes and writes one message (and adds a chunk to the footer's manifest).
    pub(crate) fn append(&mut self, msg: &LogMsg) -> Result<(), String> {
        let LogMsg::ArrowMsg(store_id, arrow_msg) = msg else {
            // Store info and blueprint activation: small, as the SDK encodes them.
            let transport = msg
                .to_transport(EncodingOptions::PROTOBUF_COMPRESSED.compression)
                .map_err(|e| e.to_string())?;
            self.head.clear();
            transport
                .to_rrd_bytes(&mut self.head)
                .map_err(|e| e.to_string())?;
            return self.write_head();
        };
        let mut scratch = std::mem::take(&mut self.scratch);
        let result = encode_chunk(store_id, arrow_msg, Lz4::WhereWorth, &mut scratch)
            .and_then(|chunk| self.write_chunk(&chunk));
        self.scratch = scratch;
        result
    }

    /// Writes a chunk encoded by [`encode_chunk`] (and adds it to the footer's manifest).
    pub(crate) fn write_chunk(&mut self, chunk: &EncodedChunk<'_>) -> Result<(), String> {
        let payload_len = chunk.payload.len();
        let len = (chunk.fields.len() + payload_len) as u64;
        self.head.clear();
        MessageHeader {
            kind: MessageKind::ArrowMsg,
            len,
        }
        .to_rrd_bytes(&mut self.head)
        .map_err(|e| e.to_string())?;
        self.head.extend_from_slice(&chunk.fields);
        let span = re_span::Span {
            start: self.written + MessageHeader::ENCODED_SIZE_BYTES as u64,
            len,
        };
        self.write_head()?;
        match &chunk.payload {
            Payload::Stream(stream) => stream.write_to(&mut self.out),
            Payload::Lz4(bytes) => self.out.write_all(bytes),
        }
        .map_err(|e| e.to_string())?;
        self.written += payload_len as u64;
        self.manifests
            .entry(chunk.store_id.clone())
            .or_default()
            .append(&chunk.chunk_batch, span, chunk.uncompressed_size)
    }

    fn write_head(&mut self) -> Result<(), String> {
        self.out.write_all(&self.head).map_err(|e| e.to_string())?;
        self.written += self.head.len() as u64;
        Ok(())
    }

    /// Flushes what the writer buffers.
    pub(crate) fn flush(&mut self) -> Result<(), String> {
        self.out.flush().map_err(|e| e.to_string())
    }

    /// Writes the end-of-stream marker, the RRD footer (the manifests) and the stream
    /// footer, as the SDK's `Encoder::finish`; gives back the writer.
    pub(crate) fn finish(mut self) -> Result<W, String> {
        let manifests = std::mem::take(&mut self.manifests)
            .into_iter()
            .map(|(id, m)| m.build(id.clone()).map(|m| (id, m)))
            .collect::<Result<HashMap<_, _>, _>>()?;
        let footer = RrdFooter { manifests }
            .to_transport(())
            .map_err(|e| e.to_string())?;
        let mut footer_bytes = Vec::new();
        footer
            .to_rrd_bytes(&mut footer_bytes)
            .map_err(|e| e.to_string())?;
        self.head.clear();
        MessageHeader {
            kind: MessageKind::End,
            len: footer_bytes.len() as u64,
        }
        .to_rrd_bytes(&mut self.head)
        .map_err(|e| e.to_string())?;
        self.write_head()?;
        let footer_offset = self.written;
        self.out
            .write_all(&footer_bytes)
            .map_err(|e| e.to_string())?;
        self.written += footer_bytes.len() as u64;
        self.head.clear();
        StreamFooter::from_rrd_footer_bytes(footer_offset, &footer_bytes)
            .to_rrd_bytes(&mut self.head)
            .map_err(|e| e.to_string())?;
        self.write_head()?;
        self.flush()?;
        Ok(self.out)
    }
}

/// Whether LZ4 is expected to save at least [`MIN_SAVING`] of `stream`, from a few samples
/// of each of its buffers.
fn worth_compressing(stream: &IpcStream) -> bool {
    let len = stream.len();
    if len < ALWAYS_COMPRESS_BELOW {
        return true;
    }
    let mut saved = 0.0;
    for buffer in stream.body() {
        if buffer.len() < IGNORE_BELOW {
            continue;
        }
        let samples: Vec<&[u8]> = if buffer.len() <= SAMPLES * SAMPLE_BYTES {
            vec![buffer]
        } else {
            let step = (buffer.len() - SAMPLE_BYTES) / (SAMPLES - 1);
            (0..SAMPLES)
                .map(|i| &buffer[i * step..i * step + SAMPLE_BYTES])
                .collect()
        };
        let raw: usize = samples.iter().map(|s| s.len()).sum();
        let packed: usize = samples
            .iter()
            .map(|s| lz4_flex::block::compress(s).len())
            .sum();
        saved += buffer.len() as f64 * (1.0 - (packed as f64 / raw as f64).min(1.0));
    }
    saved >= MIN_SAVING * len as f64
}

/// Appends `v` as a protobuf varint.
fn push_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_protos::log_msg::v1alpha1::log_msg::Msg;
    use re_sdk::ComponentBatch;
    use re_sdk::RecordingStreamBuilder;
    use re_sdk::external::re_log_encoding::{Decodable, Encoder, ToApplication};
    use re_sdk::log::{Chunk, RowId};
    use re_sdk::time::Timeline;
    use re_sdk_types::archetypes::{Points3D, Scalars};
    use re_sdk_types::components::{ClassId, Position3D};

    /// A few messages as a run logs them: store info, clouds (one of them unlabelled, one
    /// with its positions and class ids in rows of their own), scalars on three frames (rows
    /// the batcher joins into chunks), a timeline on some frames only, static data.
    fn messages() -> Vec<LogMsg> {
        let (rec, storage) = RecordingStreamBuilder::new("encoder_test")
            .memory()
            .expect("memory recording");
        rec.log_static("world", &Scalars::single(1.0))
            .expect("log static");
        for frame in 0..3_i64 {
            rec.set_time_sequence("frame", frame);
            if frame == 1 {
                rec.set_timestamp_nanos_since_epoch("time", 1_700_000_000_000_000_000_i64);
            } else {
                rec.disable_timeline("time");
            }
            // Two rows of one entity, each with one component: two chunks.
            rec.log(
                "world/split",
                &Points3D::update_fields().with_positions([[frame as f32, 0.0, 1.0]]),
            )
            .expect("log positions");
            rec.log(
                "world/split",
                &Points3D::update_fields().with_class_ids([frame as u16]),
            )
            .expect("log class ids");
            let n = 1000 + frame as usize * 77;
            let xyz = (0..n).map(|i| [i as f32, 0.5, -(i as f32)]);
            rec.log(
                "world/refined",
                &Points3D::new(xyz).with_class_ids((0..n).map(|i| (i % 8) as u16)),
            )
            .expect("log points");
            rec.log("scores/biou", &Scalars::single(0.25 * frame as f64))
                .expect("log scalar");
        }
        // A chunk of three rows in which each component misses a row (nulls), as a chunk
        // sent whole; the times out of order.
        let positions: Vec<Position3D> = vec![[1.0, 2.0, 3.0].into(); 4];
        let ids: Vec<ClassId> = vec![2.into(); 4];
        let mut sparse = Chunk::builder("world/sparse");
        for (frame, with_positions, with_ids) in
            [(5_i64, true, true), (2, true, false), (9, false, true)]
        {
            sparse = sparse.with_sparse_component_batches(
                RowId::new(),
                [(Timeline::new_sequence("frame"), frame)],
                [
                    (
                        Points3D::descriptor_positions(),
                        with_positions.then_some(&positions as &dyn ComponentBatch),
                    ),
                    (
                        Points3D::descriptor_class_ids(),
                        with_ids.then_some(&ids as &dyn ComponentBatch),
                    ),
                ],
            );
        }
        rec.send_chunk(sparse.build().expect("sparse chunk"));
        rec.flush_blocking().expect("flush");
        storage.take()
    }

    /// The stream's messages, decoded, and the bytes after the last one (end marker, RRD
    /// footer, stream footer).
    fn parse(stream: &[u8]) -> (Vec<Msg>, Vec<u8>) {
        let mut at = StreamHeader::ENCODED_SIZE_BYTES;
        let mut msgs = Vec::new();
        loop {
            let header =
                MessageHeader::from_rrd_bytes(&stream[at..at + MessageHeader::ENCODED_SIZE_BYTES])
                    .expect("message header");
            if header.kind == MessageKind::End {
                return (msgs, stream[at..].to_vec());
            }
            let end = at + MessageHeader::ENCODED_SIZE_BYTES + header.len as usize;
            let msg = Option::<Msg>::from_rrd_bytes(&stream[at..end])
                .expect("message")
                .expect("not the end");
            msgs.push(msg);
            at = end;
        }
    }

    /// The RRD footer of a stream's tail (end marker, footer, stream footer).
    fn footer(tail: &[u8]) -> RrdFooter {
        let header = MessageHeader::from_rrd_bytes(&tail[..MessageHeader::ENCODED_SIZE_BYTES])
            .expect("end marker");
        assert_eq!(header.kind, MessageKind::End);
        let at = MessageHeader::ENCODED_SIZE_BYTES;
        re_protos::log_msg::v1alpha1::RrdFooter::from_rrd_bytes(&tail[at..at + header.len as usize])
            .expect("footer")
            .to_application(())
            .expect("footer contents")
    }

    #[test]
    fn writes_what_the_sdks_encoder_writes() {
        let msgs = messages();
        assert!(
            msgs.iter()
                .filter(|m| matches!(m, LogMsg::ArrowMsg(..)))
                .count()
                >= 3,
            "the test logs several chunks"
        );
        let version = re_sdk::build_info().version;
        let mut sdk = Encoder::new_eager(version, EncodingOptions::PROTOBUF_COMPRESSED, Vec::new())
            .expect("SDK encoder");
        let mut ours = RrdEncoder::new(version, Vec::new()).expect("our encoder");
        for m in &msgs {
            sdk.append(m).expect("SDK append");
            ours.append(m).expect("our append");
        }
        sdk.finish().expect("SDK finish");
        let sdk = sdk.into_inner().expect("SDK bytes");
        let ours = ours.finish().expect("our bytes");
        assert_eq!(
            sdk[..StreamHeader::ENCODED_SIZE_BYTES],
            ours[..StreamHeader::ENCODED_SIZE_BYTES],
            "stream header"
        );
        // The payload field comes last in ours (prost writes fields by tag): the messages
        // are equal once decoded, and as long, so the footers' byte spans are the same.
        let (sdk_msgs, sdk_tail) = parse(&sdk);
        let (our_msgs, our_tail) = parse(&ours);
        assert_eq!(sdk_msgs.len(), msgs.len());
        assert!(sdk_msgs == our_msgs, "decoded messages differ");
        // The messages as long: the footers' byte spans are the same.
        assert_eq!(sdk.len() - sdk_tail.len(), ours.len() - our_tail.len());
        // The footer's bytes, and even their length, are not deterministic (two SDK
        // encodings of these messages differ: its schema's metadata maps are hash maps, and
        // their order moves the Arrow IPC's padding), so the footers are compared decoded.
        let (sdk_footer, our_footer) = (footer(&sdk_tail), footer(&our_tail));
        assert_eq!(sdk_footer.manifests.len(), our_footer.manifests.len());
        for (id, want) in &sdk_footer.manifests {
            let got = our_footer.manifests.get(id).expect("the same recordings");
            assert_eq!(got.store_id, want.store_id);
            // The schema's field order (and so its hash) comes from a hash map in the SDK.
            let fields = |m: &re_sdk::external::re_log_encoding::RawRrdManifest| {
                let mut f: Vec<_> = m.sorbet_schema.fields().iter().cloned().collect();
                f.sort_by(|a, b| a.name().cmp(b.name()));
                f
            };
            assert_eq!(fields(got), fields(want));
            assert_eq!(got.data, want.data, "manifest of {id:?}");
        }
    }

    /// Pseudo-random bits (xorshift64), for data LZ4 cannot shrink.
    fn noise(n: usize) -> Vec<f32> {
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                f32::from_bits((x as u32 & 0x3fff_ffff) | 0x3c00_0000)
            })
            .collect()
    }

    #[test]
    fn chunks_lz4_barely_shrinks_are_written_uncompressed_and_read_back_the_same() {
        let (rec, storage) = RecordingStreamBuilder::new("encoder_test")
            .memory()
            .expect("memory recording");
        rec.set_time_sequence("frame", 0);
        let n = 20_000;
        let xyz = noise(3 * n);
        let positions = || xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]);
        // Random positions: ~240 kB LZ4 cannot shrink; the same with constant class ids
        // (~40 kB LZ4 shrinks to nothing, 14 % of the chunk); and all zeros.
        rec.log("noise", &Points3D::new(positions())).expect("log");
        rec.log(
            "noise_with_ids",
            &Points3D::new(positions()).with_class_ids(vec![3_u16; n]),
        )
        .expect("log");
        rec.log("zeros", &Points3D::new(vec![[0.0_f32; 3]; n]))
            .expect("log");
        rec.flush_blocking().expect("flush");
        let msgs = storage.take();
        let mut ours = RrdEncoder::new(re_sdk::build_info().version, Vec::new()).expect("encoder");
        for m in &msgs {
            ours.append(m).expect("append");
        }
        let (decoded, _) = parse(&ours.finish().expect("bytes"));
        let mut compression = HashMap::new();
        for (original, decoded) in msgs.iter().zip(&decoded) {
            let (LogMsg::ArrowMsg(_, original), Msg::ArrowMsg(decoded)) = (original, decoded)
            else {
                continue;
            };
            let entity = re_sorbet::ChunkBatch::try_from(&original.batch)
                .expect("chunk")
                .entity_path()
                .to_string();
            compression.insert(entity, decoded.compression());
            let back = decoded.to_application(()).expect("decodes");
            assert!(back.batch == original.batch, "a chunk reads back as logged");
        }
        assert_eq!(compression["/noise"], ProtoCompression::None);
        assert_eq!(compression["/noise_with_ids"], ProtoCompression::Lz4);
        assert_eq!(compression["/zeros"], ProtoCompression::Lz4);
    }

    #[test]
    fn varints_are_protobufs() {
        for (v, want) in [
            (0_u64, vec![0_u8]),
            (1, vec![1]),
            (127, vec![0x7f]),
            (128, vec![0x80, 0x01]),
            (300, vec![0xac, 0x02]),
            (u64::from(u32::MAX), vec![0xff, 0xff, 0xff, 0xff, 0x0f]),
        ] {
            let mut out = Vec::new();
            push_varint(&mut out, v);
            assert_eq!(out, want, "{v}");
        }
    }
}
