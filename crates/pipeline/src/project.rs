//! `bodyseg project`: one frame of a recording (rig.toml, depth and parsing PNGs) →
//! labelled world-frame PLY.

use crate::config::PipelineConfig;
use crate::frame::read_and_project;
use crate::outputs::{check_output_file, ply_options, write_stage};
use crate::stage::Stage;
use anyhow::{Context, Result};
use bodyseg_project::ProjectMode;
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
    /// (`out.ply` → `out.config.resolved.toml`).
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
    check_output_file(&opts.out, &["ply"], &[])?;
    let (rig, cloud, mut stages) = read_and_project(&opts.recording, &opts.frame, cfg)?;
    let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
    let mut points_per_camera = vec![0; rig.cameras.len()];
    for o in &cloud.origins {
        if let Some(n) = points_per_camera.get_mut(usize::from(o.camera)) {
            *n += 1;
        }
    }
    let mode = cfg.project.mode;
    let ply = ply_options(opts.ascii);
    let (resolved_config, write) =
        write_stage(&opts.out, cfg, opts.write_resolved_config, None, || {
            bodyseg_io::write_ply(&opts.out, &cloud, &ply).context("labelled cloud (--out)")
        })?;
    stages.push(write);

    Ok(ProjectSummary {
        points: cloud.len(),
        unknown,
        points_per_camera,
        mode,
        resolved_config,
        stages,
    })
}
