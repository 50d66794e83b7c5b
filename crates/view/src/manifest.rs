//! [`Manifest`]: the RRD footer's manifest of one recording, kept compact while the file is
//! written and built by the SDK's `RrdManifestBuilder` when the file ends.
//!
//! Why: `re_log_encoding` 0.36.3's builder keeps its index dense from the start: every chunk
//! appends an entry to *every* (timeline, component) column seen so far (~25 bytes each, from
//! its source), so its memory grows with chunks × columns: `run --rerun` kept ~25-30 KB a
//! frame more live memory than the plain run, most of it this index (a counting allocator over
//! 1000 frames of one camera, docs/notes/2026-12-02-rerun.md, 2026-12-04, sessions 42 and 43).
//! Here a chunk keeps only what the builder reads from it: its id, entity, row count, byte
//! span, the time of each row per timeline, and per component its column (descriptor and Arrow
//! type, shared by all chunks) and which rows hold it: ~130-260 bytes a chunk (estimated from
//! the struct sizes). At the end each chunk is rebuilt as a skeleton (the same rows, times and
//! validity, every list empty) and appended to the SDK's builder, which makes the same
//! manifest as if it had seen the chunks themselves (unit test in `encoder.rs`).

use re_sdk::ComponentDescriptor;
use re_sdk::EntityPath;
use re_sdk::external::arrow::array::{Array, ArrayRef, ListArray, new_empty_array};
use re_sdk::external::arrow::buffer::{NullBuffer, OffsetBuffer, ScalarBuffer};
use re_sdk::external::arrow::datatypes::{DataType, FieldRef, Schema};
use re_sdk::external::re_log_encoding::{RawRrdManifest, RrdManifestBuilder};
use re_sdk::external::re_log_types::StoreId;
use re_sdk::log::{Chunk, ChunkComponents, ChunkId, TimeColumn};
use re_sdk::time::Timeline;
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// One chunk of the file, as the manifest needs it.
struct Entry {
    id: ChunkId,
    entity: EntityPath,
    span: re_span::Span<u64>,
    uncompressed_size: u64,
    rows: u32,
    /// Its timelines in [`Manifest::timelines`]: (timeline, start of its rows' times in
    /// [`Manifest::times`]).
    timelines: Range<u32>,
    /// Its components in [`Manifest::components`].
    components: Range<u32>,
}

/// The manifest of one recording's chunks (see the module documentation).
#[derive(Default)]
pub(crate) struct Manifest {
    entries: Vec<Entry>,
    /// Per entry and timeline: the timeline and where its `rows` times start in `times`.
    timelines: Vec<(Timeline, u32)>,
    times: Vec<i64>,
    /// Per entry and component: its column in `columns` and where its `rows` validity flags
    /// start in `valid` (`u32::MAX`: every row holds it).
    components: Vec<(u32, u32)>,
    valid: Vec<bool>,
    /// The distinct component columns: descriptor and list field.
    columns: Vec<(ComponentDescriptor, FieldRef)>,
    column_index: HashMap<(ComponentDescriptor, DataType), u32>,
    /// The recording's schema, from the chunks themselves (one entry per column): the
    /// skeletons' empty lists would mark every column "semantically empty".
    schema: re_sorbet::SchemaBuilder,
}

impl Manifest {
    /// Adds a chunk written at `span` (bytes after its message header) whose Arrow IPC is
    /// `uncompressed_size` bytes.
    pub(crate) fn append(
        &mut self,
        chunk_batch: &re_sorbet::ChunkBatch,
        span: re_span::Span<u64>,
        uncompressed_size: u64,
    ) -> Result<(), String> {
        self.schema.add_chunk(chunk_batch);
        let chunk = Chunk::from_chunk_batch(chunk_batch).map_err(|e| e.to_string())?;
        let rows = chunk.num_rows();
        let timelines_start = self.timelines.len() as u32;
        for column in chunk.timelines().values() {
            self.timelines
                .push((*column.timeline(), self.times.len() as u32));
            self.times.extend_from_slice(column.times_raw());
        }
        let components_start = self.components.len() as u32;
        for column in chunk.components().values() {
            let list = &column.list_array;
            let DataType::List(field) = list.data_type() else {
                return Err(format!(
                    "component {} of a chunk is not a list",
                    column.descriptor
                ));
            };
            let key = (column.descriptor.clone(), list.data_type().clone());
            let index = match self.column_index.get(&key) {
                Some(&i) => i,
                None => {
                    let i = self.columns.len() as u32;
                    self.columns
                        .push((column.descriptor.clone(), field.clone()));
                    self.column_index.insert(key, i);
                    i
                }
            };
            let valid = match list.nulls() {
                Some(nulls) if nulls.null_count() > 0 => {
                    let at = self.valid.len() as u32;
                    self.valid.extend(nulls.iter());
                    at
                }
                _ => u32::MAX,
            };
            self.components.push((index, valid));
        }
        self.entries.push(Entry {
            id: chunk.id(),
            entity: chunk.entity_path().clone(),
            span,
            uncompressed_size,
            rows: rows as u32,
            timelines: timelines_start..self.timelines.len() as u32,
            components: components_start..self.components.len() as u32,
        });
        Ok(())
    }

    /// The chunk of `entry` without its data: the same id, entity, rows, times and
    /// validity, every component's lists empty.
    fn skeleton(&self, entry: &Entry) -> Result<Chunk, String> {
        let rows = entry.rows as usize;
        let timelines = self.timelines
            [entry.timelines.start as usize..entry.timelines.end as usize]
            .iter()
            .map(|&(timeline, at)| {
                let times = self.times[at as usize..at as usize + rows].to_vec();
                (
                    *timeline.name(),
                    TimeColumn::new(None, timeline, ScalarBuffer::from(times)),
                )
            })
            .collect();
        let components: ChunkComponents = self.components
            [entry.components.start as usize..entry.components.end as usize]
            .iter()
            .map(|&(index, valid)| {
                let (descriptor, field) = &self.columns[index as usize];
                let nulls = (valid != u32::MAX).then(|| {
                    NullBuffer::from(self.valid[valid as usize..valid as usize + rows].to_vec())
                });
                let values: ArrayRef = new_empty_array(field.data_type());
                let list = ListArray::try_new(
                    Arc::clone(field),
                    OffsetBuffer::new_zeroed(rows),
                    values,
                    nulls,
                )
                .map_err(|e| e.to_string())?;
                Ok((descriptor.clone(), list))
            })
            .collect::<Result<Vec<_>, String>>()?
            .into_iter()
            .collect();
        // Rows out of time order are sorted by a new chunk: the id is set again.
        Chunk::from_auto_row_ids(entry.id, entry.entity.clone(), timelines, components)
            .map(|chunk| chunk.with_id(entry.id))
            .map_err(|e| e.to_string())
    }

    /// The manifest, as the SDK's builder makes it from the chunks.
    pub(crate) fn build(&self, store_id: StoreId) -> Result<RawRrdManifest, String> {
        let mut builder = RrdManifestBuilder::default();
        for entry in &self.entries {
            let batch = self
                .skeleton(entry)?
                .to_chunk_batch()
                .map_err(|e| e.to_string())?;
            builder
                .append(&batch, entry.span, entry.uncompressed_size)
                .map_err(|e| e.to_string())?;
        }
        let mut manifest = builder.build(store_id).map_err(|e| e.to_string())?;
        // The schema as the builder would have made it from the chunks themselves.
        manifest.sorbet_schema =
            Schema::new_with_metadata(self.schema.clone().build(), Default::default());
        manifest.sorbet_schema_sha256 =
            RawRrdManifest::compute_sorbet_schema_sha256(&manifest.sorbet_schema)
                .map_err(|e| e.to_string())?;
        Ok(manifest)
    }
}
