//! The resumable, sharded frame loop under `bodyseg run` and `bodyseg convert`.
//!
//! A batch is a sorted list of frames (jobs). Each process takes its shard of the list
//! (`--shard K/N`: every frame whose position modulo N is K), skips the frames an
//! earlier run finished, and processes the rest in parallel (rayon), each frame on its
//! own: one frame's data in memory per worker, whatever the recording's length.
//!
//! Completeness: every output file is written atomically (temporary + rename), and a
//! frame's record `OUT/frames/<frame>.json` is written last, listing the outputs with
//! their sizes and the hash of the configuration that made them. A frame is complete
//! when its record reads back, carries the same configuration hash, every listed output
//! exists with the listed size and every input file it read has the size and modification
//! time it had; anything else (no record: killed midway; another configuration; a file
//! deleted since; a recording generated again) is done again. A frame that fails is reported and
//! skipped, and the files it wrote in that attempt are removed, so no partial frame is
//! left behind.
//!
//! Durability: frame outputs and records are renamed into place without an fsync each
//! ([`bodyseg_io::Durability::Renamed`]; two fsyncs per file cost ~10% of the
//! throughput), and the batch syncs the output's file system once at its end. A killed
//! process loses nothing (the data is in the OS's cache); after an OS crash or power
//! loss a frame whose files did not reach the disk shows a missing or shorter file
//! (journaling file systems such as ext4 and XFS set a file's on-disk size only once its
//! data is written), so its record no longer matches and the frame is done again.

use crate::recording::check_relative_path;
use crate::stage::Stage;
use anyhow::{Context, Result, bail};
use bodyseg_eval::Report;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Folder of the per-frame records, inside the output folder.
pub(crate) const RECORDS_FOLDER: &str = "frames";

/// The part of a batch one process does: frames whose position in the sorted list, modulo
/// `count`, equals `index` (0-based). `0/1` is the whole batch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0..count`.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl Shard {
    /// The whole batch.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether the frame at `position` of the sorted list is this shard's.
    pub fn holds(self, position: usize) -> bool {
        position % self.count as usize == self.index as usize
    }

    /// How many of `len` frames are this shard's.
    pub fn share(self, len: usize) -> usize {
        (0..len).filter(|&i| self.holds(i)).count()
    }

    /// Suffix of this shard's report files: empty for the whole batch, else
    /// `.shard-K-of-N`.
    pub fn suffix(self) -> String {
        if self.count == 1 {
            String::new()
        } else {
            format!(".shard-{}-of-{}", self.index, self.count)
        }
    }
}

impl Default for Shard {
    fn default() -> Self {
        Shard::ALL
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// `K/N` with `0 <= K < N` (a Slurm array task id and the array size).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("shard must be K/N with 0 <= K < N (e.g. 3/8), got {s:?}");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = k.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// One file a frame wrote: its path relative to the output folder and its size.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputFile {
    /// Path relative to the output folder, `/`-separated.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
}

/// One file a frame read: its path, size and modification time (nanoseconds since the
/// Unix epoch; 0 where the file system has none).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    /// The path as given to the reader.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// Modification time, nanoseconds since the Unix epoch.
    pub modified_ns: u128,
}

impl InputFile {
    /// The fingerprint of `path` now; `None` when it cannot be inspected.
    pub fn of(path: &Path) -> Option<InputFile> {
        let m = std::fs::metadata(path).ok()?;
        let modified_ns = m
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        Some(InputFile {
            path: path.display().to_string(),
            bytes: m.len(),
            modified_ns,
        })
    }
}

/// What a finished frame left: `OUT/frames/<frame>.json`. Holds no times, so that an
/// interrupted and resumed batch writes the same records as an uninterrupted one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The frame's id (`000012`; `<recording>/000012` in a batch of recordings).
    pub frame: String,
    /// Hash of everything that decides the outputs (configuration, options); a record
    /// with another hash is out of date.
    pub config_hash: String,
    /// Points of the frame's cloud.
    pub points: usize,
    /// Points the projection left unknown.
    pub unknown: usize,
    /// Person boxes.
    pub people: usize,
    /// The files written, in writing order.
    pub outputs: Vec<OutputFile>,
    /// The files read, with size and modification time: a frame whose inputs changed
    /// since (a recording generated again) is done again.
    #[serde(default)]
    pub inputs: Vec<InputFile>,
    /// The frame's evaluation (a bodyseg-eval report in its JSON form) when the input has
    /// ground truth.
    pub scores: Option<FrameScores>,
}

/// A frame's evaluation report held as compact JSON text; in the record file it is the
/// same nested JSON object as ever. Why not a `serde_json::Value`: a run keeps every
/// frame's record until its end (the report merges them), and a `Value` tree (an enum per
/// number, a `String` per key, map nodes) took ~60 KB a frame of live memory against the
/// text's few KB (a counting allocator over 1000 frames, docs/notes/2026-12-02-rerun.md).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameScores(String);

impl FrameScores {
    /// The scores of `value` (kept as its compact JSON text).
    pub fn from_value(value: &serde_json::Value) -> FrameScores {
        FrameScores(value.to_string())
    }

    /// The report's JSON text.
    pub fn json(&self) -> &str {
        &self.0
    }
}

impl Serialize for FrameScores {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        // Written as a nested object (not a string), as the records always were.
        let value: serde_json::Value =
            serde_json::from_str(&self.0).map_err(serde::ser::Error::custom)?;
        value.serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for FrameScores {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        serde_json::Value::deserialize(deserializer).map(|value| FrameScores::from_value(&value))
    }
}

/// A frame that failed: its id and the error, one line.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameFailure {
    /// The frame's id.
    pub frame: String,
    /// What went wrong, naming the file.
    pub error: String,
}

/// Progress of a batch, handed to the caller's callback after each frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BatchProgress {
    /// Frames of this shard finished so far (processed, skipped or failed).
    pub finished: usize,
    /// Frames of this shard.
    pub total: usize,
    /// Of `finished`, those that failed.
    pub failed: usize,
    /// Of `finished`, those skipped as already complete.
    pub skipped: usize,
}

/// The frames' scores summed as the frames finish (see [`BatchOutcome::scores`]); the first
/// record whose scores cannot be read or added, as an error.
#[derive(Default)]
struct ScoreFold {
    reports: BTreeMap<String, Report>,
    error: Option<String>,
}

impl ScoreFold {
    /// Takes `record`'s scores out of it and adds them to its group's sum. Sums of counts:
    /// the order frames finish in does not change them.
    fn take(&mut self, record: &mut FrameRecord) {
        let Some(scores) = record.scores.take() else {
            return;
        };
        if self.error.is_some() {
            return;
        }
        let group = record.frame.rsplit_once('/').map_or("", |(group, _)| group);
        let added = Report::from_json(scores.json())
            .with_context(|| format!("frame {}: scores in its record", record.frame))
            .and_then(|frame| match self.reports.get(group) {
                None => Ok(frame),
                Some(sum) => Report::merge([sum, &frame])
                    .with_context(|| format!("merging the frames' scores: frame {}", record.frame)),
            });
        match added {
            Ok(sum) => {
                self.reports.insert(group.to_string(), sum);
            }
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }
}

/// What a batch did.
#[derive(Debug)]
pub struct BatchOutcome {
    /// Records of this shard's complete frames (processed now or skipped), in list order,
    /// without their scores: those are folded into [`BatchOutcome::scores`] as the frames
    /// finish, so that a long batch does not hold every frame's evaluation until its end.
    pub records: Vec<FrameRecord>,
    /// The frames' scores summed per group of frames: the part of a frame id before its
    /// last `/` (a recording of `convert`), `""` for a plain frame id. Groups without
    /// scores are absent.
    pub scores: BTreeMap<String, Report>,
    /// Frames processed now.
    pub processed: usize,
    /// Frames skipped as complete.
    pub skipped: usize,
    /// Frames that failed, in list order.
    pub failed: Vec<FrameFailure>,
    /// Per stage, the time summed over the processed frames (worker time, not wall time),
    /// in the order stages first appeared.
    pub stage_totals: Vec<(&'static str, Duration)>,
    /// Wall-clock time of the frame loop.
    pub elapsed: Duration,
}

impl BatchOutcome {
    /// Frames processed per second of the loop's wall-clock time.
    pub fn frames_per_second(&self) -> f64 {
        self.processed as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    /// One summary line per stage (total over the processed frames, and per frame), then
    /// the loop's: frames processed (per second), skipped, failed.
    pub fn stage_lines(&self) -> Vec<Stage> {
        let mut stages: Vec<Stage> = self
            .stage_totals
            .iter()
            .map(|(name, total)| {
                let per = total.as_secs_f64() * 1e3 / self.processed.max(1) as f64;
                Stage::new(
                    name,
                    *total,
                    format!("{per:.1} ms per frame (summed over workers)"),
                )
            })
            .collect();
        stages.push(Stage::new(
            "frames",
            self.elapsed,
            format!(
                "{} processed ({:.1} frames/s), {} skipped as complete, {} failed",
                self.processed,
                self.frames_per_second(),
                self.skipped,
                self.failed.len()
            ),
        ));
        stages
    }
}

/// Writes a frame's files into the output folder, remembering each one: the record lists
/// them, and a failed frame's are removed.
#[derive(Debug)]
pub struct FrameWriter {
    out: PathBuf,
    written: Vec<OutputFile>,
}

impl FrameWriter {
    /// A writer into the output folder `out` (the batch makes one per frame; benches and
    /// tests may too).
    pub fn new(out: &Path) -> FrameWriter {
        FrameWriter {
            out: out.to_path_buf(),
            written: Vec::new(),
        }
    }

    /// Writes the file `relative` (inside the output folder; parent folders created) with
    /// `write`, which must write it atomically (bodyseg-io's writers do), and records it.
    ///
    /// # Errors
    /// The folder cannot be created, `write` fails, or the file cannot be inspected.
    pub fn write(
        &mut self,
        relative: &str,
        write: impl FnOnce(&Path) -> Result<()>,
    ) -> Result<PathBuf> {
        check_relative_path(relative)?;
        let path = self.out.join(relative);
        if let Some(parent) = path.parent() {
            bodyseg_io::create_folder(parent)?;
        }
        write(&path)?;
        let bytes = std::fs::metadata(&path)
            .with_context(|| format!("{}: cannot read back its size", path.display()))?
            .len();
        self.written.push(OutputFile {
            path: relative.to_string(),
            bytes,
        });
        Ok(path)
    }

    /// The files written so far.
    pub fn outputs(&self) -> &[OutputFile] {
        &self.written
    }

    /// Removes every file written (a failed frame leaves nothing).
    pub(crate) fn remove_all(&self) {
        for f in &self.written {
            let _ = std::fs::remove_file(self.out.join(&f.path));
        }
    }
}

/// Where the record of `frame` goes.
pub(crate) fn record_path(out: &Path, frame: &str) -> PathBuf {
    out.join(RECORDS_FOLDER).join(format!("{frame}.json"))
}

/// The record of `frame` if the frame is complete under `config_hash` (see the module
/// documentation), else `None`.
pub(crate) fn complete_record(out: &Path, frame: &str, config_hash: &str) -> Option<FrameRecord> {
    let text = std::fs::read_to_string(record_path(out, frame)).ok()?;
    let record: FrameRecord = serde_json::from_str(&text).ok()?;
    if record.frame != frame || record.config_hash != config_hash {
        return None;
    }
    let intact = record.outputs.iter().all(|f| {
        std::fs::metadata(out.join(&f.path)).is_ok_and(|m| m.is_file() && m.len() == f.bytes)
    });
    let inputs_unchanged = record
        .inputs
        .iter()
        .all(|f| InputFile::of(Path::new(&f.path)).as_ref() == Some(f));
    (intact && inputs_unchanged).then_some(record)
}

/// Hash of a text (FNV-1a, 64 bits) as 16 hex digits: stable across runs and machines,
/// unlike std's `DefaultHasher`.
pub(crate) fn text_hash(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Removes the temporary files (`.bodyseg-*.tmp`) a killed run left in `out` and its
/// sub-folders. Only for a whole batch: with shards, another process may be writing
/// ([`run_batch`] calls it so).
fn remove_stale_temporaries(out: &Path) {
    let mut stack = vec![out.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            match e.file_type() {
                Ok(t) if t.is_dir() => stack.push(path),
                Ok(t) if t.is_file() && name.starts_with(".bodyseg-") && name.ends_with(".tmp") => {
                    let _ = std::fs::remove_file(&path);
                }
                _ => {}
            }
        }
    }
}

/// Locks the output folder of a batch for this process and shard
/// (`OUT/.bodyseg.lock`, `OUT/.bodyseg.shard-0-of-4.lock`): a second `run` or `convert`
/// of the same shard into the same folder is refused while the first runs (its frames
/// would clash), naming the first's pid. Shards of one batch share the folder. The lock
/// file goes when the returned guard is dropped.
///
/// # Errors
/// Another process holds the lock, or the file cannot be created.
pub(crate) fn lock_output(out: &Path, shard: Shard) -> Result<bodyseg_io::FolderLock> {
    bodyseg_io::create_folder(out)?;
    Ok(bodyseg_io::lock_folder(
        out,
        &format!(".bodyseg{}.lock", shard.suffix()),
    )?)
}

/// Runs `process` on one frame, turning a panic into the frame's error
/// (`internal error: <panic message>`), so that one frame's bug fails that frame only and
/// the batch goes on.
///
/// `AssertUnwindSafe` is sound here: what the frame function touches mutably is this
/// frame's own (`writer`, whose files the batch removes after a failure, and `stages`,
/// dropped with the failure); the shared state it reads (`job`, the processor) is behind
/// shared references, and what it locks (the segmenter, the buffer pool) is behind
/// mutexes, which a panic poisons (the segmenter's lock then fails later frames with a
/// message; a buffer taken from the pool is dropped, not returned).
fn process_caught<J>(
    process: &FrameFn<'_, J>,
    frame: BatchFrame<'_, J>,
    writer: &mut FrameWriter,
    stages: &mut Vec<Stage>,
) -> Result<FrameRecord> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        process(frame, writer, stages)
    })) {
        Ok(result) => result,
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_string());
            Err(anyhow::anyhow!("internal error: {message}"))
        }
    }
}

/// What [`run_batch`] calls per frame: the frame, a writer for its files, its stage
/// records; returns its record.
pub(crate) type FrameFn<'a, J> =
    dyn Fn(BatchFrame<'_, J>, &mut FrameWriter, &mut Vec<Stage>) -> Result<FrameRecord> + Sync + 'a;

/// The frame a batch hands its `process` function.
#[derive(Debug)]
pub(crate) struct BatchFrame<'a, J> {
    /// The frame's id.
    pub id: &'a str,
    /// The caller's job description.
    pub job: &'a J,
}

/// Runs `process` on this shard's frames of `jobs` (`(id, job)`, sorted by id, ids
/// unique) that are not complete yet (all of them with `redo`), in parallel, after
/// removing the temporaries a killed run left (whole batch only). `process`
/// writes its files through the [`FrameWriter`], pushes its stages, and returns the
/// record (the batch fills in `outputs`, then writes the record).
///
/// # Errors
/// Only for the batch as a whole: ids not unique. A frame's error is a [`FrameFailure`].
pub(crate) fn run_batch<J: Sync>(
    jobs: &[(String, J)],
    out: &Path,
    shard: Shard,
    config_hash: &str,
    redo: bool,
    progress: &(dyn Fn(BatchProgress) + Sync),
    process: &FrameFn<'_, J>,
) -> Result<BatchOutcome> {
    for w in jobs.windows(2) {
        if w[0].0 == w[1].0 {
            bail!("frame {} is listed twice", w[0].0);
        }
    }
    let mine: Vec<&(String, J)> = jobs
        .iter()
        .enumerate()
        .filter(|(i, _)| shard.holds(*i))
        .map(|(_, j)| j)
        .collect();
    if shard == Shard::ALL {
        remove_stale_temporaries(out);
    }
    let total = mine.len();
    let finished = AtomicUsize::new(0);
    let failed_count = AtomicUsize::new(0);
    let skipped_count = AtomicUsize::new(0);
    let totals: Mutex<Vec<(&'static str, Duration)>> = Mutex::new(Vec::new());
    let scores: Mutex<ScoreFold> = Mutex::new(ScoreFold::default());
    let fold = |record: &mut FrameRecord| {
        if let Ok(mut s) = scores.lock() {
            s.take(record);
        }
    };
    let start = Instant::now();

    enum Done {
        Processed(FrameRecord),
        Skipped(FrameRecord),
        Failed(FrameFailure),
    }
    let results: Vec<Done> = mine
        .par_iter()
        .with_max_len(1)
        .map(|(id, job)| {
            let done = if let Some(mut r) = (!redo)
                .then(|| complete_record(out, id, config_hash))
                .flatten()
            {
                skipped_count.fetch_add(1, Ordering::Relaxed);
                fold(&mut r);
                Done::Skipped(r)
            } else {
                let mut writer = FrameWriter::new(out);
                let mut stages = Vec::new();
                let result =
                    process_caught(process, BatchFrame { id, job }, &mut writer, &mut stages)
                        .and_then(|mut record| {
                            record.frame = id.clone();
                            record.config_hash = config_hash.to_string();
                            record.outputs = writer.outputs().to_vec();
                            let json = serde_json::to_string_pretty(&record)?;
                            check_relative_path(id)?;
                            let path = record_path(out, id);
                            if let Some(parent) = path.parent() {
                                bodyseg_io::create_folder(parent)?;
                            }
                            bodyseg_io::write_atomic_with(
                                &path,
                                bodyseg_io::Durability::Renamed,
                                |w| w.write_all(json.as_bytes()),
                            )?;
                            Ok(record)
                        });
                match result {
                    Ok(mut record) => {
                        fold(&mut record);
                        if let Ok(mut t) = totals.lock() {
                            for s in &stages {
                                match t.iter_mut().find(|(n, _)| *n == s.name) {
                                    Some((_, d)) => *d += s.elapsed,
                                    None => t.push((s.name, s.elapsed)),
                                }
                            }
                        }
                        Done::Processed(record)
                    }
                    Err(e) => {
                        writer.remove_all();
                        let _ = std::fs::remove_file(record_path(out, id));
                        failed_count.fetch_add(1, Ordering::Relaxed);
                        tracing::debug!(frame = %id, "frame failed: {e:#}");
                        Done::Failed(FrameFailure {
                            frame: id.clone(),
                            error: format!("{e:#}"),
                        })
                    }
                }
            };
            progress(BatchProgress {
                finished: finished.fetch_add(1, Ordering::Relaxed) + 1,
                total,
                failed: failed_count.load(Ordering::Relaxed),
                skipped: skipped_count.load(Ordering::Relaxed),
            });
            done
        })
        .collect();

    let scores = scores
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a frame worker panicked while adding its scores"))?;
    if let Some(e) = scores.error {
        bail!("{e}");
    }
    let mut outcome = BatchOutcome {
        records: Vec::new(),
        scores: scores.reports,
        processed: 0,
        skipped: 0,
        failed: Vec::new(),
        stage_totals: totals.into_inner().unwrap_or_default(),
        elapsed: start.elapsed(),
    };
    for r in results {
        match r {
            Done::Processed(record) => {
                outcome.processed += 1;
                outcome.records.push(record);
            }
            Done::Skipped(record) => {
                outcome.skipped += 1;
                outcome.records.push(record);
            }
            Done::Failed(f) => outcome.failed.push(f),
        }
    }
    // The frames' files were renamed into place unsynced: one sync for all of them.
    if outcome.processed > 0 {
        bodyseg_io::sync_file_system(out).context("syncing the outputs to disk")?;
    }
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_the_list_without_overlap() {
        let shards: Vec<Shard> = (0..3).map(|k| Shard { index: k, count: 3 }).collect();
        for i in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.holds(i)).count(), 1, "{i}");
        }
        assert!(Shard::ALL.holds(7));
        assert_eq!("2/3".parse::<Shard>(), Ok(shards[2]));
        for bad in ["3/3", "1", "a/2", "0/0", "-1/2"] {
            let e = bad.parse::<Shard>().expect_err(bad);
            assert!(e.contains("K/N"), "{e}");
        }
        assert_eq!(shards[1].suffix(), ".shard-1-of-3");
        assert_eq!(Shard::ALL.suffix(), "");
    }

    #[test]
    fn text_hash_is_stable_and_sensitive() {
        assert_eq!(text_hash(""), "cbf29ce484222325");
        assert_ne!(text_hash("a"), text_hash("b"));
    }

    /// Jobs `000`, `001`, ... each holding its index.
    fn numbered_jobs(n: u32) -> Vec<(String, u32)> {
        (0..n).map(|i| (format!("{i:03}"), i)).collect()
    }

    /// A frame function that writes the frame's output `a/<id>.txt` (which a failed frame
    /// must not leave behind), then fails the frame where `fail`, given the job, errs or
    /// panics; else it returns the frame's record.
    fn marking(
        fail: impl Fn(u32) -> Result<()> + Sync,
    ) -> impl Fn(BatchFrame<'_, u32>, &mut FrameWriter, &mut Vec<Stage>) -> Result<FrameRecord> + Sync
    {
        move |f, w, _| {
            w.write(&format!("a/{}.txt", f.id), |p| {
                Ok(bodyseg_io::write_bytes_atomic(p, b"x")?)
            })?;
            fail(*f.job)?;
            record_of(f.id)
        }
    }

    /// [`run_batch`] of every job (no shard, no redo, no progress) under `hash`.
    fn whole<J: Sync>(
        jobs: &[(String, J)],
        out: &Path,
        hash: &str,
        process: &FrameFn<'_, J>,
    ) -> BatchOutcome {
        run_batch(jobs, out, Shard::ALL, hash, false, &|_| {}, process).expect("batch")
    }

    /// A record's scores are written as the nested JSON object a `serde_json::Value` gives
    /// (the record files stay as they were) and read back equal.
    #[test]
    fn frame_scores_are_written_as_a_nested_object() {
        let value: serde_json::Value = serde_json::json!({
            "version": 1,
            "configurations": [{ "name": "M-R-N", "metrics": { "miou": 0.75, "biou": 0.5 } }],
        });
        let mut record = record_of("000001").expect("record");
        record.scores = Some(FrameScores::from_value(&value));
        let text = serde_json::to_string_pretty(&record).expect("serialise");
        let mut as_value =
            serde_json::to_value(record_of("000001").expect("record")).expect("value");
        as_value["scores"] = value;
        let written: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        assert_eq!(written, as_value, "scores nested, not a string");
        let back: FrameRecord = serde_json::from_str(&text).expect("read back");
        assert_eq!(back, record);
        assert!(serde_json::from_str::<FrameRecord>(&text.replace("0.75", "\"x")).is_err());
    }

    /// A frame's report: `n` points, labels 1 of which `hits` predicted right (else 2).
    fn frame_report(n: usize, hits: usize) -> Report {
        let gt = vec![bodyseg_core::Label::from_id_or_unknown(1); n];
        let pred: Vec<_> = (0..n)
            .map(|i| bodyseg_core::Label::from_id_or_unknown(if i < hits { 1 } else { 2 }))
            .collect();
        let mut r = Report::new();
        r.push(
            "M",
            bodyseg_eval::score_aligned(&pred, &gt).expect("scores"),
        )
        .expect("push");
        r
    }

    /// The batch sums the frames' scores per group (the id's part before its last `/`) as
    /// they finish and keeps the records without them; a resumed batch (frames skipped as
    /// complete, their scores read from their records) sums the same.
    #[test]
    fn scores_are_summed_per_group_as_frames_finish() {
        let dir = tempfile::tempdir().expect("temp dir");
        let jobs: Vec<(String, usize)> = ["a/000", "a/001", "b/000", "b/001", "b/002"]
            .iter()
            .enumerate()
            .map(|(i, id)| (id.to_string(), i))
            .collect();
        let per_frame = |i: usize| frame_report(10 + i, 3 + i);
        let process = |f: BatchFrame<'_, usize>, _: &mut FrameWriter, _: &mut Vec<Stage>| {
            let mut record = record_of(f.id)?;
            let value: serde_json::Value = serde_json::from_str(&per_frame(*f.job).to_json()?)?;
            record.scores = Some(FrameScores::from_value(&value));
            Ok(record)
        };
        let first = whole(&jobs, dir.path(), "h", &process);
        assert!(first.records.iter().all(|r| r.scores.is_none()));
        let want = |ids: &[usize]| {
            let reports: Vec<Report> = ids.iter().map(|&i| per_frame(i)).collect();
            Report::merge(&reports).expect("merge")
        };
        assert_eq!(first.scores.keys().collect::<Vec<_>>(), ["a", "b"]);
        assert_eq!(first.scores["a"], want(&[0, 1]));
        assert_eq!(first.scores["b"], want(&[2, 3, 4]));
        let resumed = whole(&jobs, dir.path(), "h", &process);
        assert_eq!(resumed.skipped, 5);
        assert_eq!(resumed.scores, first.scores);
        // A plain frame id is the group "".
        let plain: Vec<(String, usize)> = (0..2).map(|i| (format!("{i:03}"), i)).collect();
        let dir = tempfile::tempdir().expect("temp dir");
        let outcome = whole(&plain, dir.path(), "h", &process);
        assert_eq!(outcome.scores.keys().collect::<Vec<_>>(), [""]);
        assert_eq!(outcome.scores[""], want(&[0, 1]));
    }

    fn record_of(id: &str) -> Result<FrameRecord> {
        Ok(FrameRecord {
            frame: id.to_string(),
            config_hash: String::new(),
            points: 1,
            unknown: 0,
            people: 0,
            outputs: Vec::new(),
            inputs: Vec::new(),
            scores: None,
        })
    }

    #[test]
    fn complete_frames_are_skipped_failed_ones_leave_nothing() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path();
        let jobs = numbered_jobs(6);
        let process = marking(|job| match job {
            4 => bail!("frame {job:03} is bad"),
            _ => Ok(()),
        });
        let first = whole(&jobs, out, "h1", &process);
        assert_eq!((first.processed, first.skipped), (5, 0));
        assert_eq!(first.failed.len(), 1);
        assert!(first.failed[0].error.contains("004 is bad"));
        assert!(
            !out.join("a/004.txt").exists(),
            "a failed frame leaves nothing"
        );
        assert!(!record_path(out, "004").exists());

        let again = whole(&jobs, out, "h1", &process);
        assert_eq!((again.processed, again.skipped), (0, 5));
        assert_eq!(again.records, first.records);

        // A deleted output or another configuration makes a frame incomplete.
        std::fs::remove_file(out.join("a/002.txt")).expect("remove");
        let third = whole(&jobs, out, "h1", &process);
        assert_eq!((third.processed, third.skipped), (1, 4));
        let other = whole(&jobs, out, "h2", &process);
        assert_eq!((other.processed, other.skipped), (5, 0));

        // Shards split the work.
        let s = run_batch(
            &jobs,
            out,
            Shard { index: 1, count: 2 },
            "h3",
            false,
            &|_| {},
            &process,
        )
        .expect("batch");
        let ids: Vec<&str> = s.records.iter().map(|r| r.frame.as_str()).collect();
        assert_eq!(ids, ["001", "003", "005"]);
    }

    #[test]
    fn a_panicking_frame_fails_alone_and_leaves_nothing() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path();
        let jobs = numbered_jobs(4);
        let process = marking(|job| {
            if job == 2 {
                let cells: Vec<u32> = Vec::new();
                // A bug: an index out of bounds.
                bail!("cell {}", cells[job as usize]);
            }
            if job == 3 {
                panic!("frame {job:03} panicked");
            }
            Ok(())
        });
        let outcome = whole(&jobs, out, "h", &process);
        assert_eq!(outcome.processed, 2, "the batch goes on");
        let failed: Vec<(&str, &str)> = outcome
            .failed
            .iter()
            .map(|f| (f.frame.as_str(), f.error.as_str()))
            .collect();
        assert_eq!(failed.len(), 2);
        assert_eq!(failed[0].0, "002");
        assert!(
            failed[0]
                .1
                .starts_with("internal error: index out of bounds"),
            "{}",
            failed[0].1
        );
        assert_eq!(failed[1], ("003", "internal error: frame 003 panicked"));
        for id in ["002", "003"] {
            assert!(!out.join(format!("a/{id}.txt")).exists(), "{id}");
            assert!(!record_path(out, id).exists(), "{id}");
        }
        assert!(out.join("a/001.txt").exists());
    }

    #[test]
    fn a_frame_whose_input_changed_is_done_again() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path().join("out");
        let input = dir.path().join("in.txt");
        std::fs::write(&input, b"one").expect("write");
        let jobs = vec![("000".to_string(), ())];
        let process = |f: BatchFrame<'_, ()>, _: &mut FrameWriter, _: &mut Vec<Stage>| {
            let mut r = record_of(f.id)?;
            r.inputs.extend(InputFile::of(&input));
            Ok(r)
        };
        let run = || whole(&jobs, &out, "h", &process);
        assert_eq!(run().processed, 1);
        assert_eq!(run().skipped, 1);
        std::fs::write(&input, b"three").expect("rewrite");
        assert_eq!(run().processed, 1, "the input changed size");
    }
}
