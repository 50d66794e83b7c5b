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

use crate::batch::{BatchFrame, BatchOutcome, BatchProgress, FrameRecord, FrameWriter, Shard};
use crate::config::PipelineConfig;
use crate::figure::{FigurePanel, LabelView, figure_image, panel_view};
use crate::frame::{Frame, FrameNeeds, ParsedFrame, parse_frame};
use crate::fs::write_text;
use crate::parse::{load_segmenter, resolve_model};
use crate::recording::{Layer, Recording, check_stem};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_calib::Rig;
use bodyseg_core::{Label, LabelImage, LabeledCloud, PersonBoxes, RgbImage};
use bodyseg_eval::Report;
use bodyseg_io::{Durability, PlyFormat, PlyWriteOptions};
use bodyseg_parsing::{RecordedSegmenter, Segmenter};
use bodyseg_people::BoxMode;
use bodyseg_project::{CameraImages, FrameProjector, Hits};
use bodyseg_refine::{NoiseMode, PointEvidence, RefinedVariants, Steps, VoteMode};
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Where a run's 2D labels come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ParserChoice {
    /// Recorded predictions when the recording has `parsing/` folders, else the model.
    #[default]
    Auto,
    /// The ONNX model (`parsing.model`, or the bundled one) on the colour images.
    Model,
    /// The recording's `<camera>/parsing/<frame>.png`.
    Recorded,
}

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
        }
    }
}

/// What [`run_recording`] did.
#[derive(Debug)]
pub struct RunSummary {
    /// Frames of this shard.
    pub frames: usize,
    /// The frame loop's outcome: records, counts, failures, stage times.
    pub outcome: BatchOutcome,
    /// The merged report (when the recording has ground truth).
    pub report: Option<Report>,
    /// Report files written (`report.md`, `report.json`, `config.resolved.toml`,
    /// `run.json`).
    pub written: Vec<PathBuf>,
    /// Figures written or already present, in frame order.
    pub figures: Vec<PathBuf>,
    /// Setup, frame-loop totals per stage, and the report.
    pub stages: Vec<Stage>,
}

/// The configurations of the paper's table, in its order.
pub const ABLATION: [Steps; 5] = Steps::PAPER;

/// A recording opened for processing: the rig, the parser, per-worker projection buffers
/// and what to write. Built once per run; frames go through [`FrameProcessor::read`]
/// ([`Frame`]), [`FrameProcessor::parse`] ([`ParsedFrame`]) and
/// [`FrameProcessor::process`] (project → boxes → refine → score → write), from any
/// number of threads.
pub struct FrameProcessor {
    recording: Recording,
    config: PipelineConfig,
    /// The 2D parser: the ONNX model or the recorded predictions. Behind a lock: a
    /// segmenter parses one frame at a time (the model batches the frame's views).
    segmenter: Mutex<Box<dyn Segmenter + Send>>,
    /// What the segmenter needs read ([`FrameNeeds::of`]).
    segmenter_needs: FrameNeeds,
    uses_model: bool,
    /// Idle per-worker buffers; a worker takes one per frame.
    scratch: Mutex<Vec<Scratch>>,
    template: FrameProjector,
    has_truth: bool,
    write_stages: bool,
    label_images: bool,
    figure_frames: BTreeSet<String>,
    views: Vec<LabelView>,
    /// Prepended to every output path (a recording's folder in a batch of recordings).
    prefix: String,
}

/// One worker's buffers.
struct Scratch {
    projector: FrameProjector,
    cloud: LabeledCloud,
    /// Where the cloud's points landed in their colour images (for the label images).
    hits: Hits,
    /// The label images' depth-and-label keys.
    keys: Vec<u32>,
    label_image: LabelImage,
    /// The multi-view vote's labels (`refine.vote = multi_view`; empty otherwise).
    voted: Vec<Label>,
    /// The parser's probability of each point's label (`refine.noise = probability`
    /// with a parser that gives probabilities; empty otherwise).
    label_probs: Vec<f32>,
}

impl std::fmt::Debug for FrameProcessor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameProcessor")
            .field("recording", &self.recording.root())
            .field("cameras", &self.rig().cameras.len())
            .field("model", &self.uses_model)
            .field("has_truth", &self.has_truth)
            .finish_non_exhaustive()
    }
}

impl FrameProcessor {
    /// Opens `opts.recording`: reads `rig.toml`, decides the parser (and loads the model),
    /// builds the projection tables. No frame gets a figure until
    /// [`FrameProcessor::with_figures`].
    ///
    /// # Errors
    /// `rig.toml` cannot be read or is invalid; the model or the ONNX Runtime library is
    /// missing; recorded predictions are asked for and the recording has none.
    pub fn open(opts: &RunOptions) -> Result<FrameProcessor> {
        let recording = Recording::open(&opts.recording)?;
        let rig = recording.rig();
        let recorded_present = recording.has_layer(Layer::Parsing);
        let use_model = match opts.parser {
            ParserChoice::Model => true,
            ParserChoice::Recorded => {
                if !recorded_present {
                    bail!(
                        "{}: no <camera>/parsing/ folders (recorded predictions); run with \
                         --parser model",
                        opts.recording.display()
                    );
                }
                false
            }
            ParserChoice::Auto => !recorded_present,
        };
        let segmenter: Box<dyn Segmenter + Send> = if use_model {
            let model = resolve_model(&opts.config)?;
            Box::new(load_segmenter(&opts.config, &model)?)
        } else {
            Box::new(RecordedSegmenter::new())
        };
        let segmenter_needs = FrameNeeds::of(segmenter.as_ref());
        let template = FrameProjector::new(rig).with_context(|| {
            format!(
                "{}: cannot project with this rig",
                recording.rig_path().display()
            )
        })?;
        let has_truth = recording.has_layer(Layer::DepthLabels);
        let views = rig
            .cameras
            .iter()
            .map(|c| LabelView::new(c, opts.config.backproject.stride))
            .collect();
        Ok(FrameProcessor {
            recording,
            config: opts.config.clone(),
            segmenter: Mutex::new(segmenter),
            segmenter_needs,
            uses_model: use_model,
            scratch: Mutex::new(Vec::new()),
            template,
            has_truth,
            write_stages: opts.write_stages,
            label_images: opts.label_images,
            figure_frames: BTreeSet::new(),
            views,
            prefix: String::new(),
        })
    }

    /// Draws a figure for these frames (none by default).
    pub fn with_figures(mut self, frames: BTreeSet<String>) -> FrameProcessor {
        self.figure_frames = frames;
        self
    }

    /// Writes this recording's files under `OUT/<prefix>` (`prefix` ends with `/`).
    pub fn with_prefix(mut self, prefix: String) -> FrameProcessor {
        self.prefix = prefix;
        self
    }

    /// The rig of the recording.
    pub fn rig(&self) -> &Rig {
        self.recording.rig()
    }

    /// The recording.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }

    /// Whether the recording has per-depth-pixel ground truth (`depth_labels/`).
    pub fn has_truth(&self) -> bool {
        self.has_truth
    }

    /// Whether the 2D labels come from the ONNX model.
    pub fn uses_model(&self) -> bool {
        self.uses_model
    }

    /// Whether the refinement or the box finder needs the points' camera colours (then the
    /// colour images are read, and sampled where the points land): foreign colours, and
    /// geometry mode's split between people and what is nobody's.
    fn needs_colours(&self) -> bool {
        self.config.refine.foreign_colour_density > 0.0 || self.config.boxes.uses_colours()
    }

    /// What [`FrameProcessor::read`] reads besides depth: what the segmenter needs, the
    /// colour images when the points' colours are wanted, the truth when there is one.
    pub fn needs(&self) -> FrameNeeds {
        FrameNeeds {
            depth: true,
            colour: self.segmenter_needs.colour || self.needs_colours(),
            parsing: self.segmenter_needs.parsing,
            truth: self.has_truth,
        }
    }

    /// Reads and decodes one frame's images (stage `read`).
    ///
    /// # Errors
    /// A file is missing, does not decode, or has another size than the rig says. Each
    /// error names the file.
    pub fn read(&self, frame: &str, stages: &mut Vec<Stage>) -> Result<Frame> {
        let (frame, took) = timed(|| Frame::read(&self.recording, frame, self.needs()))?;
        stages.push(Stage::new(
            "read",
            took,
            plural(self.rig().cameras.len(), "camera", "cameras"),
        ));
        Ok(frame)
    }

    /// Runs the parser on a frame (stage `parse`): the model on its colour images or the
    /// recorded predictions, through [`parse_frame`]. The colour images are kept only when
    /// the later stages use them.
    ///
    /// # Errors
    /// The parser fails, or failed on an earlier frame (its lock is poisoned).
    pub fn parse(&self, frame: Frame, stages: &mut Vec<Stage>) -> Result<ParsedFrame> {
        let (mut parsed, took) = timed(|| -> Result<ParsedFrame> {
            let mut segmenter = self
                .segmenter
                .lock()
                .map_err(|_| anyhow::anyhow!("the parser failed on an earlier frame"))?;
            parse_frame(frame, self.rig(), segmenter.as_mut())
        })?;
        if !self.needs_colours() {
            parsed.frame.colour = None;
        }
        let source = if self.uses_model { "model" } else { "recorded" };
        stages.push(Stage::new("parse", took, source.into()));
        Ok(parsed)
    }

    /// Reads, parses and processes one frame ([`FrameProcessor::read`],
    /// [`FrameProcessor::parse`], [`FrameProcessor::process`]).
    ///
    /// # Errors
    /// As those three.
    pub fn run_frame(
        &self,
        frame: &str,
        writer: &mut FrameWriter,
        stages: &mut Vec<Stage>,
    ) -> Result<FrameRecord> {
        let frame = self.read(frame, stages)?;
        let parsed = self.parse(frame, stages)?;
        self.process(&parsed, writer, stages)
    }

    /// Projects, finds boxes, refines, evaluates and writes one frame (stages `project`,
    /// `boxes`, `refine`, `eval`, `write`, `figure`); returns its record (outputs are
    /// filled in by the batch).
    ///
    /// # Errors
    /// The inputs do not fit the rig; file-mode boxes are missing; writing fails.
    pub fn process(
        &self,
        parsed: &ParsedFrame,
        writer: &mut FrameWriter,
        stages: &mut Vec<Stage>,
    ) -> Result<FrameRecord> {
        let frame = parsed.frame.stem.as_str();
        // Buffers for this worker, reused from frame to frame: no page faults on
        // megabytes of fresh memory per frame.
        let mut scratch = self
            .scratch
            .lock()
            .ok()
            .and_then(|mut p| p.pop())
            .unwrap_or_else(|| Scratch {
                projector: self.template.clone(),
                cloud: LabeledCloud::default(),
                hits: Hits::default(),
                keys: Vec::new(),
                label_image: LabelImage::filled(0, 0, Label::UNKNOWN),
                voted: Vec::new(),
                label_probs: Vec::new(),
            });
        let result = self.process_with(parsed, writer, stages, &mut scratch);
        if let Ok(mut p) = self.scratch.lock() {
            p.push(scratch);
        }
        result.with_context(|| format!("frame {frame}"))
    }

    fn process_with(
        &self,
        parsed: &ParsedFrame,
        writer: &mut FrameWriter,
        stages: &mut Vec<Stage>,
        scratch: &mut Scratch,
    ) -> Result<FrameRecord> {
        let Scratch {
            projector,
            cloud,
            hits,
            keys,
            label_image,
            voted,
            label_probs,
        } = scratch;
        let inputs = &parsed.frame;
        let frame = inputs.stem.as_str();
        let cfg = &self.config;
        let images: Vec<CameraImages<'_>> = inputs
            .depth
            .iter()
            .zip(&parsed.labels)
            .map(|(d, l)| CameraImages {
                depth_raw: &d.depth_mm,
                labels: l,
            })
            .collect();
        // Recorded label images carry no probabilities; the model's do.
        let with_probs = cfg.refine.noise == NoiseMode::Probability
            && parsed.labels.iter().any(|l| l.probs.is_some());
        let ((), took) = timed(|| -> Result<()> {
            if self.label_images || with_probs || self.needs_colours() {
                // The label images and the label probabilities reuse where the points
                // landed.
                projector.project_frame_keeping_hits(
                    &images,
                    &cfg.backproject.options(),
                    &cfg.project,
                    cloud,
                    hits,
                )?;
            } else {
                projector.project_frame_into(
                    &images,
                    &cfg.backproject.options(),
                    &cfg.project,
                    cloud,
                )?;
            }
            if with_probs {
                hits.label_probs_into(cloud, &images, label_probs);
            }
            if self.needs_colours() {
                let colour: Vec<&RgbImage> = inputs
                    .colour
                    .as_ref()
                    .context("the colour images were not read")?
                    .iter()
                    .collect();
                cloud.colors = Some(hits.colors_of(cloud, &colour));
            }
            Ok(())
        })?;
        let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
        stages.push(Stage::new("project", took, String::new()));
        let vote = cfg.refine.vote == VoteMode::MultiView;
        if vote {
            let ((), took) = timed(|| -> Result<()> {
                projector
                    .vote_labels(
                        &images,
                        &cfg.backproject.options(),
                        &cfg.project,
                        cloud,
                        voted,
                    )
                    .context("multi-view vote")?;
                Ok(())
            })?;
            stages.push(Stage::new("vote", took, String::new()));
        }

        let (boxes, took) = timed(|| -> Result<PersonBoxes> {
            let mut boxes = if cfg.boxes.mode == BoxMode::File {
                self.recording
                    .read_boxes(frame)
                    .context("boxes file (boxes.mode = file)")?
            } else {
                bodyseg_people::find_boxes(cloud, &cfg.boxes)?
            };
            boxes.frame = frame.to_string();
            Ok(boxes)
        })?;
        stages.push(Stage::new("boxes", took, String::new()));

        // The configurations: the configured one, and the paper's five when they are
        // scored, written or drawn.
        let figure = self.figure_frames.contains(frame);
        let ablation = inputs.truth.is_some() || self.write_stages || figure;
        let mut steps: Vec<Steps> = if ablation {
            ABLATION.to_vec()
        } else {
            Vec::new()
        };
        if !steps.contains(&cfg.refine.steps) {
            steps.push(cfg.refine.steps);
        }
        let (mut variants, took) = timed(|| {
            bodyseg_refine::refine_variants_with(
                cloud,
                PointEvidence {
                    voted: vote.then_some(voted.as_slice()),
                    label_probs: with_probs.then_some(label_probs.as_slice()),
                },
                &boxes.boxes,
                &cfg.refine,
                &steps,
                figure,
            )
            .context("refinement")
        })?;
        stages.push(Stage::new("refine", took, String::new()));
        let main = steps
            .iter()
            .position(|s| *s == cfg.refine.steps)
            .unwrap_or(steps.len() - 1);

        // The truth of every point, once: scored here, drawn in the figure.
        let ((gt, scores), took) = timed(|| -> Result<_> {
            let Some(truth) = &inputs.truth else {
                return Ok((None, None));
            };
            let gt = truth_labels(cloud, truth)?;
            let mut report = Report::new();
            for (s, labels) in steps.iter().zip(&variants.labels) {
                report.push(s.to_string(), bodyseg_eval::score_aligned(labels, &gt)?)?;
            }
            let scores: serde_json::Value = serde_json::from_str(&report.to_json()?)?;
            Ok((Some(gt), Some(scores)))
        })?;
        stages.push(Stage::new("eval", took, String::new()));

        let prefix = &self.prefix;
        let ((), took) = timed(|| -> Result<()> {
            // Unsynced: the batch syncs once at its end (see the `batch` module).
            let ply = PlyWriteOptions {
                format: PlyFormat::BinaryLittleEndian,
                durability: Durability::Renamed,
                ..Default::default()
            };
            if self.write_stages {
                // Before the labels are swapped: the projected cloud as it came.
                writer.write(&format!("{prefix}stages/{frame}/projected.ply"), |p| {
                    Ok(bodyseg_io::write_ply(p, cloud, &ply)?)
                })?;
            }
            // Each configuration's labels are swapped into the cloud for writing, so no
            // point is copied.
            with_labels(cloud, &mut variants.labels[main], |c| -> Result<()> {
                writer.write(&format!("{prefix}clouds/{frame}.ply"), |p| {
                    Ok(bodyseg_io::write_ply(p, c, &ply)?)
                })?;
                writer.write(&format!("{prefix}boxes/{frame}.json"), |p| {
                    Ok(bodyseg_io::write_boxes_with(
                        p,
                        &boxes,
                        Durability::Renamed,
                    )?)
                })?;
                if self.label_images {
                    for (index, (camera, view)) in
                        self.rig().cameras.iter().zip(&self.views).enumerate()
                    {
                        view.render_into(c, index as u8, Some(hits), keys, label_image);
                        writer.write(
                            &format!("{prefix}labels/{}/{frame}.png", camera.name),
                            |p| {
                                Ok(bodyseg_io::write_label_png_with(
                                    p,
                                    label_image,
                                    Durability::Renamed,
                                )?)
                            },
                        )?;
                    }
                }
                Ok(())
            })?;
            if self.write_stages {
                for (s, labels) in steps.iter().zip(variants.labels.iter_mut()) {
                    if *s == Steps::Reference {
                        continue; // The projected cloud.
                    }
                    with_labels(cloud, labels, |c| {
                        writer.write(&format!("{prefix}stages/{frame}/{s}.ply"), |p| {
                            Ok(bodyseg_io::write_ply(p, c, &ply)?)
                        })
                    })?;
                }
            }
            Ok(())
        })?;
        stages.push(Stage::new("write", took, String::new()));

        if figure {
            let ((), took) = timed(|| -> Result<()> {
                let image = self.figure(cloud, &boxes, &steps, &variants, gt.as_deref());
                writer.write(&format!("{prefix}figures/{frame}.png"), |p| {
                    Ok(bodyseg_io::write_rgb_png(
                        p,
                        image.width,
                        image.height,
                        &image.rgb,
                    )?)
                })?;
                Ok(())
            })?;
            stages.push(Stage::new("figure", took, String::new()));
        }

        Ok(FrameRecord {
            frame: frame.to_string(),
            config_hash: String::new(),
            points: cloud.len(),
            unknown,
            people: boxes.boxes.len(),
            outputs: Vec::new(),
            inputs: inputs.inputs.clone(),
            scores,
        })
    }

    /// The Figure-5 panels of a frame: input, clusters, each configuration of the
    /// ablation after Reference, and the truth when there is one.
    fn figure(
        &self,
        cloud: &LabeledCloud,
        boxes: &PersonBoxes,
        steps: &[Steps],
        variants: &RefinedVariants,
        truth: Option<&[Label]>,
    ) -> RgbImage {
        let view = panel_view(cloud, &boxes.boxes, self.rig());
        let mut panels = vec![FigurePanel::Labels {
            title: "INPUT".into(),
            labels: &cloud.labels,
        }];
        if steps.iter().any(|s| *s != Steps::Reference) {
            panels.push(FigurePanel::Clusters {
                title: "CLUSTERS".into(),
                clusters: &variants.clusters,
            });
        }
        for (s, labels) in steps.iter().zip(&variants.labels) {
            if *s != Steps::Reference {
                panels.push(FigurePanel::Labels {
                    title: s.to_string(),
                    labels,
                });
            }
        }
        if let Some(t) = truth {
            panels.push(FigurePanel::Labels {
                title: "TRUTH".into(),
                labels: t,
            });
        }
        figure_image(cloud, &view, &panels)
    }
}

/// Runs `f` on `cloud` with `labels` in place of its own (swapped in and back out: no
/// copy of the points).
fn with_labels<T>(
    cloud: &mut LabeledCloud,
    labels: &mut Vec<Label>,
    f: impl FnOnce(&LabeledCloud) -> T,
) -> T {
    std::mem::swap(&mut cloud.labels, labels);
    let out = f(cloud);
    std::mem::swap(&mut cloud.labels, labels);
    out
}

/// The ground-truth label of every point of `cloud`: its depth pixel's in `truth`.
fn truth_labels(cloud: &LabeledCloud, truth: &[LabelImage]) -> Result<Vec<Label>> {
    cloud
        .origins
        .iter()
        .map(|o| {
            truth
                .get(usize::from(o.camera))
                .and_then(|t| t.labels.get(o.pixel as usize))
                .copied()
                .with_context(|| {
                    format!(
                        "point of camera {} pixel {} has no ground truth",
                        o.camera, o.pixel
                    )
                })
        })
        .collect()
}

/// The frames of `opts` that get a figure.
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

/// This run's log (`run.json`): counts, failures and times; unlike the other outputs it
/// differs from run to run.
#[derive(Serialize)]
struct RunLog<'a> {
    recording: String,
    shard: String,
    frames: usize,
    processed: usize,
    skipped: usize,
    failed: &'a [crate::batch::FrameFailure],
    seconds: f64,
    frames_per_second: f64,
    stage_seconds: Vec<(&'static str, f64)>,
}

/// Runs a recording through every stage (see the module documentation for the outputs).
///
/// # Errors
/// The recording or its rig cannot be read, the model cannot be loaded, a frame asked for
/// does not exist, the output folder cannot be created, or the reports cannot be written.
/// A frame that fails is not an error: it is in [`BatchOutcome::failed`] (and `run.json`,
/// `report.md`).
pub fn run_recording(
    opts: &RunOptions,
    progress: &(dyn Fn(BatchProgress) + Sync),
) -> Result<RunSummary> {
    let (setup, took) = timed(|| -> Result<_> {
        let processor = FrameProcessor::open(opts)?;
        let all = processor.recording().frames()?.complete;
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
        Ok((frames, figures, processor))
    })?;
    let (frames, figures, processor) = setup;
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
    let outcome = crate::batch::run_batch(
        &jobs,
        &opts.out,
        opts.shard,
        &hash,
        opts.redo,
        progress,
        &|f: BatchFrame<'_, ()>, writer: &mut FrameWriter, stages: &mut Vec<Stage>| {
            processor.run_frame(f.id, writer, stages)
        },
    )?;
    let fps = outcome.frames_per_second();
    stages.extend(outcome.stage_lines());

    let ((report, written), took) =
        timed(|| write_reports(opts, &frames, &outcome, &resolved, fps))?;
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
        written,
        figures,
        stages,
    })
}

/// Merges the frames' scores and writes `report.md`, `report.json` (when there are
/// scores), `config.resolved.toml` and `run.json`; with a shard, the report files carry
/// its suffix (`report.shard-0-of-4.json`) so shards can share one folder.
pub(crate) fn write_reports(
    opts: &RunOptions,
    frames: &[String],
    outcome: &BatchOutcome,
    resolved: &str,
    fps: f64,
) -> Result<(Option<Report>, Vec<PathBuf>)> {
    let mut reports = Vec::new();
    for r in &outcome.records {
        if let Some(s) = &r.scores {
            let report = Report::from_json(&s.to_string())
                .with_context(|| format!("frame {}: scores in its record", r.frame))?;
            reports.push(report);
        }
    }
    let report = if reports.is_empty() {
        None
    } else {
        Some(Report::merge(&reports).context("merging the frames' scores")?)
    };
    let suffix = opts.shard.suffix();
    let mut written = Vec::new();
    if let Some(report) = &report {
        let path = opts.out.join(format!("report{suffix}.json"));
        write_text(&path, &report.to_json()?)?;
        written.push(path);
    }
    let md = report_markdown(opts, frames, outcome, report.as_ref());
    let path = opts.out.join(format!("report{suffix}.md"));
    write_text(&path, &md)?;
    written.push(path);
    let path = opts.out.join("config.resolved.toml");
    write_text(&path, resolved)?;
    written.push(path);
    let log = RunLog {
        recording: opts.recording.display().to_string(),
        shard: opts.shard.to_string(),
        frames: frames.len(),
        processed: outcome.processed,
        skipped: outcome.skipped,
        failed: &outcome.failed,
        seconds: outcome.elapsed.as_secs_f64(),
        frames_per_second: fps,
        stage_seconds: outcome
            .stage_totals
            .iter()
            .map(|(n, d)| (*n, d.as_secs_f64()))
            .collect(),
    };
    let path = opts.out.join(format!("run{suffix}.json"));
    write_text(&path, &serde_json::to_string_pretty(&log)?)?;
    written.push(path);
    Ok((report, written))
}

/// The figures among the frames' outputs (paths relative to the output folder).
fn figure_outputs(outcome: &BatchOutcome) -> impl Iterator<Item = &str> {
    outcome
        .records
        .iter()
        .flat_map(|r| &r.outputs)
        .map(|o| o.path.as_str())
        .filter(|p| p.starts_with("figures/"))
}

/// `report.md`: what ran, the paper's table, the failed frames and the figures. No times
/// (they are in `run.json`), so that a resumed run writes the same file.
fn report_markdown(
    opts: &RunOptions,
    frames: &[String],
    outcome: &BatchOutcome,
    report: Option<&Report>,
) -> String {
    let mut md = String::new();
    md.push_str("# bodyseg report\n\n");
    md.push_str(&format!(
        "Input `{}`: {} complete of {} in shard {} ({} frames selected in all).\n\n",
        opts.recording.display(),
        plural(outcome.records.len(), "frame", "frames"),
        outcome.records.len() + outcome.failed.len(),
        opts.shard,
        frames.len()
    ));
    match report {
        Some(r) => {
            md.push_str(
                "Per-point scores against the recording's ground truth (`depth_labels/`), \
                 all frames together; under each configuration its change from Reference.\n\n",
            );
            md.push_str(&r.to_markdown());
            md.push('\n');
        }
        None => md.push_str("No ground truth: no scores.\n\n"),
    }
    if !outcome.failed.is_empty() {
        md.push_str(&format!("## Failed frames ({})\n\n", outcome.failed.len()));
        for f in &outcome.failed {
            md.push_str(&format!("- `{}`: {}\n", f.frame, f.error));
        }
        md.push('\n');
    }
    let figures: Vec<&str> = figure_outputs(outcome).collect();
    if !figures.is_empty() {
        md.push_str("## Figures\n\n");
        for f in figures {
            md.push_str(&format!("![{f}]({f})\n"));
        }
    }
    md
}
