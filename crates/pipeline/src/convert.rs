//! `bodyseg convert`: a dataset in batch → labelled point clouds, resumable and sharded
//! (the frame loop of [`crate::batch`]).
//!
//! - `recording`: one recording, or a folder of recordings. Each frame runs through the
//!   pipeline as in `bodyseg run` (no figures, no label images) into
//!   `OUT/<recording>/clouds/`, `boxes/` (`OUT/clouds/`... for a single recording); per
//!   recording `report.md` / `report.json`, and over all of them `OUT/report.json`.
//! - `3dpeople`: every view of a 3DPeople dataset → `OUT/clouds/<view>.ply`, the
//!   ground-truth body parts on the back-projected depth, camera colours.
//!
//! Records go to `OUT/frames/<id>.json` (id `<recording>/<frame>` or the view's stem);
//! report files carry the shard's suffix (`report.shard-3-of-8.json`) so every shard can
//! write into one shared folder, and `bodyseg eval --merge` sums them.

use crate::batch::{
    BatchFrame, BatchOutcome, BatchProgress, FrameRecord, FrameWriter, InputFile, Shard, run_batch,
    text_hash,
};
use crate::config::PipelineConfig;
use crate::model::ParserChoice;
use crate::outputs::check_output_folder;
use crate::processor::FrameProcessor;
use crate::recording::{Recording, check_folder_name};
use crate::report::{ReportTarget, RunSummary, write_reports};
use crate::stage::{Stage, plural, timed};
use crate::threedpeople::{ThreeDPeopleCamera, list_3dpeople_views, read_3dpeople_view};
use crate::viewer::{RerunOutput, run_batch_with_rerun};
use anyhow::{Context, Result, bail};
use bodyseg_eval::Report;
use bodyseg_io::{PlyColors, PlyFormat, PlyWriteOptions};
use std::path::{Path, PathBuf};

/// The dataset layouts `bodyseg convert` reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConvertFormat {
    /// bodyseg recordings (FORMATS.md).
    Recording,
    /// The 3DPeople dataset.
    ThreeDPeople,
}

/// What [`convert_dataset`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct ConvertOptions {
    /// The dataset folder.
    pub input: PathBuf,
    /// Its layout.
    pub format: ConvertFormat,
    /// The resolved configuration, validated.
    pub config: PipelineConfig,
    /// Output folder.
    pub out: PathBuf,
    /// Recordings: where the 2D labels come from.
    pub parser: ParserChoice,
    /// This process's part of the frames.
    pub shard: Shard,
    /// Recordings: also write the projected cloud and the ablation's clouds.
    pub write_stages: bool,
    /// Redo complete frames.
    pub redo: bool,
    /// 3DPeople: intrinsics, depth unit and palette matching.
    pub camera_3dpeople: ThreeDPeopleCamera,
    /// One recording: also log every frame into this Rerun file (`.rrd`, feature
    /// `rerun`; complete frames are redone; no label images in it, convert draws none).
    pub rerun: Option<PathBuf>,
    /// With `rerun`: also log the clusters layer (`world/clusters`).
    pub rerun_clusters: bool,
}

/// What [`convert_dataset`] did: as `bodyseg run` (no figures).
pub type ConvertSummary = RunSummary;

/// The summary of a conversion once its reports are written.
fn summary(
    frames: usize,
    outcome: BatchOutcome,
    report: Option<Report>,
    written: Vec<PathBuf>,
    mut stages: Vec<Stage>,
    took: std::time::Duration,
) -> ConvertSummary {
    stages.push(Stage::new(
        "report",
        took,
        plural(written.len(), "file", "files"),
    ));
    RunSummary {
        frames,
        outcome,
        report,
        written,
        figures: Vec::new(),
        stages,
    }
}

/// The recordings of `input`: itself when it holds `rig.toml`, else its sub-folders that
/// do (sorted by name), named by folder.
///
/// # Errors
/// `input` is not a folder, or holds no recording.
pub(crate) fn list_recordings(input: &Path) -> Result<Vec<(String, PathBuf)>> {
    bodyseg_io::require_folder(input, "dataset")?;
    if Recording::is_recording(input) {
        return Ok(vec![(String::new(), input.to_path_buf())]);
    }
    let mut found: Vec<(String, PathBuf)> = std::fs::read_dir(input)
        .with_context(|| format!("{}: cannot list", input.display()))?
        .flatten()
        .filter(|e| Recording::is_recording(&e.path()))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path()))
        .filter(|(name, _)| !name.starts_with('.'))
        .collect();
    found.sort();
    for (name, _) in &found {
        check_folder_name(&format!("{}: recording", input.display()), name)?;
    }
    if found.is_empty() {
        bail!(
            "{}: no recording (a folder with rig.toml) in it or below it",
            input.display()
        );
    }
    Ok(found)
}

/// Converts a dataset (see the module documentation).
///
/// # Errors
/// The dataset cannot be listed, a recording's rig or the model cannot be loaded, the
/// output folder cannot be created, reports cannot be written. A frame's failure is not
/// an error: it is in [`BatchOutcome::failed`].
pub fn convert_dataset(
    opts: &ConvertOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<ConvertSummary> {
    check_output_folder(&opts.out, "--input", &opts.input)?;
    match opts.format {
        ConvertFormat::Recording => convert_recordings(opts, progress),
        ConvertFormat::ThreeDPeople => convert_3dpeople(opts, progress),
    }
}

fn convert_recordings(
    opts: &ConvertOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<ConvertSummary> {
    let (setup, took) = timed(|| -> Result<_> {
        let recordings = list_recordings(&opts.input)?;
        if opts.rerun.is_some() && recordings.len() != 1 {
            bail!(
                "--rerun: {} holds {} recordings; a Rerun file is written for one recording",
                opts.input.display(),
                recordings.len()
            );
        }
        bodyseg_io::create_folder(&opts.out)?;
        let mut rerun = None;
        let mut processors = Vec::new();
        let mut jobs: Vec<(String, (usize, String))> = Vec::new();
        for (k, (name, path)) in recordings.iter().enumerate() {
            let prefix = if name.is_empty() {
                String::new()
            } else {
                format!("{name}/")
            };
            let processor = FrameProcessor::open(path, &opts.config, opts.parser)
                .with_context(|| format!("recording {}", path.display()))?
                .with_stage_clouds(opts.write_stages)
                .with_label_images(false)
                .with_prefix(prefix.clone());
            let processor = match &opts.rerun {
                Some(file) => {
                    let all = processor.recording().frames()?.complete;
                    let out = RerunOutput::create(
                        file,
                        processor.recording(),
                        &all,
                        opts.rerun_clusters,
                    )?;
                    let processor = processor.with_sink(Some(out.sink()));
                    rerun = Some(out);
                    processor
                }
                None => processor,
            };
            for frame in processor.recording().frames()?.complete {
                jobs.push((format!("{prefix}{frame}"), (k, frame)));
            }
            processors.push(processor);
        }
        jobs.sort_by(|a, b| a.0.cmp(&b.0));
        Ok((recordings, processors, jobs, rerun))
    })?;
    let (recordings, processors, jobs, rerun) = setup;
    let _lock = crate::batch::lock_output(&opts.out, opts.shard)?;
    let mut stages = vec![Stage::new(
        "setup",
        took,
        format!(
            "{}, {}",
            plural(recordings.len(), "recording", "recordings"),
            plural(jobs.len(), "frame", "frames")
        ),
    )];
    let resolved = opts.config.resolved_toml()?;
    let hash = text_hash(&format!(
        "{resolved}\nconvert recording parser={:?} stages={} v1",
        opts.parser, opts.write_stages
    ));
    let (outcome, _) = run_batch_with_rerun(
        &jobs,
        &opts.out,
        opts.shard,
        &hash,
        opts.redo,
        rerun.as_ref(),
        progress,
        &|f: BatchFrame<'_, (usize, String)>,
          writer: &mut FrameWriter,
          stages: &mut Vec<Stage>|
         -> Result<FrameRecord> {
            let (k, frame) = f.job;
            processors[*k].run_frame(frame, writer, stages)
        },
        &mut stages,
    )?;
    let fps = outcome.frames_per_second();

    // Reports per recording (its records and failures), then over all recordings.
    let (written_report, took) = timed(|| -> Result<_> {
        let mut written = Vec::new();
        for (name, path) in &recordings {
            if name.is_empty() {
                continue; // A single recording: the overall report is its report.
            }
            let prefix = format!("{name}/");
            // A shard holding none of this recording's frames has nothing to report on it
            // (and its folder may not exist).
            let held = jobs
                .iter()
                .enumerate()
                .any(|(i, (id, _))| opts.shard.holds(i) && id.starts_with(&prefix));
            if !held {
                continue;
            }
            let sub = BatchOutcome {
                records: outcome
                    .records
                    .iter()
                    .filter(|r| r.frame.starts_with(&prefix))
                    .cloned()
                    .collect(),
                scores: outcome
                    .scores
                    .get(name.as_str())
                    .map(|r| (name.clone(), r.clone()))
                    .into_iter()
                    .collect(),
                processed: 0,
                skipped: 0,
                failed: outcome
                    .failed
                    .iter()
                    .filter(|f| f.frame.starts_with(&prefix))
                    .cloned()
                    .collect(),
                stage_totals: Vec::new(),
                elapsed: outcome.elapsed,
            };
            let frames: Vec<String> = jobs
                .iter()
                .filter(|(id, _)| id.starts_with(&prefix))
                .map(|(id, _)| id.clone())
                .collect();
            let target = ReportTarget {
                out: &opts.out.join(name),
                input: path,
                shard: opts.shard,
                header: false,
                incomplete: &[],
            };
            let (_, w) = write_reports(target, &frames, &sub, &resolved, fps)?;
            written.extend(w);
        }
        let frames: Vec<String> = jobs.iter().map(|(id, _)| id.clone()).collect();
        let (report, w) = write_reports(opts.report_target(), &frames, &outcome, &resolved, fps)?;
        written.extend(w);
        Ok((written, report))
    })?;
    let (written, report) = written_report;
    let frames = opts.shard.share(jobs.len());
    Ok(summary(frames, outcome, report, written, stages, took))
}

impl ConvertOptions {
    /// Where the reports over the whole data set go.
    fn report_target(&self) -> ReportTarget<'_> {
        ReportTarget {
            out: &self.out,
            input: &self.input,
            shard: self.shard,
            header: false,
            incomplete: &[],
        }
    }
}

fn convert_3dpeople(
    opts: &ConvertOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<ConvertSummary> {
    if opts.rerun.is_some() {
        bail!("--rerun: only for a bodyseg recording, not --format 3dpeople");
    }
    let (views, took) = timed(|| -> Result<_> {
        let views = list_3dpeople_views(&opts.input)?;
        if views.is_empty() {
            bail!(
                "{}: no 3DPeople view (rgb/<subject>/<sequence>/cameraNN/*)",
                opts.input.display()
            );
        }
        bodyseg_io::create_folder(&opts.out)?;
        Ok(views)
    })?;
    let _lock = crate::batch::lock_output(&opts.out, opts.shard)?;
    let mut jobs: Vec<(String, _)> = views.into_iter().map(|v| (v.stem(), v)).collect();
    jobs.sort_by(|a, b| a.0.cmp(&b.0));
    let mut stages = vec![Stage::new(
        "setup",
        took,
        plural(jobs.len(), "view", "views"),
    )];
    let camera = opts.camera_3dpeople;
    camera.validate().context("3DPeople camera")?;
    let hash = text_hash(&format!("convert 3dpeople {camera:?} v1"));
    let ply = PlyWriteOptions {
        format: PlyFormat::BinaryLittleEndian,
        colors: PlyColors::Camera,
        // The batch syncs once at its end.
        durability: bodyseg_io::Durability::Renamed,
    };
    let outcome = run_batch(
        &jobs,
        &opts.out,
        opts.shard,
        &hash,
        opts.redo,
        progress,
        &|f, writer, stages| -> Result<FrameRecord> {
            let (cloud, took) = timed(|| read_3dpeople_view(f.job, &camera))?;
            stages.push(Stage::new("read", took, String::new()));
            let ((), took) = timed(|| -> Result<()> {
                writer.write(&format!("clouds/{}.ply", f.id), |p| {
                    Ok(bodyseg_io::write_ply(p, &cloud, &ply)?)
                })?;
                Ok(())
            })?;
            stages.push(Stage::new("write", took, String::new()));
            Ok(FrameRecord {
                frame: f.id.to_string(),
                config_hash: String::new(),
                points: cloud.len(),
                unknown: cloud.labels.iter().filter(|l| l.is_unknown()).count(),
                people: 0,
                outputs: Vec::new(),
                inputs: [&f.job.rgb_path, &f.job.depth_path, &f.job.segmentation_path]
                    .into_iter()
                    .filter_map(|p| InputFile::of(p))
                    .collect(),
                scores: None,
            })
        },
    )?;
    let fps = outcome.frames_per_second();
    stages.extend(outcome.stage_lines());
    let frames: Vec<String> = jobs.iter().map(|(id, _)| id.clone()).collect();
    let resolved = opts.config.resolved_toml()?;
    let ((report, written), took) =
        timed(|| write_reports(opts.report_target(), &frames, &outcome, &resolved, fps))?;
    let frames = opts.shard.share(jobs.len());
    Ok(summary(frames, outcome, report, written, stages, took))
}
