//! `bodyseg view`: a Rerun recording (`.rrd`) of a finished run, from its files, without
//! recomputing: the recording's images (colour, depth, `parsing/` when it has one) and
//! the run's outputs (`clouds/<frame>.ply`, `stages/<frame>/projected.ply` when written,
//! `boxes/<frame>.json`, `labels/<camera>/<frame>.png`, the scores of
//! `frames/<frame>.json`). Frames the run has no cloud for are left out; the DBSCAN
//! clusters are not in a run's files, so the file has none.

use crate::frame::{Frame, FrameNeeds};
use crate::recording::{Layer, Recording};
use crate::stage::{Stage, plural, timed};
use crate::viewer::{RerunOutput, camera_views, score_series};
use anyhow::{Context, Result, bail};
use bodyseg_core::{LabelImage, LabeledCloud, PersonBoxes};
use bodyseg_eval::Report;
use bodyseg_view::{CloudView, ViewFrame};
use std::path::{Path, PathBuf};

/// What [`view_run`] reads and writes.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The recording folder.
    pub recording: PathBuf,
    /// The run's output folder (`bodyseg run --out`).
    pub run: PathBuf,
    /// The `.rrd` file to write.
    pub rerun: PathBuf,
}

/// What [`view_run`] did.
#[derive(Debug)]
pub struct ViewSummary {
    /// Frames logged.
    pub frames: usize,
    /// The file written.
    pub written: PathBuf,
    /// One line per stage.
    pub stages: Vec<Stage>,
}

/// One frame's files of a run, read.
struct RunFrame {
    refined: LabeledCloud,
    projected: Option<LabeledCloud>,
    boxes: Option<PersonBoxes>,
    drawn: Vec<LabelImage>,
    scores: Vec<(String, f64)>,
}

/// Writes the Rerun file of a finished run (see the module documentation).
///
/// # Errors
/// The recording cannot be opened, the run folder holds no cloud of it, a file of a frame
/// cannot be read (named), the `.rrd` cannot be written; built without the `rerun` feature.
pub fn view_run(opts: &ViewOptions) -> Result<ViewSummary> {
    let ((recording, all, frames), took) = timed(|| -> Result<_> {
        let recording = Recording::open(&opts.recording)?;
        bodyseg_io::require_folder(&opts.run, "run")?;
        let all = recording.frames()?.complete;
        let frames: Vec<String> = all
            .iter()
            .filter(|f| cloud_path(&opts.run, f).is_file())
            .cloned()
            .collect();
        if frames.is_empty() {
            bail!(
                "{}: no cloud of a frame of {} (clouds/<frame>.ply)",
                opts.run.display(),
                opts.recording.display()
            );
        }
        Ok((recording, all, frames))
    })?;
    let mut stages = vec![Stage::new(
        "setup",
        took,
        plural(frames.len(), "frame", "frames"),
    )];
    let needs = FrameNeeds {
        depth: true,
        color: false,
        // Logged as stored (PNG or JPEG bytes), not decoded.
        color_files: recording.has_layer(Layer::Color),
        parsing: recording.has_layer(Layer::Parsing),
        truth: false,
    };
    let ((), took) = timed(|| -> Result<()> {
        let out = RerunOutput::create(&opts.rerun, &recording, &all, false)?;
        let sink = out.sink();
        for stem in &frames {
            let images = Frame::read(&recording, stem, needs)?;
            let files = read_run_frame(&opts.run, &recording, stem)?;
            let view = frame_view(&images, &files);
            sink.write_frame(&view)
                .with_context(|| format!("frame {stem}: --rerun"))?;
        }
        out.finish()?;
        Ok(())
    })?;
    stages.push(Stage::new("rerun", took, opts.rerun.display().to_string()));
    Ok(ViewSummary {
        frames: frames.len(),
        written: opts.rerun.clone(),
        stages,
    })
}

fn cloud_path(run: &Path, stem: &str) -> PathBuf {
    run.join("clouds").join(format!("{stem}.ply"))
}

/// The run's files of one frame; the optional ones when they exist.
fn read_run_frame(run: &Path, recording: &Recording, stem: &str) -> Result<RunFrame> {
    let refined = bodyseg_io::read_ply(&cloud_path(run, stem))?;
    let projected_path = run.join("stages").join(stem).join("projected.ply");
    let projected = match projected_path.is_file() {
        true => Some(bodyseg_io::read_ply(&projected_path)?),
        false => None,
    };
    let boxes_path = run.join("boxes").join(format!("{stem}.json"));
    let boxes = match boxes_path.is_file() {
        true => Some(bodyseg_io::read_boxes(&boxes_path)?),
        false => None,
    };
    let mut drawn = Vec::new();
    for camera in recording.cameras() {
        let path = run.join("labels").join(camera).join(format!("{stem}.png"));
        if !path.is_file() {
            drawn.clear(); // All cameras or none: the views are by camera index.
            break;
        }
        drawn.push(bodyseg_io::read_label_png(&path)?);
    }
    let record_path = run.join("frames").join(format!("{stem}.json"));
    let scores = if record_path.is_file() {
        let text = bodyseg_io::read_text(&record_path)?;
        let record: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("{}: not JSON", record_path.display()))?;
        match record.get("scores") {
            Some(s) if !s.is_null() => {
                let report = Report::from_json(&s.to_string())
                    .with_context(|| format!("{}: scores", record_path.display()))?;
                score_series(&report)
            }
            _ => Vec::new(),
        }
    } else {
        Vec::new()
    };
    Ok(RunFrame {
        refined,
        projected,
        boxes,
        drawn,
        scores,
    })
}

fn frame_view<'a>(images: &'a Frame, files: &'a RunFrame) -> ViewFrame<'a> {
    let cameras = camera_views(
        images,
        images.parsing.as_deref().unwrap_or(&[]),
        &files.drawn,
    );
    let cloud = |c: &'a LabeledCloud| CloudView {
        positions_m: &c.positions_m,
        labels: &c.labels,
    };
    ViewFrame {
        stem: &images.stem,
        cameras,
        projected: files.projected.as_ref().map(cloud),
        refined: Some(cloud(&files.refined)),
        clusters: None,
        boxes: files.boxes.as_ref().map(|b| b.boxes.as_slice()),
        scores: files.scores.clone(),
    }
}
