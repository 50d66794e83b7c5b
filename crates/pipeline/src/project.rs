//! `bodyseg project`: one frame of a recording (rig.toml, depth and parsing PNGs) →
//! labelled world-frame PLY.

use crate::config::PipelineConfig;
use crate::fs::write_text;
use crate::recording::{Layer, Recording, check_stem};
use crate::refine::resolved_config_path;
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result};
use bodyseg_calib::Rig;
use bodyseg_core::{LabelImage, LabeledCloud, RgbImage};
use bodyseg_io::{DepthImage, PlyFormat, PlyWriteOptions};
use bodyseg_project::{CameraImages, FrameProjector, ProjectMode};
use std::path::PathBuf;

/// What [`project_file`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct ProjectOptions {
    /// The recording folder (FORMATS.md, "Recording"): `rig.toml`, and per camera
    /// `<camera>/depth/<frame>.png` and `<camera>/parsing/<frame>.png`.
    pub recording: PathBuf,
    /// The frame's file stem (`000012`), without folder or extension.
    pub frame: String,
    /// The resolved configuration (defaults < file < flags), already validated; its
    /// `[backproject]` and `[project]` sections are used.
    pub config: PipelineConfig,
    /// Labelled cloud to write (PLY). Replaced atomically; untouched when the command
    /// fails.
    pub out: PathBuf,
    /// Write ASCII PLY instead of binary little-endian.
    pub ascii: bool,
    /// Also write the resolved configuration beside the output
    /// ([`resolved_config_path`]).
    pub write_resolved_config: bool,
}

/// What [`project_file`] did.
#[derive(Clone, Debug)]
pub struct ProjectSummary {
    /// Points written (every back-projected depth point, labelled or not).
    pub points: usize,
    /// Points whose label is `unknown` (255).
    pub unknown: usize,
    /// Points per camera, rig order.
    pub points_per_camera: Vec<usize>,
    /// The mode that ran.
    pub mode: ProjectMode,
    /// The resolved configuration written beside the output, if any.
    pub resolved_config: Option<PathBuf>,
    /// Per stage (read, project, write): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// One camera's images, read and checked against the rig.
struct CameraFiles {
    depth: DepthImage,
    labels: LabelImage,
    /// Read only when the points' colours are wanted (geometry-mode boxes).
    colour: Option<RgbImage>,
}

/// Reads and checks one camera's depth and parsing PNGs.
fn read_camera(rec: &Recording, index: usize, opts: &ProjectOptions) -> Result<CameraFiles> {
    let (depth, _) = rec.read_depth(index, &opts.frame)?;
    let (labels, _) = rec.read_labels(index, Layer::Parsing, &opts.frame)?;
    let colour = if opts.config.boxes.uses_colours() {
        Some(rec.read_colour(index, &opts.frame)?.0)
    } else {
        None
    };
    Ok(CameraFiles {
        depth,
        labels,
        colour,
    })
}

/// The read and project stages of [`project_file`] (also `bodyseg boxes --recording`):
/// the rig, the labelled cloud and the two stages' records.
pub(crate) fn read_and_project(opts: &ProjectOptions) -> Result<(Rig, LabeledCloud, Vec<Stage>)> {
    check_stem(&opts.frame)?;
    let cfg = &opts.config;
    let ((rig, cameras), read) = timed(|| -> Result<_> {
        let rec = Recording::open(&opts.recording)?;
        let cameras = (0..rec.rig().cameras.len())
            .map(|i| read_camera(&rec, i, opts))
            .collect::<Result<Vec<_>>>()?;
        Ok((rec.rig().clone(), cameras))
    })?;
    let mut stages = vec![Stage::new(
        "read",
        read,
        format!(
            "{}, frame {}",
            plural(rig.cameras.len(), "camera", "cameras"),
            opts.frame
        ),
    )];
    tracing::info!(recording = %opts.recording.display(), frame = %opts.frame, "read frame");

    let (cloud, took) = timed(|| {
        let images: Vec<CameraImages<'_>> = cameras
            .iter()
            .map(|c| CameraImages {
                depth_raw: &c.depth.depth_mm,
                labels: &c.labels,
            })
            .collect();
        let colour: Option<Vec<&RgbImage>> = cameras.iter().map(|c| c.colour.as_ref()).collect();
        let context = || format!("{}: frame {}", opts.recording.display(), opts.frame);
        let projector = FrameProjector::new(&rig).with_context(context)?;
        let backproject = cfg.backproject.options();
        match colour {
            // Geometry-mode boxes split people from what is nobody's by colour too.
            Some(colour) => {
                projector.project_frame_coloured(&images, &colour, &backproject, &cfg.project)
            }
            None => projector.project_frame(&images, &backproject, &cfg.project),
        }
        .with_context(context)
    })?;
    let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
    let mode = cfg.project.mode;
    let mode_name = match mode {
        ProjectMode::Naive => "naive",
        ProjectMode::Dsa => "dsa",
    };
    stages.push(Stage::new(
        "project",
        took,
        format!(
            "{}, {} unknown (mode {mode_name})",
            plural(cloud.len(), "point", "points"),
            unknown
        ),
    ));

    Ok((rig, cloud, stages))
}

/// Projects the labels of one frame of a recording onto its depth points
/// ([`bodyseg_project::project_frame`]) and writes the labelled world-frame cloud (PLY,
/// FORMATS.md): cameras in rig order, pixels row-major, every back-projected point kept
/// (those no label reaches are `unknown`).
///
/// # Errors
/// The frame stem is a path; `rig.toml` cannot be read or is invalid; a camera folder of
/// the rig is missing (the error names the folder); a depth or parsing PNG is missing,
/// not a PNG, of the wrong pixel format (an 8-bit depth PNG) or of a size other than the
/// rig's sensor (the error names the file and both sizes); writing fails. Nothing is
/// written unless every earlier step succeeded.
pub fn project_file(opts: &ProjectOptions) -> Result<ProjectSummary> {
    let cfg = &opts.config;
    let (rig, cloud, mut stages) = read_and_project(opts)?;
    let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
    let mut points_per_camera = vec![0; rig.cameras.len()];
    for o in &cloud.origins {
        if let Some(n) = points_per_camera.get_mut(usize::from(o.camera)) {
            *n += 1;
        }
    }
    let mode = cfg.project.mode;
    let ply = PlyWriteOptions {
        format: if opts.ascii {
            PlyFormat::Ascii
        } else {
            PlyFormat::BinaryLittleEndian
        },
        ..Default::default()
    };
    let resolved_config = opts
        .write_resolved_config
        .then(|| resolved_config_path(&opts.out));
    let ((), took) = timed(|| -> Result<()> {
        bodyseg_io::write_ply(&opts.out, &cloud, &ply).context("labelled cloud (--out)")?;
        if let Some(path) = &resolved_config {
            write_text(path, &cfg.resolved_toml()?).context("resolved configuration")?;
        }
        Ok(())
    })?;
    let mut written = opts.out.display().to_string();
    if let Some(path) = &resolved_config {
        written.push_str(&format!(", {}", path.display()));
    }
    stages.push(Stage::new("write", took, written));

    Ok(ProjectSummary {
        points: cloud.len(),
        unknown,
        points_per_camera,
        mode,
        resolved_config,
        stages,
    })
}
