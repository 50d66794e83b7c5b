//! `bodyseg import ros2`: a ROS 2 bag (an `.mcap` file, or a rosbag2 folder with
//! `metadata.yaml` and MCAP files) into a recording (FORMATS.md), through
//! [`RecordingWriter`].
//!
//! Two streamed passes over the bag (bodyseg-ros2): the first reads every message's
//! header, the CameraInfos and tf, and decides the rig and the frames; every error of the
//! bag is found there, before anything is written. The second decodes the chosen images
//! and writes them, frames in parallel (one reader thread, the frames on rayon's workers
//! through a bounded queue: memory holds a few frames whatever the bag's length).
//!
//! ```text
//! OUT/rig.toml                       the cameras (CameraInfo, tf)
//! OUT/<camera>/depth/<stem>.png      16-bit millimetres
//! OUT/<camera>/color/<stem>.png|.jpg RGB PNG, or the bag's JPEG as it is
//! OUT/stamps.csv                     frame, camera, depth and colour stamps (ns)
//! OUT/import_ros2/import.json        the bag, topics per camera, notes, unpaired counts
//! OUT/import_ros2/frames/<stem>.json each frame's record, written last (resumable)
//! ```
//!
//! Frames are `000000`, `000001`, ... in stamp order. Resumable like `run`: a frame whose
//! record reads back with the same bag and options and whose files are all there with
//! their sizes is skipped.

use crate::batch::{BatchProgress, FrameFailure, FrameWriter, OutputFile, text_hash};
use crate::recording::{Layer, RecordingWriter};
use crate::stage::{Stage, plural};
use anyhow::{Context, Result, bail};
use bodyseg_ros2::{
    BagMessage, BagReader, BagScan, Color, ImportOptions, ImportPlan, PlannedFrame, decode_color,
    decode_depth,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Folder of the import's own files inside the recording.
const IMPORT_FOLDER: &str = "import_ros2";
/// The stamps of every frame, inside the recording.
const STAMPS_FILE: &str = "stamps.csv";
/// Read buffer per bag file, bytes: MCAP chunks are ~1 MiB (rosbag2's and the Python
/// writer's default), read in a few calls.
const READ_BUFFER: usize = 1 << 20;
/// Frames waiting for a worker, per worker: enough to keep them busy while the reader
/// decompresses the next chunk, few enough to keep memory flat.
const QUEUE_PER_WORKER: usize = 2;

/// What `bodyseg import ros2` is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct Ros2ImportOptions {
    /// The bag: an `.mcap` file or a rosbag2 folder.
    pub bag: PathBuf,
    /// The recording to write (created; complete frames in it are skipped).
    pub out: PathBuf,
    /// `(camera name, topic prefix)`, rig order; empty = found by layout.
    pub cameras: Vec<(String, String)>,
    /// The tf frame that becomes the world; `None` = the root of the cameras' tf tree.
    pub world_frame: Option<String>,
    /// Largest stamp difference between a camera's depth and colour images and between
    /// the cameras of one frame, milliseconds.
    pub max_skew_ms: f64,
    /// Write frames already complete in `out` again.
    pub redo: bool,
}

/// What the import did.
#[derive(Debug)]
pub struct Ros2ImportSummary {
    /// One line per camera: its topics, sizes, frames and what was imported.
    pub cameras: Vec<String>,
    /// Choices and warnings.
    pub notes: Vec<String>,
    /// Frames of the bag (complete in `out` now, unless failed).
    pub frames: usize,
    /// Frames written now.
    pub written: usize,
    /// Frames skipped as complete.
    pub skipped: usize,
    /// Frames that failed (reported and left out; the others are written).
    pub failed: Vec<FrameFailure>,
    /// Per stage timings and counts.
    pub stages: Vec<Stage>,
}

/// The MCAP files of a bag, in order.
fn bag_files(bag: &Path) -> Result<Vec<PathBuf>> {
    let is_db3 = |p: &Path| p.extension().is_some_and(|e| e == "db3");
    if bag.is_file() {
        if is_db3(bag) {
            return Err(bodyseg_ros2::sqlite_error(&bag.display().to_string()).into());
        }
        return Ok(vec![bag.to_path_buf()]);
    }
    if !bag.is_dir() {
        bail!(
            "{}: no such bag: give an .mcap file or a rosbag2 folder (metadata.yaml)",
            bag.display()
        );
    }
    let metadata = bag.join("metadata.yaml");
    if metadata.is_file() {
        let text = std::fs::read_to_string(&metadata)
            .with_context(|| format!("{}: cannot read", metadata.display()))?;
        let parsed =
            bodyseg_ros2::parse_metadata(&text).with_context(|| metadata.display().to_string())?;
        let files: Vec<PathBuf> = parsed.files.iter().map(|f| bag.join(f)).collect();
        for f in &files {
            if !f.is_file() {
                bail!(
                    "{}: metadata.yaml lists {}, which is missing",
                    bag.display(),
                    f.display()
                );
            }
        }
        return Ok(files);
    }
    let listing = bodyseg_io::list_folder(bag, "bag folder")?;
    let mut mcaps: Vec<PathBuf> = Vec::new();
    for e in listing.iter().filter(|e| !e.is_folder) {
        let path = bag.join(&e.name);
        if is_db3(&path) {
            return Err(bodyseg_ros2::sqlite_error(&bag.display().to_string()).into());
        }
        if path.extension().is_some_and(|x| x == "mcap") {
            mcaps.push(path);
        }
    }
    if mcaps.is_empty() {
        bail!(
            "{}: no metadata.yaml and no .mcap file: not a rosbag2 folder",
            bag.display()
        );
    }
    mcaps.sort();
    Ok(mcaps)
}

/// A streaming reader over the bag's files.
fn open_bag(files: &[PathBuf]) -> Result<BagReader<BufReader<File>>> {
    let mut readers = Vec::new();
    for f in files {
        let file =
            File::open(f).with_context(|| format!("{}: cannot open the bag", f.display()))?;
        readers.push((
            f.display().to_string(),
            BufReader::with_capacity(READ_BUFFER, file),
        ));
    }
    Ok(BagReader::new(readers))
}

/// The first pass: every message through [`BagScan`], then the plan.
fn scan(files: &[PathBuf], options: &ImportOptions) -> Result<(ImportPlan, u64)> {
    let mut scan = BagScan::default();
    for message in open_bag(files)? {
        scan.observe(&message?)?;
    }
    let plan = scan.plan(options)?;
    Ok((plan, scan.messages))
}

/// What decides a frame's files: the bag's files (path, size, modification time) and
/// the options. A record with another hash is out of date.
fn config_hash(files: &[PathBuf], options: &Ros2ImportOptions) -> String {
    let mut text = String::new();
    for f in files {
        let id = crate::batch::InputFile::of(f);
        text.push_str(&format!("{id:?}\n"));
    }
    text.push_str(&format!(
        "{:?} {:?} {}",
        options.cameras, options.world_frame, options.max_skew_ms
    ));
    text_hash(&text)
}

/// A frame's record: `OUT/import_ros2/frames/<stem>.json`, written after its images.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
struct ImportRecord {
    frame: String,
    config_hash: String,
    /// Per camera (rig order), `[depth stamp, colour stamp]`, nanoseconds.
    stamps_ns: Vec<[i64; 2]>,
    outputs: Vec<OutputFile>,
}

fn record_path(out: &Path, stem: &str) -> PathBuf {
    out.join(IMPORT_FOLDER)
        .join("frames")
        .join(format!("{stem}.json"))
}

/// Whether frame `stem` is complete in `out` under `hash`.
fn is_complete(out: &Path, stem: &str, hash: &str) -> bool {
    let Ok(text) = std::fs::read_to_string(record_path(out, stem)) else {
        return false;
    };
    let Ok(record) = serde_json::from_str::<ImportRecord>(&text) else {
        return false;
    };
    record.frame == stem
        && record.config_hash == hash
        && record.outputs.iter().all(|f| {
            std::fs::metadata(out.join(&f.path)).is_ok_and(|m| m.is_file() && m.len() == f.bytes)
        })
}

/// The stem of frame `index`.
fn stem_of(index: usize) -> String {
    format!("{index:06}")
}

/// One frame's messages, as the second pass collected them: per camera, depth and colour.
struct FrameData {
    index: usize,
    views: Vec<[Vec<u8>; 2]>,
}

/// Decodes and writes one frame through `writer`; returns its record.
fn write_frame(
    frame: &FrameData,
    plan: &ImportPlan,
    rec: &RecordingWriter,
    writer: &mut FrameWriter,
    hash: &str,
) -> Result<ImportRecord> {
    let stem = stem_of(frame.index);
    let planned = &plan.frames[frame.index];
    let out = rec.root().to_path_buf();
    let relative = |path: &Path| -> String {
        path.strip_prefix(&out)
            .unwrap_or(path)
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/")
    };
    for (i, (data, view)) in frame.views.iter().zip(&planned.views).enumerate() {
        let source = &plan.sources[i];
        let camera = &plan.rig.cameras[i];
        let [depth_msg, color_msg] = data;
        let depth = decode_depth(
            view.depth.kind,
            depth_msg,
            (camera.depth.width, camera.depth.height),
        )
        .map_err(|e| e.at(&source.depth.topic, view.depth.stamp))?;
        let path = rec.image_path(i, Layer::Depth, &stem, "png")?;
        writer.write(&relative(&path), |_| rec.write_depth(i, &stem, &depth))?;
        let color = decode_color(
            view.color.kind,
            color_msg,
            (camera.color.width, camera.color.height),
        )
        .map_err(|e| e.at(&source.color.topic, view.color.stamp))?;
        match color {
            Color::Rgb { rgb, .. } => {
                let path = rec.image_path(i, Layer::Color, &stem, "png")?;
                writer.write(&relative(&path), |_| rec.write_color(i, &stem, &rgb))?;
            }
            Color::Jpeg { bytes, .. } => {
                let path = rec.image_path(i, Layer::Color, &stem, "jpg")?;
                writer.write(&relative(&path), |_| rec.write_color_jpeg(i, &stem, &bytes))?;
            }
        }
    }
    Ok(ImportRecord {
        frame: stem,
        config_hash: hash.to_string(),
        stamps_ns: planned
            .views
            .iter()
            .map(|v| [v.depth.stamp.ns(), v.color.stamp.ns()])
            .collect(),
        outputs: writer.outputs().to_vec(),
    })
}

/// Which message goes where: `ordinal → (frame index, camera, 0 depth / 1 colour)`.
fn wanted_messages(frames: &[(usize, &PlannedFrame)]) -> HashMap<u64, (usize, usize, usize)> {
    let mut wanted = HashMap::new();
    for (index, frame) in frames {
        for (camera, view) in frame.views.iter().enumerate() {
            wanted.insert(view.depth.ordinal, (*index, camera, 0));
            wanted.insert(view.color.ordinal, (*index, camera, 1));
        }
    }
    wanted
}

/// Frames being assembled by the second pass's reader.
struct Assembly {
    views: Vec<[Option<Vec<u8>>; 2]>,
    missing: usize,
}

/// The second pass's reader: streams the bag and hands each frame on as soon as its
/// messages are all read. Returns the reader's error, if any; `send` is dropped on
/// return, which ends the receiving loop.
fn read_frames(
    files: &[PathBuf],
    wanted: &HashMap<u64, (usize, usize, usize)>,
    cameras: usize,
    send: std::sync::mpsc::SyncSender<FrameData>,
) -> Result<()> {
    let mut open: HashMap<usize, Assembly> = HashMap::new();
    for message in open_bag(files)? {
        let BagMessage { ordinal, data, .. } = message?;
        let Some(&(index, camera, slot)) = wanted.get(&ordinal) else {
            continue;
        };
        let assembly = open.entry(index).or_insert_with(|| Assembly {
            views: (0..cameras).map(|_| [None, None]).collect(),
            missing: 2 * cameras,
        });
        if assembly.views[camera][slot].replace(data).is_none() {
            assembly.missing -= 1;
        }
        if assembly.missing == 0
            && let Some(done) = open.remove(&index)
        {
            let views = done
                .views
                .into_iter()
                .map(|[d, c]| [d.unwrap_or_default(), c.unwrap_or_default()])
                .collect();
            if send.send(FrameData { index, views }).is_err() {
                // The workers stopped: nothing more to do.
                return Ok(());
            }
        }
    }
    if !open.is_empty() {
        bail!(
            "the bag changed between the two passes: {} frames lack messages",
            open.len()
        );
    }
    Ok(())
}

/// `OUT/stamps.csv`: `frame,camera,depth_stamp_ns,colour_stamp_ns`, one line per frame
/// and camera.
fn stamps_csv(plan: &ImportPlan) -> String {
    let mut text = String::from("frame,camera,depth_stamp_ns,colour_stamp_ns\n");
    for (index, frame) in plan.frames.iter().enumerate() {
        for (view, camera) in frame.views.iter().zip(&plan.rig.cameras) {
            text.push_str(&format!(
                "{},{},{},{}\n",
                stem_of(index),
                camera.name,
                view.depth.stamp.ns(),
                view.color.stamp.ns()
            ));
        }
    }
    text
}

/// `OUT/import_ros2/import.json`: where the recording came from.
fn import_json(files: &[PathBuf], plan: &ImportPlan, cameras: &[String]) -> Result<String> {
    let unpaired: Vec<serde_json::Value> = plan
        .unpaired
        .iter()
        .map(|u| {
            serde_json::json!({
                "camera": u.camera, "depth": u.depth, "colour": u.color, "pairs": u.pairs,
            })
        })
        .collect();
    let value = serde_json::json!({
        "bag": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
        "world_frame": plan.world_frame,
        "cameras": cameras,
        "frames": plan.frames.len(),
        "unpaired": unpaired,
        "notes": plan.notes,
    });
    Ok(serde_json::to_string_pretty(&value)?)
}

/// Imports a ROS 2 bag into a recording; `progress` is called after each frame.
///
/// # Errors
/// The bag cannot be read (missing, a SQLite bag, truncated, an unknown encoding, a
/// camera without CameraInfo, no transform between a camera's depth and colour frames):
/// one error naming the topic or field and the stamp, and nothing is written. A frame
/// whose images fail to decode is reported in [`Ros2ImportSummary::failed`] and leaves
/// no file.
pub fn import_ros2(
    options: &Ros2ImportOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<Ros2ImportSummary> {
    if !(options.max_skew_ms.is_finite() && options.max_skew_ms >= 0.0) {
        bail!(
            "--max-skew-ms must be a number of milliseconds >= 0, got {}",
            options.max_skew_ms
        );
    }
    let import_options = ImportOptions {
        cameras: options.cameras.clone(),
        world_frame: options.world_frame.clone(),
        max_skew_ns: (options.max_skew_ms * 1e6).round() as i64,
    };
    let bag = options.bag.display().to_string();
    let start = Instant::now();
    let files = bag_files(&options.bag)?;
    let (plan, messages) = scan(&files, &import_options).with_context(|| bag.clone())?;
    let mut stages = vec![Stage::new(
        "scan",
        start.elapsed(),
        format!(
            "{} in {}",
            plural(messages as usize, "message", "messages"),
            plural(files.len(), "file", "files")
        ),
    )];
    for s in &plan.sources {
        if s.name == IMPORT_FOLDER || s.name == "boxes" {
            bail!(
                "{bag}: camera {:?} would share its folder with the recording's {0}/: name it \
                 with --camera NAME=TOPIC_PREFIX",
                s.name
            );
        }
    }
    if plan.frames.is_empty() {
        let counts: Vec<String> = plan
            .unpaired
            .iter()
            .map(|u| {
                format!(
                    "{}: {} depth, {} colour unpaired",
                    u.camera, u.depth, u.color
                )
            })
            .collect();
        bail!(
            "{bag}: no frame: no depth and colour images of every camera within --max-skew-ms \
             {} ({})",
            options.max_skew_ms,
            counts.join("; ")
        );
    }
    let cameras: Vec<String> = plan.sources.iter().map(|s| s.describe()).collect();
    let mut notes = plan.notes.clone();
    for u in plan
        .unpaired
        .iter()
        .filter(|u| u.depth + u.color + u.pairs > 0)
    {
        notes.push(format!(
            "camera {}: left out {} depth and {} colour images without a partner within {} ms, \
             and {} pairs without every other camera",
            u.camera, u.depth, u.color, options.max_skew_ms, u.pairs
        ));
    }

    // Nothing was written so far; now the recording.
    let hash = config_hash(&files, options);
    let rec = RecordingWriter::create(&options.out, &plan.rig, &[Layer::Color, Layer::Depth])?;
    let out = options.out.as_path();
    let total = plan.frames.len();
    let todo: Vec<(usize, &PlannedFrame)> = plan
        .frames
        .iter()
        .enumerate()
        .filter(|(i, _)| options.redo || !is_complete(out, &stem_of(*i), &hash))
        .collect();
    let skipped = total - todo.len();
    let finished = AtomicUsize::new(skipped);
    let failed_count = AtomicUsize::new(0);
    progress(BatchProgress {
        finished: skipped,
        total,
        failed: 0,
        skipped,
    });
    let write_start = Instant::now();
    let failures: Mutex<Vec<FrameFailure>> = Mutex::new(Vec::new());
    if !todo.is_empty() {
        let wanted = wanted_messages(&todo);
        let workers = rayon::current_num_threads().max(1);
        let (send, receive) =
            std::sync::mpsc::sync_channel::<FrameData>(QUEUE_PER_WORKER * workers);
        let reader_result = std::thread::scope(|scope| {
            // The sender moves into the reader thread: when it returns, the channel
            // closes and the workers' loop ends.
            let (files, wanted, cameras) = (&files, &wanted, plan.rig.cameras.len());
            let reader = scope.spawn(move || read_frames(files, wanted, cameras, send));
            receive.into_iter().par_bridge().for_each(|frame| {
                let stem = stem_of(frame.index);
                let mut writer = FrameWriter::new(out);
                let result =
                    write_frame(&frame, &plan, &rec, &mut writer, &hash).and_then(|record| {
                        let path = record_path(out, &stem);
                        if let Some(parent) = path.parent() {
                            bodyseg_io::create_folder(parent)?;
                        }
                        crate::outputs::write_text(&path, &serde_json::to_string_pretty(&record)?)
                    });
                if let Err(e) = result {
                    writer.remove_all();
                    let _ = std::fs::remove_file(record_path(out, &stem));
                    failed_count.fetch_add(1, Ordering::Relaxed);
                    if let Ok(mut f) = failures.lock() {
                        f.push(FrameFailure {
                            frame: stem,
                            error: format!("{e:#}"),
                        });
                    }
                }
                progress(BatchProgress {
                    finished: finished.fetch_add(1, Ordering::Relaxed) + 1,
                    total,
                    failed: failed_count.load(Ordering::Relaxed),
                    skipped,
                });
            });
            reader.join()
        });
        match reader_result {
            Ok(result) => result.with_context(|| bag.clone())?,
            Err(_) => bail!("{bag}: the bag reader panicked"),
        }
    }
    let mut failed = failures.into_inner().unwrap_or_default();
    failed.sort_by(|a, b| a.frame.cmp(&b.frame));
    crate::outputs::write_text(&out.join(STAMPS_FILE), &stamps_csv(&plan))?;
    crate::outputs::write_text(
        &out.join(IMPORT_FOLDER).join("import.json"),
        &import_json(&files, &plan, &cameras)?,
    )?;
    let written = todo.len() - failed.len();
    let elapsed = write_start.elapsed();
    stages.push(Stage::new(
        "frames",
        elapsed,
        format!(
            "{} written ({:.1} frames/s), {} skipped as complete, {} failed, {} into {}",
            written,
            written as f64 / elapsed.as_secs_f64().max(1e-9),
            skipped,
            failed.len(),
            plural(plan.rig.cameras.len(), "camera", "cameras"),
            out.display()
        ),
    ));
    Ok(Ros2ImportSummary {
        cameras,
        notes,
        frames: total,
        written,
        skipped,
        failed,
        stages,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bags_are_files_or_rosbag2_folders_and_sqlite_is_refused_by_name() {
        let dir = tempfile::tempdir().expect("temp dir");
        let e = format!(
            "{:#}",
            bag_files(&dir.path().join("none")).expect_err("missing")
        );
        assert!(e.contains("no such bag"), "{e}");
        let db3 = dir.path().join("rec_0.db3");
        std::fs::write(&db3, b"SQLite format 3\0").expect("write");
        let e = format!("{:#}", bag_files(&db3).expect_err("db3 file"));
        assert!(e.contains("ros2 bag convert"), "{e}");
        let e = format!("{:#}", bag_files(dir.path()).expect_err("db3 folder"));
        assert!(e.contains("ros2 bag convert"), "{e}");
        std::fs::write(
            dir.path().join("metadata.yaml"),
            "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  \
             relative_file_paths: [rec_0.db3]\n",
        )
        .expect("write");
        let e = format!("{:#}", bag_files(dir.path()).expect_err("sqlite metadata"));
        assert!(e.contains("ros2 bag convert"), "{e}");
        let mcap = tempfile::tempdir().expect("temp dir");
        std::fs::write(mcap.path().join("b.mcap"), b"").expect("write");
        std::fs::write(mcap.path().join("a.mcap"), b"").expect("write");
        let files = bag_files(mcap.path()).expect("mcap folder");
        assert_eq!(
            files,
            [mcap.path().join("a.mcap"), mcap.path().join("b.mcap")]
        );
    }
}
