//! [`IpcStream`]: one record batch as an Arrow IPC stream (schema message, the batch's
//! message, end-of-stream marker), byte for byte what arrow-ipc 58's `StreamWriter` writes
//! with its default options, but held as the list of the batch's own buffers.
//!
//! arrow-ipc's `StreamWriter::write` copies every buffer of the batch into a new `Vec` grown
//! by doubling, then copies that `Vec` into the stream: on this project's 2-core VM the copies,
//! the reallocations and their fresh pages were ~60 % of the `.rrd` writer thread's samples
//! (docs/notes/2026-12-02-rerun.md, 2026-12-04, session 42). Here the body's buffers are
//! reference-counted slices of the batch's arrays (offsets re-based and bits shifted where
//! arrow-ipc does so, which copies those only), so the stream's length is known before a
//! byte is written and the bytes are copied once, straight to where they go
//! ([`IpcStream::write_to`]). The traversal is arrow-ipc's `write_array_data` for the types
//! a Rerun chunk holds; a batch with another type (dictionaries, unions, views, run-end
//! encoding, nulls) is left to `StreamWriter` ([`IpcStream::new`] returns `None`). A unit
//! test compares the bytes with `StreamWriter`'s.

use re_sdk::external::arrow::array::{
    Array, ArrayData, BufferSpec, OffsetSizeTrait, RecordBatch, layout,
};
use re_sdk::external::arrow::buffer::Buffer;
use re_sdk::external::arrow::datatypes::{DataType, Field};
use re_sdk::external::arrow::error::ArrowError;
use re_sdk::external::arrow::ipc;
use re_sdk::external::arrow::ipc::writer::{
    DictionaryTracker, IpcDataGenerator, IpcWriteOptions, write_message,
};
use std::io::Write;

/// Alignment of the body's buffers and of the messages: `IpcWriteOptions::default()`'s.
const ALIGN: usize = 64;

/// Zeros for the padding after each buffer and message.
const PADDING: [u8; ALIGN] = [0; ALIGN];

/// The message prefix: continuation marker, then the metadata length (i32, little-endian).
const CONTINUATION: [u8; 4] = [0xff; 4];

/// One record batch as an Arrow IPC stream, its body not yet copied (see the module
/// documentation).
pub(crate) struct IpcStream {
    /// The schema message and the batch's message metadata, framed and padded.
    head: Vec<u8>,
    /// The body's buffers in order; each is followed by zeros up to a multiple of [`ALIGN`].
    body: Vec<Buffer>,
    /// The whole stream's length in bytes.
    len: usize,
}

/// What the traversal gathers: the batch's field nodes, buffer descriptors and buffers.
#[derive(Default)]
struct Gather {
    nodes: Vec<ipc::FieldNode>,
    buffers: Vec<ipc::Buffer>,
    body: Vec<Buffer>,
    /// Body bytes so far, padding included.
    offset: usize,
}

impl IpcStream {
    /// The stream of `batch`, or `None` when it holds a type this writer leaves to arrow-ipc.
    ///
    /// # Errors
    /// When arrow-ipc cannot encode the schema.
    pub(crate) fn new(batch: &RecordBatch) -> Result<Option<IpcStream>, ArrowError> {
        if !batch
            .schema_ref()
            .fields()
            .iter()
            .all(|f| supported(f.data_type()))
        {
            return Ok(None);
        }
        let options = IpcWriteOptions::default();
        let mut head = Vec::new();
        let schema = IpcDataGenerator::default().schema_to_bytes_with_dictionary_tracker(
            batch.schema_ref(),
            &mut DictionaryTracker::new(false),
            &options,
        );
        write_message(&mut head, schema, &options)?;
        let mut gather = Gather::default();
        for column in batch.columns() {
            gather.array(&column.to_data(), column.len(), column.null_count());
        }
        let metadata = record_batch_message(batch.num_rows(), &gather);
        // As `write_message`: continuation, length, metadata, padding to ALIGN.
        let framed = (metadata.len() + 8).div_ceil(ALIGN) * ALIGN;
        let prefix = i32::try_from(framed - 8)
            .map_err(|_| ArrowError::IpcError("batch metadata too large".into()))?;
        head.extend_from_slice(&CONTINUATION);
        head.extend_from_slice(&prefix.to_le_bytes());
        head.extend_from_slice(&metadata);
        head.extend_from_slice(&PADDING[..framed - 8 - metadata.len()]);
        // The end-of-stream marker (continuation, length 0) follows the body.
        let len = head.len() + gather.offset + 8;
        Ok(Some(IpcStream {
            head,
            body: gather.body,
            len,
        }))
    }

    /// The stream's length in bytes.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The body's buffers (without padding), in order.
    pub(crate) fn body(&self) -> impl Iterator<Item = &[u8]> {
        self.body.iter().map(|b| b.as_slice())
    }

    /// Writes the stream ([`IpcStream::len`] bytes) to `out`.
    ///
    /// # Errors
    /// The writer's.
    pub(crate) fn write_to<W: Write>(&self, out: &mut W) -> std::io::Result<()> {
        out.write_all(&self.head)?;
        for buffer in &self.body {
            out.write_all(buffer)?;
            out.write_all(&PADDING[..padding(buffer.len())])?;
        }
        out.write_all(&CONTINUATION)?;
        out.write_all(&0_i32.to_le_bytes())
    }
}

/// Zeros after `len` bytes up to a multiple of [`ALIGN`].
fn padding(len: usize) -> usize {
    len.next_multiple_of(ALIGN) - len
}

/// Whether [`Gather::array`] writes `data_type` as arrow-ipc does (checked by the tests).
fn supported(data_type: &DataType) -> bool {
    match data_type {
        DataType::Boolean
        | DataType::Binary
        | DataType::Utf8
        | DataType::LargeBinary
        | DataType::LargeUtf8
        | DataType::FixedSizeBinary(_) => true,
        DataType::List(f)
        | DataType::LargeList(f)
        | DataType::Map(f, _)
        | DataType::FixedSizeList(f, _) => supported(f.data_type()),
        DataType::Struct(fields) => fields
            .iter()
            .all(|f: &std::sync::Arc<Field>| supported(f.data_type())),
        t => t.is_numeric() || t.is_temporal(),
    }
}

impl Gather {
    /// One array (and its children) as arrow-ipc's `write_array_data` with metadata V5, no
    /// compression, for the types [`supported`] accepts.
    fn array(&mut self, data: &ArrayData, num_rows: usize, null_count: usize) {
        self.nodes
            .push(ipc::FieldNode::new(num_rows as i64, null_count as i64));
        // Every supported type has a validity buffer, empty when nothing is null.
        let nulls = match data.nulls() {
            Some(nulls) if null_count > 0 => nulls.inner().sliced(),
            _ => Buffer::from_vec(Vec::<u8>::new()),
        };
        self.buffer(nulls);
        let data_type = data.data_type();
        match data_type {
            DataType::Binary | DataType::Utf8 => {
                let (offsets, values) = byte_array_buffers::<i32>(data);
                self.buffer(offsets);
                self.buffer(values);
            }
            DataType::LargeBinary | DataType::LargeUtf8 => {
                let (offsets, values) = byte_array_buffers::<i64>(data);
                self.buffer(offsets);
                self.buffer(values);
            }
            DataType::Boolean => {
                self.buffer(data.buffers()[0].bit_slice(data.offset(), data.len()));
            }
            DataType::List(_) | DataType::Map(_, _) | DataType::LargeList(_) => {
                let (offsets, child) = if matches!(data_type, DataType::LargeList(_)) {
                    list_buffers::<i64>(data)
                } else {
                    list_buffers::<i32>(data)
                };
                self.buffer(offsets);
                self.array(&child, child.len(), child.null_count());
                return;
            }
            DataType::FixedSizeList(_, size) => {
                let size = *size as usize;
                let child = data.child_data()[0].slice(data.offset() * size, data.len() * size);
                self.array(&child, child.len(), child.null_count());
                return;
            }
            DataType::Struct(_) => {
                for buffer in data.buffers() {
                    self.buffer(buffer.clone());
                }
            }
            // Numeric, temporal, fixed-size binary: the values, cut to the array's slice.
            _ => self.buffer(values_buffer(data)),
        }
        for child in data.child_data() {
            self.array(child, child.len(), child.null_count());
        }
    }

    /// Appends a body buffer and its descriptor (offset, length; padded to [`ALIGN`]).
    fn buffer(&mut self, buffer: Buffer) {
        let len = buffer.len();
        self.buffers
            .push(ipc::Buffer::new(self.offset as i64, len as i64));
        self.offset += len + padding(len);
        self.body.push(buffer);
    }
}

/// The `RecordBatch` message's flatbuffer, as arrow-ipc's `record_batch_to_bytes` builds it
/// (the same builders in the same order, so the same bytes).
fn record_batch_message(num_rows: usize, gather: &Gather) -> Vec<u8> {
    let mut fbb = flatbuffers::FlatBufferBuilder::new();
    let buffers = fbb.create_vector(&gather.buffers);
    let nodes = fbb.create_vector(&gather.nodes);
    let batch = {
        let mut b = ipc::RecordBatchBuilder::new(&mut fbb);
        b.add_length(num_rows as i64);
        b.add_nodes(nodes);
        b.add_buffers(buffers);
        b.finish().as_union_value()
    };
    let mut message = ipc::MessageBuilder::new(&mut fbb);
    message.add_version(ipc::MetadataVersion::V5);
    message.add_header_type(ipc::MessageHeader::RecordBatch);
    message.add_bodyLength(gather.offset as i64);
    message.add_header(batch);
    let root = message.finish();
    fbb.finish(root, None);
    fbb.finished_data().to_vec()
}

/// The values buffer of a fixed-width array, cut to its slice (arrow-ipc's
/// `get_or_truncate_buffer`).
fn values_buffer(data: &ArrayData) -> Buffer {
    let buffer = &data.buffers()[0];
    let width = match layout(data.data_type()).buffers.first() {
        Some(BufferSpec::FixedWidth { byte_width, .. }) => *byte_width,
        _ => 0,
    };
    let min_length = data.len() * width;
    if data.offset() != 0 || min_length < buffer.len() {
        let start = data.offset() * width;
        buffer.slice_with_length(start, min_length.min(buffer.len() - start))
    } else {
        buffer.clone()
    }
}

/// Offsets re-based to start at 0 (a copy only when they do not), with the range of the
/// values they cover (arrow-ipc's `reencode_offsets`).
fn rebased_offsets<O: OffsetSizeTrait>(data: &ArrayData) -> (Buffer, usize, usize) {
    let offsets = &data.buffers()[0];
    let all: &[O] = offsets.typed_data::<O>();
    let these = &all[data.offset()..data.offset() + data.len() + 1];
    let (start, end) = (these[0].as_usize(), these[data.len()].as_usize());
    let rebased = if start == 0 {
        let size = std::mem::size_of::<O>();
        offsets.slice_with_length(data.offset() * size, (data.len() + 1) * size)
    } else {
        these.iter().map(|o| *o - these[0]).collect()
    };
    (rebased, start, end - start)
}

/// Offsets and values of a (large) binary or string array (arrow-ipc's
/// `get_byte_array_buffers`).
fn byte_array_buffers<O: OffsetSizeTrait>(data: &ArrayData) -> (Buffer, Buffer) {
    if data.is_empty() {
        return (
            Buffer::from_vec(vec![O::usize_as(0)]),
            Buffer::from_vec(Vec::<u8>::new()),
        );
    }
    let (offsets, start, len) = rebased_offsets::<O>(data);
    (offsets, data.buffers()[1].slice_with_length(start, len))
}

/// Offsets and sliced child of a (large) list or map array (arrow-ipc's
/// `get_list_array_buffers`).
fn list_buffers<O: OffsetSizeTrait>(data: &ArrayData) -> (Buffer, ArrayData) {
    if data.is_empty() {
        return (
            Buffer::from_vec(vec![O::usize_as(0)]),
            data.child_data()[0].slice(0, 0),
        );
    }
    let (offsets, start, len) = rebased_offsets::<O>(data);
    (offsets, data.child_data()[0].slice(start, len))
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_sdk::external::arrow::array::{
        ArrayRef, BinaryArray, BooleanArray, FixedSizeBinaryArray, FixedSizeListArray,
        Float32Array, Int64Array, LargeStringArray, ListArray, StringArray, StructArray,
        TimestampNanosecondArray, UInt8Array, UInt16Array,
    };
    use re_sdk::external::arrow::datatypes::{Field, Fields, Int32Type, Schema};
    use re_sdk::external::arrow::ipc::writer::StreamWriter;
    use std::sync::Arc;

    /// What arrow-ipc's `StreamWriter` writes for `batch`.
    fn arrow_stream(batch: &RecordBatch) -> Vec<u8> {
        let mut out = Vec::new();
        let mut w = StreamWriter::try_new(&mut out, batch.schema_ref()).expect("writer");
        w.write(batch).expect("write");
        w.finish().expect("finish");
        drop(w);
        out
    }

    fn ours(batch: &RecordBatch) -> Vec<u8> {
        let stream = IpcStream::new(batch)
            .expect("encode")
            .expect("supported types");
        let mut out = Vec::new();
        stream.write_to(&mut out).expect("write");
        assert_eq!(out.len(), stream.len(), "announced length");
        out
    }

    /// Columns of every supported kind, with nulls, several rows.
    fn columns(n: usize) -> Vec<(&'static str, ArrayRef)> {
        let xyz = Float32Array::from_iter_values((0..3 * n).map(|i| i as f32 * 0.25));
        let positions = FixedSizeListArray::new(
            Arc::new(Field::new("item", DataType::Float32, false)),
            3,
            Arc::new(xyz),
            None,
        );
        let ids = UInt16Array::from_iter((0..n).map(|i| (i % 7 != 3).then_some(i as u16 % 9)));
        let id_lists = ListArray::from_iter_primitive::<Int32Type, _, _>(
            (0..n).map(|i| (i % 5 != 1).then(|| (0..i % 4).map(|j| Some(j as i32)))),
        );
        let bytes = BinaryArray::from_iter((0..n).map(|i| (i % 3 != 0).then(|| vec![i as u8; i])));
        let names = StringArray::from_iter((0..n).map(|i| (i % 4 != 2).then(|| format!("n{i}"))));
        let large = LargeStringArray::from_iter_values((0..n).map(|i| "x".repeat(i % 6)));
        let flags = BooleanArray::from_iter((0..n).map(|i| (i % 6 != 5).then_some(i % 3 == 0)));
        let row_ids = FixedSizeBinaryArray::new(
            16,
            Buffer::from_vec((0..16 * n).map(|i| (i / 16) as u8).collect::<Vec<_>>()),
            None,
        );
        let times = Int64Array::from_iter_values((0..n as i64).map(|i| i * 1000));
        let stamps = TimestampNanosecondArray::from_iter_values((0..n as i64).map(|i| i * 7));
        let format = StructArray::new(
            Fields::from(vec![
                Field::new("w", DataType::UInt16, true),
                Field::new("kind", DataType::Utf8, true),
            ]),
            vec![
                Arc::new(UInt16Array::from_iter_values((0..n).map(|i| i as u16))) as ArrayRef,
                Arc::new(StringArray::from_iter_values(
                    (0..n).map(|i| format!("k{i}")),
                )),
            ],
            Some((0..n).map(|i| i % 8 != 7).collect()),
        );
        let pixels = ListArray::new(
            Arc::new(Field::new("item", DataType::UInt8, false)),
            re_sdk::external::arrow::buffer::OffsetBuffer::from_lengths((0..n).map(|i| i * 3)),
            Arc::new(UInt8Array::from_iter_values(
                (0..(0..n).map(|i| i * 3).sum::<usize>()).map(|i| i as u8),
            )),
            None,
        );
        vec![
            ("positions", Arc::new(positions) as ArrayRef),
            ("ids", Arc::new(ids)),
            ("id_lists", Arc::new(id_lists)),
            ("bytes", Arc::new(bytes)),
            ("names", Arc::new(names)),
            ("large", Arc::new(large)),
            ("flags", Arc::new(flags)),
            ("row_ids", Arc::new(row_ids)),
            ("times", Arc::new(times)),
            ("stamps", Arc::new(stamps)),
            ("format", Arc::new(format)),
            ("pixels", Arc::new(pixels)),
        ]
    }

    fn batch(columns: Vec<(&'static str, ArrayRef)>) -> RecordBatch {
        let schema = Schema::new(
            columns
                .iter()
                .map(|(name, a)| Field::new(*name, a.data_type().clone(), true))
                .collect::<Vec<_>>(),
        );
        RecordBatch::try_new(
            Arc::new(schema),
            columns.into_iter().map(|(_, a)| a).collect(),
        )
        .expect("batch")
    }

    #[test]
    fn writes_what_arrow_ipc_writes_for_every_supported_type() {
        for n in [0, 1, 2, 9, 70] {
            let b = batch(columns(n));
            assert_eq!(ours(&b), arrow_stream(&b), "{n} rows");
        }
    }

    #[test]
    fn writes_what_arrow_ipc_writes_for_sliced_arrays() {
        // Slices that start mid-buffer and mid-byte (validity and booleans at bit offsets),
        // list offsets that do not start at 0.
        let full = batch(columns(70));
        for (offset, len) in [(0, 69), (1, 0), (3, 17), (13, 50), (69, 1)] {
            let b = full.slice(offset, len);
            assert_eq!(ours(&b), arrow_stream(&b), "rows {offset}..+{len}");
        }
        // A column sliced on its own (a shared positions array, as `order.rs` makes).
        let (name, positions) = columns(40).swap_remove(0);
        let b = batch(vec![(name, positions.slice(5, 30))]);
        assert_eq!(ours(&b), arrow_stream(&b), "sliced column");
    }

    #[test]
    fn other_types_are_left_to_arrow_ipc() {
        let dict = re_sdk::external::arrow::array::DictionaryArray::<Int32Type>::from_iter([
            "a", "b", "a",
        ]);
        assert!(
            IpcStream::new(&batch(vec![("d", Arc::new(dict) as ArrayRef)]))
                .expect("encode")
                .is_none()
        );
    }
}
