//! `bodyseg refine`: labelled PLY + person boxes JSON → refined labelled PLY.

use crate::config::PipelineConfig;
use crate::floor::transformed;
use crate::outputs::{check_output_file, ply_options, read_labelled_ply, write_stage};
use crate::sanity::{boxes_warnings, cloud_scale_warning, warn_all};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result};
use bodyseg_core::Label;
use std::path::PathBuf;

/// What [`refine_file`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct RefineOptions {
    /// Labelled cloud to refine (PLY, FORMATS.md).
    pub cloud: PathBuf,
    /// Person boxes of the cloud's frame (JSON, FORMATS.md).
    pub boxes: PathBuf,
    /// Refined cloud to write (PLY). Replaced atomically; untouched when the command fails.
    pub out: PathBuf,
    /// The resolved configuration (defaults < file < flags), already validated.
    pub config: PipelineConfig,
    /// Write ASCII PLY instead of binary little-endian.
    pub ascii: bool,
    /// Also write the resolved configuration beside the output
    /// (`out.ply` → `out.config.resolved.toml`).
    pub write_resolved_config: bool,
}

/// What [`refine_file`] did.
#[derive(Clone, Debug)]
pub struct RefineSummary {
    /// Points in the cloud (the output has the same points in the same order).
    pub points: usize,
    /// Person boxes refined.
    pub people: usize,
    /// Points whose label differs between input and output.
    pub labels_changed: usize,
    /// The resolved configuration written beside the output, if any.
    pub resolved_config: Option<PathBuf>,
    /// Per stage (read, refine, write): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// Reads a labelled cloud and its person boxes, refines the labels
/// ([`bodyseg_refine::refine`]) and writes the refined cloud: the same points in the same
/// order, only labels (and so palette colours) changed.
///
/// # Errors
/// An input cannot be read or is malformed (the error names the file, and the vertex or
/// box at fault); the cloud has a NaN coordinate; writing fails. Nothing is written
/// unless every earlier step succeeded, and a failed write leaves `out` as it was.
pub fn refine_file(opts: &RefineOptions) -> Result<RefineSummary> {
    let cfg = &opts.config.refine;
    check_output_file(
        &opts.out,
        &["ply"],
        &[("--cloud", &opts.cloud), ("--boxes", &opts.boxes)],
    )?;
    let ((cloud, boxes), read) = timed(|| -> Result<_> {
        let cloud = read_labelled_ply(&opts.cloud).context("input cloud (--cloud)")?;
        let boxes = bodyseg_io::read_boxes(&opts.boxes).context("person boxes (--boxes)")?;
        Ok((cloud, boxes))
    })?;
    let mut stages = vec![Stage::new(
        "read",
        read,
        format!(
            "{}, {}",
            plural(cloud.len(), "point", "points"),
            plural(boxes.boxes.len(), "person box", "person boxes")
        ),
    )];
    tracing::info!(cloud = %opts.cloud.display(), points = cloud.len(), "read cloud");
    let what = opts.cloud.display().to_string();
    warn_all(cloud_scale_warning(&cloud, &what));
    // Boxes found in the floor's frame of a cloud that is not z up (`boxes --cloud` on a
    // camera's cloud) are compared with the cloud moved into that frame; the output keeps
    // the input's positions (only labels change).
    let in_world = boxes.world_from_cloud.map(|t| transformed(&cloud, &t));
    warn_all(boxes_warnings(
        &boxes.boxes,
        in_world.as_ref().unwrap_or(&cloud),
        &what,
    ));
    if cfg.noise == bodyseg_refine::NoiseMode::Probability {
        // A cloud file carries no parser probabilities (FORMATS.md's PLY has labels only).
        tracing::warn!(
            "refine.noise = \"probability\" on a cloud file: no parser probabilities, so every label counts as sure (the same as \"weighted\")"
        );
    }

    let (refined, took) = timed(|| {
        let mut refined =
            bodyseg_refine::refine(in_world.as_ref().unwrap_or(&cloud), &boxes.boxes, cfg)
                .with_context(|| format!("{}: cannot refine", opts.cloud.display()))?;
        if in_world.is_some() {
            refined.cloud.positions_m.clone_from(&cloud.positions_m);
        }
        anyhow::Ok(refined)
    })?;
    let labels_changed = Label::count_differing(&cloud.labels, &refined.cloud.labels);
    stages.push(Stage::new(
        "refine",
        took,
        format!(
            "{}, {} changed (steps {})",
            plural(boxes.boxes.len(), "person", "people"),
            plural(labels_changed, "label", "labels"),
            cfg.steps
        ),
    ));

    let ply = ply_options(opts.ascii);
    let (resolved_config, write) = write_stage(
        &opts.out,
        &opts.config,
        opts.write_resolved_config,
        None,
        || bodyseg_io::write_ply(&opts.out, &refined.cloud, &ply).context("refined cloud (--out)"),
    )?;
    stages.push(write);

    Ok(RefineSummary {
        points: cloud.len(),
        people: boxes.boxes.len(),
        labels_changed,
        resolved_config,
        stages,
    })
}
