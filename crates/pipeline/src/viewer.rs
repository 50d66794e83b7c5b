//! The Rerun view of a run (`--rerun OUT.rrd`, bodyseg-view): the writer opened for one
//! recording, handed to the [`crate::FrameProcessor`] as its frame sink, finished after
//! the frame loop. Built with the `rerun` feature; without it [`RerunOutput::create`]
//! says how to build.

use crate::batch::{BatchOutcome, BatchProgress, FrameFn, Shard, run_batch};
use crate::frame::{Frame, ParsedFrame};
use crate::recording::Recording;
use crate::stage::{Stage, timed};
use anyhow::Result;
use bodyseg_core::{Label, LabelImage, LabeledCloud, PersonBoxes};
use bodyseg_eval::Report;
use bodyseg_io::ColorFileFormat;
use bodyseg_view::{
    CameraView, CloudView, ColorFileView, DepthView, FrameSink, ImageFileFormat, ViewFrame,
};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The file of a recording's time stamps (`stem,nanoseconds`, or what `bodyseg import ros2` writes).
#[cfg(feature = "rerun")]
pub(crate) const STAMPS_FILE: &str = "stamps.csv";

/// An open `.rrd` file for one recording.
pub(crate) struct RerunOutput {
    #[cfg(feature = "rerun")]
    writer: Arc<bodyseg_view::ViewWriter>,
}

impl RerunOutput {
    /// Creates `path` for `recording`, whose frames (all of them, in order: their index is
    /// the `frame` timeline) are `frames`; reads `stamps.csv` when the recording has one.
    /// `clusters`: also log the clusters layer.
    ///
    /// # Errors
    /// Built without the `rerun` feature; the stamps file is malformed; the file cannot be
    /// created.
    #[cfg(feature = "rerun")]
    pub(crate) fn create(
        path: &Path,
        recording: &Recording,
        frames: &[String],
        clusters: bool,
    ) -> Result<Self> {
        use anyhow::Context;
        let stamps_path = recording.root().join(STAMPS_FILE);
        let stamps = if stamps_path.is_file() {
            let text = bodyseg_io::read_text(&stamps_path)?;
            bodyseg_view::parse_stamps(&text, &stamps_path)?
        } else {
            Vec::new()
        };
        let name = recording
            .root()
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "recording".into());
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            bodyseg_io::create_folder(parent)?;
        }
        let writer =
            bodyseg_view::ViewWriter::create(path, &name, recording.rig(), frames, &stamps)
                .with_context(|| format!("--rerun {}", path.display()))?
                .with_clusters(clusters);
        Ok(RerunOutput {
            writer: Arc::new(writer),
        })
    }

    /// Without the `rerun` feature: an error saying how to build.
    ///
    /// # Errors
    /// Always.
    #[cfg(not(feature = "rerun"))]
    pub(crate) fn create(
        path: &Path,
        _recording: &Recording,
        _frames: &[String],
        _clusters: bool,
    ) -> Result<Self> {
        anyhow::bail!(
            "--rerun {}: this bodyseg was built without Rerun support; build it with \
             `cargo build --release --features rerun`",
            path.display()
        )
    }

    /// The sink the frame loop logs into.
    pub(crate) fn sink(&self) -> Arc<dyn FrameSink> {
        #[cfg(feature = "rerun")]
        {
            self.writer.clone()
        }
        #[cfg(not(feature = "rerun"))]
        {
            Arc::new(NoSink)
        }
    }

    /// Flushes and closes the file; its path.
    ///
    /// # Errors
    /// The flush or the rename fails.
    pub(crate) fn finish(&self) -> Result<PathBuf> {
        #[cfg(feature = "rerun")]
        {
            Ok(self.writer.finish()?)
        }
        #[cfg(not(feature = "rerun"))]
        {
            anyhow::bail!("built without Rerun support")
        }
    }
}

/// [`run_batch`] of a recording's frames (`run`, `convert`) with its Rerun view, if one
/// is written: a Rerun file has every frame, so none is skipped as complete then, and
/// the file is finished after the loop. Adds the loop's stage lines, then `rerun`, to
/// `stages`; returns the outcome and the `.rrd` file written.
// The arguments of `run_batch`, then the view and the stage list: a struct of them would
// only be unpacked again.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_batch_with_rerun<J: Sync>(
    jobs: &[(String, J)],
    out: &Path,
    shard: Shard,
    config_hash: &str,
    redo: bool,
    rerun: Option<&RerunOutput>,
    progress: &(dyn Fn(BatchProgress) + Sync),
    process: &FrameFn<'_, J>,
    stages: &mut Vec<Stage>,
) -> Result<(BatchOutcome, Option<PathBuf>)> {
    let redo = redo || rerun.is_some();
    let outcome = run_batch(jobs, out, shard, config_hash, redo, progress, process)?;
    stages.extend(outcome.stage_lines());
    let rrd = match rerun {
        Some(rerun) => {
            let (path, took) = timed(|| rerun.finish())?;
            stages.push(Stage::new("rerun", took, path.display().to_string()));
            Some(path)
        }
        None => None,
    };
    Ok((outcome, rrd))
}

/// A sink that drops every frame (never built: [`RerunOutput::create`] fails first
/// without the feature).
#[cfg(not(feature = "rerun"))]
struct NoSink;

#[cfg(not(feature = "rerun"))]
impl FrameSink for NoSink {
    fn write_frame(
        &self,
        _frame: &bodyseg_view::ViewFrame<'_>,
    ) -> Result<(), bodyseg_view::ViewError> {
        Ok(())
    }
}

/// A frame's scores as Rerun series: per configuration `<name>/biou`, `<name>/miou` and
/// `<name>/iou/<class>` for each class present (the metrics that exist).
pub(crate) fn score_series(report: &Report) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for c in report.configurations() {
        let m = c.metrics();
        let name = c.name();
        if let Some(v) = m.biou {
            out.push((format!("{name}/biou"), v));
        }
        if let Some(v) = m.miou {
            out.push((format!("{name}/miou"), v));
        }
        for k in &m.per_class {
            if let Some(v) = k.iou {
                out.push((format!("{name}/iou/{}", k.class.name()), v));
            }
        }
    }
    out
}

/// Each camera of `frame` as the view takes it: its colour and depth images, the parser's
/// labels (`parsed`) and the refined labels drawn back (`drawn`), where present.
pub(crate) fn camera_views<'a>(
    frame: &'a Frame,
    parsed: &'a [LabelImage],
    drawn: &'a [LabelImage],
) -> Vec<CameraView<'a>> {
    (0..frame.depth.len())
        .map(|i| CameraView {
            color: frame.color.as_ref().and_then(|c| c.get(i)),
            color_file: frame
                .color_files
                .as_ref()
                .and_then(|c| c.get(i))
                .map(|f| ColorFileView {
                    bytes: &f.bytes,
                    format: match f.format {
                        ColorFileFormat::Png => ImageFileFormat::Png,
                        ColorFileFormat::Jpeg => ImageFileFormat::Jpeg,
                    },
                }),
            depth: frame.depth.get(i).map(|d| DepthView {
                width: d.width,
                height: d.height,
                raw: &d.depth_mm,
            }),
            parsed: parsed.get(i),
            refined: drawn.get(i),
        })
        .collect()
}

/// A processed frame as the sink takes it: the images read (colour, depth, the parser's
/// labels), the projected cloud (`cloud` with its own labels), the refined labels on the
/// same points, the clusters, the boxes, the label images drawn (`drawn`, one per camera or
/// none) and the scores.
pub(crate) fn view_frame<'a>(
    parsed: &'a ParsedFrame,
    cloud: &'a LabeledCloud,
    refined: &'a [Label],
    clusters: &'a [Option<(u32, u32)>],
    boxes: &'a PersonBoxes,
    drawn: &'a [LabelImage],
    scores: Vec<(String, f64)>,
) -> ViewFrame<'a> {
    let frame = &parsed.frame;
    let cameras = camera_views(frame, &parsed.labels, drawn);
    ViewFrame {
        stem: &frame.stem,
        cameras,
        projected: Some(CloudView {
            positions_m: &cloud.positions_m,
            labels: &cloud.labels,
        }),
        refined: Some(CloudView {
            positions_m: &cloud.positions_m,
            labels: refined,
        }),
        clusters: (clusters.len() == cloud.len()).then_some(clusters),
        boxes: Some(&boxes.boxes),
        scores,
    }
}
