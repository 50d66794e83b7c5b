//! `bodyseg run`: a whole recording through every stage, frame by frame:
//! read → parse (ONNX model or recorded predictions) → project → boxes → refine → write →
//! evaluate, with the resumable, sharded frame loop of [`crate::batch`].
//!
//! Output folder (`OUT`):
//! ```text
//! clouds/<frame>.ply               the refined cloud (refine.steps), palette colours
//! boxes/<frame>.json               the person boxes
//! labels/<camera>/<frame>.png      refined labels drawn back into each colour image (class ids, 255 = none)
//! stages/<frame>/<name>.ply        with --write-stages: projected.ply and one cloud per configuration
//! figures/<frame>.png              selected frames: input, clusters, M, N, M-N, M-R-N (and truth)
//! frames/<frame>.json              per-frame record: outputs, scores (see crate::batch)
//! report.md, report.json           the paper's table (when the recording has ground truth)
//! config.resolved.toml             the configuration that made all this
//! run.json                         this run's log: frames processed, skipped, failed; times
//! ```
//!
//! With `--rerun FILE.rrd` (feature `rerun`) every frame is also logged into a Rerun
//! recording (bodyseg-view); complete frames are then redone, not skipped, so that the
//! file has them all (`bodyseg view` writes it from a finished run's outputs instead).

use crate::batch::{BatchFrame, BatchProgress, FrameWriter, Shard};
use crate::config::PipelineConfig;
use crate::model::ParserChoice;
use crate::outputs::check_output_folder;
use crate::processor::FrameProcessor;
use crate::recording::check_stem;
use crate::report::{ReportTarget, RunSummary, figure_outputs, write_reports};
use crate::stage::{Stage, plural, timed};
use crate::viewer::{RerunOutput, run_batch_with_rerun};
use anyhow::{Result, bail};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Which frames get a Figure-5-style picture.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum FigureChoice {
    /// The middle frame of the recording (of the frames selected).
    #[default]
    Middle,
    /// None.
    Off,
    /// These frames (those not in the run are ignored).
    Frames(Vec<String>),
}

/// What [`run_recording`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The recording folder (FORMATS.md).
    pub recording: PathBuf,
    /// The resolved configuration, validated.
    pub config: PipelineConfig,
    /// Output folder (created; frames already complete in it are skipped).
    pub out: PathBuf,
    /// Where the 2D labels come from.
    pub parser: ParserChoice,
    /// Frames to run (stems); `None`: every frame of the recording.
    pub frames: Option<Vec<String>>,
    /// Run only the first this many of those frames.
    pub limit: Option<usize>,
    /// This process's part of the frames.
    pub shard: Shard,
    /// Also write the projected cloud and one cloud per configuration of the ablation.
    pub write_stages: bool,
    /// Frames that get a figure.
    pub figures: FigureChoice,
    /// Draw the refined labels back into each colour image (`labels/`).
    pub label_images: bool,
    /// Redo frames that are already complete.
    pub redo: bool,
    /// Also log every frame into this Rerun file (`.rrd`, feature `rerun`); complete
    /// frames are then redone.
    pub rerun: Option<PathBuf>,
    /// With `rerun`: also log the clusters layer (`world/clusters`).
    pub rerun_clusters: bool,
}

impl RunOptions {
    /// Options with the defaults of `bodyseg run`: every frame, whole batch, automatic
    /// parser, a figure of the middle frame, label images, no stage clouds.
    pub fn new(recording: &Path, config: PipelineConfig, out: &Path) -> RunOptions {
        RunOptions {
            recording: recording.to_path_buf(),
            config,
            out: out.to_path_buf(),
            parser: ParserChoice::Auto,
            frames: None,
            limit: None,
            shard: Shard::ALL,
            write_stages: false,
            figures: FigureChoice::Middle,
            label_images: true,
            redo: false,
            rerun: None,
            rerun_clusters: false,
        }
    }

    /// Where the run's reports go.
    fn report_target<'a>(&'a self, incomplete: &'a [(String, Vec<String>)]) -> ReportTarget<'a> {
        ReportTarget {
            out: &self.out,
            input: &self.recording,
            shard: self.shard,
            header: true,
            incomplete,
        }
    }
}

/// The frames that get a figure.
fn figure_frames(choice: &FigureChoice, frames: &[String]) -> BTreeSet<String> {
    match choice {
        FigureChoice::Off => BTreeSet::new(),
        FigureChoice::Middle => frames.get(frames.len() / 2).cloned().into_iter().collect(),
        FigureChoice::Frames(f) => f.iter().filter(|s| frames.contains(s)).cloned().collect(),
    }
}

/// Hash of everything that decides a run's outputs.
fn run_hash(
    opts: &RunOptions,
    resolved: &str,
    uses_model: bool,
    figures: &BTreeSet<String>,
) -> String {
    crate::batch::text_hash(&format!(
        "{resolved}\nmodel={uses_model} stages={} labels={} figures={figures:?} v1",
        opts.write_stages, opts.label_images
    ))
}

/// Runs a recording through every stage (see the module documentation for the outputs).
///
/// # Errors
/// The recording or its rig cannot be read, the model cannot be loaded, a frame asked for
/// does not exist, the output folder cannot be created, or the reports cannot be written.
/// A frame that fails is not an error: it is in [`crate::BatchOutcome::failed`] (and `run.json`,
/// `report.md`).
pub fn run_recording(
    opts: &RunOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<RunSummary> {
    check_output_folder(&opts.out, "REC", &opts.recording)?;
    let (setup, took) = timed(|| -> Result<_> {
        let processor = FrameProcessor::open(&opts.recording, &opts.config, opts.parser)?
            .with_stage_clouds(opts.write_stages)
            .with_label_images(opts.label_images);
        let listed = processor.recording().frames()?;
        let incomplete = listed.incomplete;
        let all = listed.complete;
        let rerun = match &opts.rerun {
            Some(path) => Some(RerunOutput::create(
                path,
                processor.recording(),
                &all,
                opts.rerun_clusters,
            )?),
            None => None,
        };
        let processor = processor.with_sink(rerun.as_ref().map(RerunOutput::sink));
        let frames = match &opts.frames {
            None => all,
            Some(want) => {
                for f in want {
                    check_stem(f)?;
                    if !all.contains(f) {
                        bail!(
                            "frame {f}: not in {} (no depth image for every camera)",
                            opts.recording.display()
                        );
                    }
                }
                let set: BTreeSet<&String> = want.iter().collect();
                all.into_iter().filter(|f| set.contains(f)).collect()
            }
        };
        let frames: Vec<String> = frames
            .into_iter()
            .take(opts.limit.unwrap_or(usize::MAX))
            .collect();
        if frames.is_empty() {
            bail!(
                "{}: no frames (REC/<camera>/depth/*.png)",
                opts.recording.display()
            );
        }
        let figures = figure_frames(&opts.figures, &frames);
        let processor = processor.with_figures(figures.clone());
        bodyseg_io::create_folder(&opts.out)?;
        Ok((frames, figures, processor, incomplete, rerun))
    })?;
    let (frames, figures, processor, incomplete, rerun) = setup;
    let _lock = crate::batch::lock_output(&opts.out, opts.shard)?;
    if !incomplete.is_empty() {
        let list: Vec<String> = incomplete
            .iter()
            .map(|(f, cams)| format!("{f} (no {})", cams.join(", ")))
            .collect();
        tracing::warn!(
            "{}: {} skipped, a camera lacks them (listed in run.json and report.md): {}",
            opts.recording.display(),
            plural(incomplete.len(), "frame", "frames"),
            list.join(", ")
        );
    }
    let mut stages = vec![Stage::new(
        "setup",
        took,
        format!(
            "{}, {}, labels from {}{}",
            plural(frames.len(), "frame", "frames"),
            plural(processor.rig().cameras.len(), "camera", "cameras"),
            if processor.uses_model() {
                "the model"
            } else {
                "parsing/"
            },
            if processor.has_truth() {
                ", ground truth"
            } else {
                ""
            }
        ),
    )];
    let resolved = opts.config.resolved_toml()?;
    let hash = run_hash(opts, &resolved, processor.uses_model(), &figures);
    let jobs: Vec<(String, ())> = frames.iter().map(|f| (f.clone(), ())).collect();
    let (outcome, written_rrd) = run_batch_with_rerun(
        &jobs,
        &opts.out,
        opts.shard,
        &hash,
        opts.redo,
        rerun.as_ref(),
        progress,
        &|f: BatchFrame<'_, ()>, writer: &mut FrameWriter, stages: &mut Vec<Stage>| {
            processor.run_frame(f.id, writer, stages)
        },
        &mut stages,
    )?;
    let fps = outcome.frames_per_second();

    let ((report, written), took) = timed(|| {
        write_reports(
            opts.report_target(&incomplete),
            &frames,
            &outcome,
            &resolved,
            fps,
        )
    })?;
    stages.push(Stage::new(
        "report",
        took,
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    ));
    let figures = figure_outputs(&outcome).map(|f| opts.out.join(f)).collect();
    Ok(RunSummary {
        frames: opts.shard.share(frames.len()),
        outcome,
        report,
        written: written.into_iter().chain(written_rrd).collect(),
        figures,
        stages,
    })
}
