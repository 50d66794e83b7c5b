//! [`FrameProcessor`]: one recording's frames through every stage, frame by frame and from
//! any number of threads (`bodyseg run`, `bodyseg convert`):
//!
//! ```text
//! read (Frame) → parse (ParsedFrame, the Segmenter) → project (LabeledCloud; → vote with
//! refine.vote = multi_view) → boxes (PersonBoxes) → refine (the configured steps, and the
//! paper's five when scored, written or drawn) → score → write
//! ```
//!
//! With a segmenter that takes person regions (BlazePose), parse starts by finding the
//! people from depth (geometry-mode boxes, [`crate::regions`]): depth → people → parse →
//! project → boxes → refine. With `boxes.mode = "geometry"` those boxes are the
//! refinement's too; in `labels` mode (default) the boxes are found again on the projected
//! labels.

use crate::batch::{FrameRecord, FrameWriter};
use crate::config::PipelineConfig;
use crate::figure::{FigurePanel, LabelView, figure_image, panel_view};
use crate::frame::{Frame, FrameNeeds, ParsedFrame, parse_frame};
use crate::model::{ParserChoice, open_segmenter};
use crate::recording::{Layer, Recording};
use crate::sanity::{boxes_warnings, projected_scale_warning, warn_all};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result};
use bodyseg_calib::Rig;
use bodyseg_core::{Label, LabelImage, LabeledCloud, PersonBoxes, RgbImage};
use bodyseg_eval::Report;
use bodyseg_io::{Durability, PlyFormat, PlyWriteOptions};
use bodyseg_parsing::Segmenter;
use bodyseg_people::BoxMode;
use bodyseg_project::{FrameProjector, Hits};
use bodyseg_refine::{NoiseMode, PointEvidence, RefinedVariants, Steps, VoteMode};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// The configurations of the paper's table, in its order.
pub(crate) const ABLATION: [Steps; 5] = Steps::PAPER;

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
    scratch: Mutex<Vec<WorkerScratch>>,
    template: FrameProjector,
    has_truth: bool,
    write_stages: bool,
    label_images: bool,
    figure_frames: BTreeSet<String>,
    views: Vec<LabelView>,
    /// Prepended to every output path (a recording's folder in a batch of recordings).
    prefix: String,
    /// Where each processed frame's stages also go (`--rerun`); `None`: nowhere.
    sink: Option<Arc<dyn bodyseg_view::FrameSink>>,
}

/// One worker's buffers.
struct WorkerScratch {
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
    /// Opens the recording at `recording` ([`Recording::open`]), decides the parser (and
    /// loads the model) as `parser` says, builds the projection tables. As `bodyseg run`
    /// by default: label images drawn, no stage clouds, no figure, no output prefix (see
    /// the `with_*` methods).
    ///
    /// # Errors
    /// The recording cannot be opened; the model or the ONNX Runtime library is missing;
    /// recorded predictions are asked for and the recording has none.
    pub fn open(
        recording: &Path,
        config: &PipelineConfig,
        parser: ParserChoice,
    ) -> Result<FrameProcessor> {
        let recording = Recording::open(recording)?;
        let rig = recording.rig();
        let (segmenter, use_model) = open_segmenter(parser, &recording, config)?;
        let segmenter_needs = FrameNeeds::of(segmenter.as_ref());
        let template = FrameProjector::new(rig).with_context(|| {
            format!(
                "{}: cannot project with this rig",
                recording.rig_path().display()
            )
        })?;
        let has_truth = recording.has_layer(Layer::DepthLabels);
        let lacking = recording.cameras_lacking(Layer::DepthLabels);
        if !lacking.is_empty() && lacking.len() < rig.cameras.len() {
            tracing::warn!(
                "{}: no ground truth (depth_labels/) for camera {}: evaluation is off",
                recording.root().display(),
                lacking.join(", ")
            );
        }
        let views = rig
            .cameras
            .iter()
            .map(|c| LabelView::new(c, config.backproject.stride))
            .collect();
        Ok(FrameProcessor {
            recording,
            config: config.clone(),
            segmenter: Mutex::new(segmenter),
            segmenter_needs,
            uses_model: use_model,
            scratch: Mutex::new(Vec::new()),
            template,
            has_truth,
            write_stages: false,
            label_images: true,
            figure_frames: BTreeSet::new(),
            views,
            prefix: String::new(),
            sink: None,
        })
    }

    /// Also writes the projected cloud and one cloud per configuration of the ablation
    /// (`stages/<frame>/`; off by default).
    pub fn with_stage_clouds(mut self, on: bool) -> FrameProcessor {
        self.write_stages = on;
        self
    }

    /// Draws the refined labels back into each colour image (`labels/`; on by default).
    pub fn with_label_images(mut self, on: bool) -> FrameProcessor {
        self.label_images = on;
        self
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

    /// Also hands each processed frame's stages to `sink` (the `.rrd` writer of `--rerun`);
    /// the colour image files are then read and kept as stored (PNG or JPEG bytes).
    pub fn with_sink(mut self, sink: Option<Arc<dyn bodyseg_view::FrameSink>>) -> FrameProcessor {
        self.sink = sink;
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
    fn needs_colors(&self) -> bool {
        self.config.refine.foreign_color_density > 0.0 || self.config.boxes.uses_colors()
    }

    /// What [`FrameProcessor::read`] reads besides depth: what the segmenter needs, the
    /// colour images when the points' colours are wanted, the truth when there is one.
    pub fn needs(&self) -> FrameNeeds {
        FrameNeeds {
            depth: true,
            color: self.segmenter_needs.color || self.needs_colors(),
            // The view logs the files as they are (no decode for it).
            color_files: self.sink.is_some(),
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
            parse_frame(frame, self.rig(), segmenter.as_mut(), &self.config)
        })?;
        if !self.needs_colors() {
            parsed.frame.color = None;
        }
        let source = if self.uses_model { "model" } else { "recorded" };
        let summary = match &parsed.people {
            Some(people) => format!(
                "{source}, {} from depth",
                plural(people.boxes.len(), "person", "people")
            ),
            None => source.to_string(),
        };
        stages.push(Stage::new("parse", took, summary));
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
            .unwrap_or_else(|| WorkerScratch {
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
        scratch: &mut WorkerScratch,
    ) -> Result<FrameRecord> {
        let WorkerScratch {
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
        let images = parsed.camera_images();
        // Recorded label images carry no probabilities; the model's do.
        let with_probs = cfg.refine.noise == NoiseMode::Probability
            && parsed.labels.iter().any(|l| l.probs.is_some());
        let ((), took) = timed(|| -> Result<()> {
            if self.label_images || with_probs || self.needs_colors() {
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
            if self.needs_colors() {
                let color: Vec<&RgbImage> = inputs
                    .color
                    .as_ref()
                    .context("the colour images were not read")?
                    .iter()
                    .collect();
                cloud.colors = Some(hits.colors_of(cloud, &color));
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
            let mut boxes = match (&parsed.people, cfg.boxes.mode) {
                (_, BoxMode::File) => self
                    .recording
                    .read_boxes(frame)
                    .context("boxes file (boxes.mode = file)")?,
                // Found from depth before parsing, as geometry mode would find them now.
                (Some(people), BoxMode::Geometry) => people.clone(),
                _ => bodyseg_people::find_boxes(cloud, &cfg.boxes)?,
            };
            boxes.frame = frame.to_string();
            Ok(boxes)
        })?;
        let what = format!("frame {}{frame}", self.prefix);
        warn_all(projected_scale_warning(cloud, self.rig(), &what));
        warn_all(boxes_warnings(&boxes.boxes, cloud, &what));
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
                figure || self.sink.as_ref().is_some_and(|s| s.wants_clusters()),
            )
            .context("refinement")
        })?;
        stages.push(Stage::new("refine", took, String::new()));
        let main = steps
            .iter()
            .position(|s| *s == cfg.refine.steps)
            .unwrap_or(steps.len() - 1);

        // The truth of every point, once: scored here, drawn in the figure.
        let ((gt, scores, series), took) = timed(|| -> Result<_> {
            let Some(truth) = &inputs.truth else {
                return Ok((None, None, Vec::new()));
            };
            let gt = truth_labels(cloud, truth)?;
            let mut report = Report::new();
            for (s, labels) in steps.iter().zip(&variants.labels) {
                report.push(s.to_string(), bodyseg_eval::score_aligned(labels, &gt)?)?;
            }
            let scores: serde_json::Value = serde_json::from_str(&report.to_json()?)?;
            let scores = crate::batch::FrameScores::from_value(&scores);
            let series = match self.sink {
                Some(_) => crate::viewer::score_series(&report),
                None => Vec::new(),
            };
            Ok((Some(gt), Some(scores), series))
        })?;
        stages.push(Stage::new("eval", took, String::new()));

        let prefix = &self.prefix;
        // The label images drawn, kept for the sink.
        let mut drawn: Vec<LabelImage> = Vec::new();
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
                        if self.sink.is_some() {
                            drawn.push(label_image.clone());
                        }
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

        if let Some(sink) = &self.sink {
            let ((), took) = timed(|| -> Result<()> {
                let view = crate::viewer::view_frame(
                    parsed,
                    cloud,
                    &variants.labels[main],
                    &variants.clusters,
                    &boxes,
                    &drawn,
                    series,
                );
                sink.write_frame(&view).context("--rerun")?;
                Ok(())
            })?;
            stages.push(Stage::new("rerun", took, String::new()));
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
