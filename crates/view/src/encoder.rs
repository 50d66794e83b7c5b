//! [`RrdEncoder`]: the `.rrd` stream of `re_log_encoding` 0.36.3's `Encoder` (stream
//! header, LZ4-compressed Arrow IPC messages, end marker, RRD footer with its manifest),
//! written with buffers kept from one message to the next.
//!
//! The SDK's `Encoder::append` encodes each chunk into a new `Vec` grown by doubling, LZ4
//! compresses it into another new `Vec`, then copies the result into a scratch `Vec` before
//! writing it: on this project's 2-core VM the fresh pages of those buffers and the copies
//! were most of the writer thread's time (docs/notes/2026-12-02-rerun.md, 2026-12-04,
//! session 41). Here the IPC and LZ4 buffers live as long as the file, and a chunk's
//! payload goes from the LZ4 buffer straight to the file. The bytes are those of the SDK's
//! encoder (the same framing types, the manifest built by its `RrdManifestBuilder`), and
//! `scripts/check_rrd.py` reads the files back with the Python SDK.

use crate::ipc::IpcStream;
use re_protos::common::v1alpha1::Compression as ProtoCompression;
use re_protos::log_msg::v1alpha1::{ArrowMsg as ProtoArrowMsg, Encoding as ProtoEncoding};
use re_sdk::external::arrow::array::RecordBatch;
use re_sdk::external::arrow::ipc::writer::StreamWriter;
use re_sdk::external::re_log_encoding::external::lz4_flex;
use re_sdk::external::re_log_encoding::{
    CrateVersion, Encodable, EncodingOptions, MessageHeader, MessageKind, RRD_FOURCC, RrdFooter,
    RrdManifestBuilder, StreamFooter, StreamHeader, ToTransport,
};
use re_sdk::external::re_log_types::{LogMsg, StoreId};
use std::collections::HashMap;
use std::io::Write;

/// Protobuf key of `ArrowMsg.payload` (field 5, length-delimited): the field written by
/// hand after the rest of the message (a decoder takes fields in any order).
const PAYLOAD_KEY: u8 = (5 << 3) | 2;

/// Writes a `.rrd` stream to `W` (see the module documentation).
pub(crate) struct RrdEncoder<W: Write> {
    out: W,
    /// Bytes written so far.
    written: u64,
    /// The chunk's Arrow IPC stream (schema and batch), uncompressed.
    ipc: Vec<u8>,
    /// Its LZ4 block; as long as the longest bound needed so far.
    lz4: Vec<u8>,
    /// Message header and the protobuf fields before the payload.
    head: Vec<u8>,
    /// The footer's manifest, per recording.
    manifests: HashMap<StoreId, RrdManifestBuilder>,
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
            ipc: Vec::new(),
            lz4: Vec::new(),
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
        let batch = &arrow_msg.batch;
        // Parsed as the SDK's encoder does, for the static flag and the manifest.
        let chunk_batch = re_sorbet::ChunkBatch::try_from(batch).map_err(|e| e.to_string())?;
        let uncompressed_size = self.encode_ipc(batch)?;
        let payload_len = self.compress()?;
        let proto = ProtoArrowMsg {
            store_id: Some(store_id.clone().into()),
            chunk_id: Some(arrow_msg.chunk_id.into()),
            compression: ProtoCompression::Lz4 as i32,
            uncompressed_size,
            encoding: ProtoEncoding::ArrowIpc as i32,
            payload: Default::default(),
            is_static: Some(chunk_batch.is_static()),
        };
        let mut fields = Vec::new();
        proto.to_rrd_bytes(&mut fields).map_err(|e| e.to_string())?;
        let mut payload_prefix = vec![PAYLOAD_KEY];
        push_varint(&mut payload_prefix, payload_len as u64);
        let len = (fields.len() + payload_prefix.len() + payload_len) as u64;
        self.head.clear();
        MessageHeader {
            kind: MessageKind::ArrowMsg,
            len,
        }
        .to_rrd_bytes(&mut self.head)
        .map_err(|e| e.to_string())?;
        self.head.extend_from_slice(&fields);
        self.head.extend_from_slice(&payload_prefix);
        let span = re_span::Span {
            start: self.written + MessageHeader::ENCODED_SIZE_BYTES as u64,
            len,
        };
        self.write_head()?;
        self.out
            .write_all(&self.lz4[..payload_len])
            .map_err(|e| e.to_string())?;
        self.written += payload_len as u64;
        self.manifests
            .entry(store_id.clone())
            .or_default()
            .append(&chunk_batch, span, uncompressed_size)
            .map_err(|e| e.to_string())
    }

    /// The batch as an Arrow IPC stream into `ipc`; its length.
    fn encode_ipc(&mut self, batch: &RecordBatch) -> Result<u64, String> {
        self.ipc.clear();
        match IpcStream::new(batch).map_err(|e| e.to_string())? {
            Some(stream) => {
                // One copy of each buffer, into a buffer kept from chunk to chunk.
                self.ipc.reserve(stream.len());
                stream.write_to(&mut self.ipc).map_err(|e| e.to_string())?;
            }
            None => {
                let mut writer = StreamWriter::try_new(&mut self.ipc, batch.schema_ref())
                    .map_err(|e| e.to_string())?;
                writer.write(batch).map_err(|e| e.to_string())?;
                writer.finish().map_err(|e| e.to_string())?;
            }
        }
        Ok(self.ipc.len() as u64)
    }

    /// `ipc` LZ4-compressed (block format, as the SDK) into `lz4`; its length.
    fn compress(&mut self) -> Result<usize, String> {
        let bound = lz4_flex::block::get_maximum_output_size(self.ipc.len());
        if self.lz4.len() < bound {
            self.lz4.resize(bound, 0);
        }
        lz4_flex::block::compress_into(&self.ipc, &mut self.lz4).map_err(|e| e.to_string())
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
            .collect::<Result<HashMap<_, _>, _>>()
            .map_err(|e| e.to_string())?;
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
    use re_sdk::RecordingStreamBuilder;
    use re_sdk::external::re_log_encoding::{Decodable, Encoder, ToApplication};
    use re_sdk_types::archetypes::{Points3D, Scalars};

    /// A few messages as a run logs them: store info, clouds (one of them unlabelled),
    /// scalars on two frames, static data.
    fn messages() -> Vec<LogMsg> {
        let (rec, storage) = RecordingStreamBuilder::new("encoder_test")
            .memory()
            .expect("memory recording");
        rec.log_static("world", &Scalars::single(1.0))
            .expect("log static");
        for frame in 0..2_i64 {
            rec.set_time_sequence("frame", frame);
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
        assert_eq!(sdk.len(), ours.len());
        // The footer's bytes are not deterministic (two SDK encodings of these messages
        // differ: metadata maps), so the footers are compared decoded.
        assert_eq!(sdk_tail.len(), our_tail.len());
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
