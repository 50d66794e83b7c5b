//! [`SmallRows`]: a frame's small rows (person boxes, scores), gathered over many frames
//! into one chunk per entity before they are written.
//!
//! A frame has ~46 such rows (45 scores with 5 configurations, the boxes), a few bytes
//! each. Logged through the SDK, each row woke the SDK's batcher thread: ~90 context
//! switches a frame (about half of them involuntary: threads preempted on a 2-core
//! machine) and the SDK's per-row work, for rows the batcher then joined anyway
//! (docs/notes/2026-12-02-rerun.md, 2026-12-04c). Here the frame worker adds its rows under
//! one short lock; an entity's rows become a chunk once [`ROWS_PER_CHUNK`] of them are
//! pending (or when the file ends), made and written by the worker that added the last
//! row. Memory stays small and bounded: at most `ROWS_PER_CHUNK - 1` rows an entity.

use re_sdk::log::{Chunk, RowId};
use re_sdk::{SerializedComponentBatch, TimePoint};
use std::collections::HashMap;
use std::sync::Mutex;

/// Rows of one entity per chunk: a 500-frame run's 46 small entities make ~200 chunks
/// (each also an entry of the footer's index), and a chunk of scores is a few KB.
pub(crate) const ROWS_PER_CHUNK: usize = 128;

/// One row: an archetype's components at one frame's time.
pub(crate) struct Row {
    /// The frame's index on the `frame` timeline: the chunk's rows are sorted by it.
    pub(crate) frame: i64,
    pub(crate) time: TimePoint,
    pub(crate) components: Vec<SerializedComponentBatch>,
}

/// Rows of one chunk: the entity, then its rows in any order.
pub(crate) type Batch = (String, Vec<Row>);

/// What pending rows are kept by: the entity and the names of the rows' timelines.
type Key = (String, Vec<String>);

/// The pending rows of each entity (see the module documentation). Rows with different
/// timelines (frames with and without a time stamp) are pending apart: a chunk's time
/// columns cover all its rows.
pub(crate) struct SmallRows {
    pending: Mutex<HashMap<Key, Vec<Row>>>,
    rows_per_chunk: usize,
}

impl SmallRows {
    pub(crate) fn new(rows_per_chunk: usize) -> SmallRows {
        SmallRows {
            pending: Mutex::new(HashMap::new()),
            rows_per_chunk: rows_per_chunk.max(1),
        }
    }

    /// Adds a frame's rows (entity, row); returns the entities' rows that are now a chunk's
    /// worth, taken out, for the caller to write.
    pub(crate) fn add(&self, rows: impl IntoIterator<Item = (String, Row)>) -> Vec<Batch> {
        let mut full = Vec::new();
        let mut pending = self.pending.lock().unwrap_or_else(|e| e.into_inner());
        for (entity, row) in rows {
            let timelines = row.time.timeline_names().map(|t| t.to_string()).collect();
            let rows = pending.entry((entity.clone(), timelines)).or_default();
            rows.push(row);
            if rows.len() >= self.rows_per_chunk {
                full.push((entity, std::mem::take(rows)));
            }
        }
        pending.retain(|_, rows| !rows.is_empty());
        full
    }

    /// All pending rows, taken out (the file ends).
    pub(crate) fn take_all(&self) -> Vec<Batch> {
        let mut pending = self.pending.lock().unwrap_or_else(|e| e.into_inner());
        let mut all: Vec<Batch> = pending
            .drain()
            .map(|((entity, _), rows)| (entity, rows))
            .collect();
        all.sort_by(|a, b| a.0.cmp(&b.0));
        all
    }
}

/// The chunk of an entity's rows, sorted by frame (then as added). Their row ids are
/// made here, in that order: a chunk's rows must be sorted by row id (the viewer's store
/// refuses a chunk that is not), and so its `frame` column is sorted too.
///
/// # Errors
/// The SDK's, when the rows do not make a valid chunk (components of different types).
pub(crate) fn chunk(entity: &str, mut rows: Vec<Row>) -> Result<Chunk, String> {
    rows.sort_by_key(|r| r.frame);
    rows.into_iter()
        .fold(Chunk::builder(entity), |builder, row| {
            builder.with_serialized_batches(RowId::new(), row.time, row.components)
        })
        .build()
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_sdk::AsComponents;
    use re_sdk::time::{TimeCell, TimelineName};
    use re_sdk_types::archetypes::Scalars;
    use std::collections::BTreeSet;

    /// A row of `value` at `frame` (and at a time stamp when `stamped`).
    fn row(frame: i64, stamped: bool, value: f64) -> Row {
        let mut time = TimePoint::default();
        time.insert_cell(TimelineName::from("frame"), TimeCell::from_sequence(frame));
        if stamped {
            time.insert_cell(
                TimelineName::from("time"),
                TimeCell::from_timestamp_nanos_since_epoch(1_000 + frame),
            );
        }
        Row {
            frame,
            time,
            components: Scalars::single(value).as_serialized_batches(),
        }
    }

    /// (entity, frame) of every row of the batches.
    fn keys(batches: &[Batch]) -> Vec<(String, i64)> {
        batches
            .iter()
            .flat_map(|(e, rows)| rows.iter().map(move |r| (e.clone(), r.frame)))
            .collect()
    }

    #[test]
    fn an_entity_becomes_a_chunk_when_it_has_a_chunks_worth_of_rows() {
        let rows = SmallRows::new(3);
        let frame = |f: i64| {
            [
                ("a".to_string(), row(f, false, 1.0)),
                ("b".to_string(), row(f, false, 2.0)),
            ]
        };
        assert!(rows.add(frame(0)).is_empty());
        assert!(rows.add(frame(1)).is_empty());
        let full = rows.add(frame(2));
        assert_eq!(
            keys(&full),
            [
                ("a".into(), 0),
                ("a".into(), 1),
                ("a".into(), 2),
                ("b".into(), 0),
                ("b".into(), 1),
                ("b".into(), 2)
            ]
        );
        // Taken out: nothing of them pending any more.
        assert!(rows.add(frame(3)).is_empty());
        assert_eq!(keys(&rows.take_all()), [("a".into(), 3), ("b".into(), 3)]);
        assert!(rows.take_all().is_empty());
    }

    #[test]
    fn rows_with_other_timelines_are_pending_apart() {
        let rows = SmallRows::new(2);
        assert!(rows.add([("a".to_string(), row(0, true, 1.0))]).is_empty());
        // Frame 1 has no time stamp: not in the chunk of frame 0's timelines.
        assert!(rows.add([("a".to_string(), row(1, false, 1.0))]).is_empty());
        let full = rows.add([("a".to_string(), row(2, true, 1.0))]);
        assert_eq!(keys(&full), [("a".into(), 0), ("a".into(), 2)]);
        let (_, full) = full.into_iter().next().expect("one batch");
        let chunk = chunk("a", full).expect("a chunk");
        assert_eq!(chunk.num_rows(), 2);
        assert_eq!(chunk.timelines().len(), 2);
        assert_eq!(keys(&rows.take_all()), [("a".into(), 1)]);
    }

    #[test]
    fn a_chunks_rows_are_sorted_by_frame_and_by_row_id() {
        let frames = [5_i64, 2, 9, 0, 7];
        let rows: Vec<Row> = frames.iter().map(|&f| row(f, false, f as f64)).collect();
        let chunk = chunk("scores/x", rows).expect("a chunk");
        assert_eq!(chunk.num_rows(), frames.len());
        // The viewer's store refuses a chunk whose row ids are not sorted.
        assert!(chunk.is_row_ids_sorted_uncached());
        let column = &chunk.timelines()[&TimelineName::from("frame")];
        assert!(column.is_sorted());
        let column = column.times_raw().to_vec();
        assert_eq!(column, [0, 2, 5, 7, 9]);
    }

    #[test]
    fn rows_of_many_threads_are_each_written_once() {
        let rows = SmallRows::new(16);
        let written = std::sync::Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for t in 0..4_i64 {
                let (rows, written) = (&rows, &written);
                s.spawn(move || {
                    for f in 0..50 {
                        let frame = t * 50 + f;
                        let full = rows
                            .add(["a", "b", "c"].map(|e| (e.to_string(), row(frame, false, 0.5))));
                        written.lock().expect("lock").extend(keys(&full));
                    }
                });
            }
        });
        let mut all = written.into_inner().expect("lock");
        // Each entity had 200 rows: 12 chunks of 16 written by the threads, 8 rows left.
        assert_eq!(all.len(), 3 * 12 * 16);
        let rest = rows.take_all();
        assert!(rest.iter().all(|(_, r)| r.len() == 8));
        all.extend(keys(&rest));
        let unique: BTreeSet<_> = all.iter().cloned().collect();
        assert_eq!(all.len(), 600);
        assert_eq!(unique.len(), 600);
    }
}
