//! `bodyseg boxes`: a cloud (PLY or PCD, in any frame) or a recording frame → person
//! boxes JSON (+ a top-view preview PNG).
//!
//! A cloud given as a file is taken in its own frame when that is z up (its floor, found
//! in any orientation, is level: bodyseg's own clouds, whose boxes stay exactly what they
//! were); otherwise (a camera's frame) it is moved into the frame of its floor (z up, the
//! floor at z = 0) before boxes are found, the boxes are written in that frame and the
//! JSON records the transform as `world_from_cloud`. A recording frame is in the world
//! frame of its rig.toml (z up by definition): no floor search.

use crate::config::PipelineConfig;
use crate::floor::{cloud_frame, likely_cause, transformed};
use crate::frame::read_and_project;
use crate::outputs::{check_output_file, read_cloud_file, write_stage};
use crate::recording::{Recording, check_stem};
use crate::sanity::{boxes_warnings, cloud_scale_warning, warn_all};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_core::{Class, LabeledCloud, PersonBox, PersonBoxes};
use bodyseg_io::FileLabels;
use bodyseg_people::{BoxMode, FloorHint};
use std::path::PathBuf;

/// Where [`boxes_file`] takes its cloud from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BoxesInput {
    /// A point cloud file: `.ply` or `.pcd` (PCL), metres, in any frame (its floor gives
    /// up); labels mode needs bodyseg's class ids in it, geometry mode none.
    Cloud(PathBuf),
    /// One frame of a recording: projected as `bodyseg project` does (labels and
    /// geometry modes), or its `boxes/<frame>.json` read (file mode).
    Recording {
        /// The recording folder.
        recording: PathBuf,
        /// The frame's file stem (`000012`).
        frame: String,
    },
}

/// What [`boxes_file`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct BoxesOptions {
    /// The input.
    pub input: BoxesInput,
    /// The resolved configuration (defaults < file < flags), already validated; its
    /// `[boxes]` section (and `[backproject]`, `[project]` for a recording) is used.
    pub config: PipelineConfig,
    /// Boxes JSON to write. Replaced atomically; untouched when the command fails.
    pub out: PathBuf,
    /// Top-view PNG of the cloud with the boxes drawn, if wanted.
    pub preview: Option<PathBuf>,
    /// Also write the resolved configuration beside the output
    /// (`out.ply` → `out.config.resolved.toml`).
    pub write_resolved_config: bool,
    /// The floor of a cloud given as a file, if the user knows it (`--ground`, `--up`);
    /// default: found. Not used for a recording frame (its rig gives the world frame).
    pub floor: FloorHint,
}

/// What [`boxes_file`] did.
#[derive(Clone, Debug)]
pub struct BoxesSummary {
    /// The boxes written.
    pub boxes: PersonBoxes,
    /// Per stage (read, floor, project, boxes, write): time and a one-line summary.
    pub stages: Vec<Stage>,
    /// What the user should know that is no error (a label field that is not ours,
    /// ignored), one line each.
    pub notes: Vec<String>,
}

/// Finds (or, in file mode, reads) the person boxes of one cloud or recording frame
/// ([`bodyseg_people::find_boxes`]) and writes them as boxes JSON (FORMATS.md), with the
/// resolved configuration beside them and, if asked, a top-view preview PNG (in the
/// boxes' frame). A cloud file in a frame that is not z up is moved into its floor's
/// frame first (module docs); no floor found, or no person: a warning naming the likely
/// cause (a camera's view without floor, a cloud in millimetres).
///
/// # Errors
/// File mode with `--cloud` (file boxes belong to a recording frame); the cloud cannot be
/// read (unknown extension, malformed PLY or PCD: the error names the file); labels mode
/// on a cloud without bodyseg's class ids (no `label` field, or another tool's ids: the
/// message names the fix, `--mode geometry`); `--ground` is not a plane; the frame's
/// images or boxes file cannot be read; writing fails. Nothing is written unless every
/// earlier step succeeded.
pub fn boxes_file(opts: &BoxesOptions) -> Result<BoxesSummary> {
    let cfg = &opts.config;
    let mode = cfg.boxes.mode;
    let input = match &opts.input {
        BoxesInput::Cloud(path) => Some(("--cloud", path.as_path())),
        BoxesInput::Recording { .. } => None,
    };
    check_output_file(&opts.out, &["json"], input.as_slice())?;
    let mut stages = Vec::new();
    let mut notes = Vec::new();
    let mut world_from_cloud = None;
    let mut floor_found = true;
    let (cloud, frame) = match &opts.input {
        BoxesInput::Cloud(path) => {
            if mode == BoxMode::File {
                bail!(
                    "boxes.mode = file reads REC/boxes/<frame>.json: give --recording and \
                     --frame instead of --cloud"
                );
            }
            let (file, took) = timed(|| read_cloud_file(path).context("input cloud (--cloud)"))?;
            stages.push(Stage::new(
                "read",
                took,
                format!(
                    "{}, {}",
                    plural(file.cloud.len(), "point", "points"),
                    path.display()
                ),
            ));
            let cloud = match (&file.labels, mode) {
                (FileLabels::Absent, BoxMode::Labels) => bail!(
                    "{}: the cloud has no 'label' field: labels mode needs bodyseg's class ids \
                     (0..=6, 255 = unknown); find the boxes without labels with --mode geometry, \
                     or label the cloud first (bodyseg project)",
                    path.display()
                ),
                (FileLabels::Foreign { .. }, BoxMode::Labels) => {
                    let element = if is_pcd(path) { "point" } else { "vertex" };
                    file.into_class_labels(element, path)
                        .context("labels mode (--mode labels)")?
                }
                (FileLabels::Foreign { index, value }, _) => {
                    notes.push(format!(
                        "{}: the label field holds ids that are not bodyseg's class ids \
                         (point {index}: {value}; PCL's segment ids?): ignored, geometry \
                         mode needs no labels",
                        path.display()
                    ));
                    file.cloud
                }
                _ => file.cloud,
            };
            let found = cloud_frame(
                &cloud.positions_m,
                &opts.floor,
                cfg.boxes.max_ground_tilt_deg,
                &path.display().to_string(),
            )?;
            stages.push(found.stage);
            floor_found = found.floor.is_some();
            world_from_cloud = found.world_from_cloud;
            let cloud = match &world_from_cloud {
                Some(t) => transformed(&cloud, t),
                None => cloud,
            };
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            (Some(cloud), stem)
        }
        BoxesInput::Recording { recording, frame } => {
            check_stem(frame)?;
            let cloud = if mode != BoxMode::File || opts.preview.is_some() {
                let (_, cloud, s) = read_and_project(recording, frame, cfg)?;
                stages.extend(s);
                Some(cloud)
            } else {
                None
            };
            (cloud, frame.clone())
        }
    };

    let (mut boxes, took) = timed(|| -> Result<PersonBoxes> {
        match (&opts.input, &cloud) {
            (BoxesInput::Recording { recording, frame }, _) if mode == BoxMode::File => {
                Ok(Recording::open(recording)?
                    .read_boxes(frame)
                    .context("boxes file (mode file)")?)
            }
            (_, Some(cloud)) => Ok(bodyseg_people::find_boxes(cloud, &cfg.boxes)
                .with_context(|| format!("frame {frame}"))?),
            (_, None) => bail!("no cloud to find boxes in"),
        }
    })?;
    if boxes.frame.is_empty() {
        boxes.frame = frame;
    }
    boxes.world_from_cloud = world_from_cloud;
    if let Some(cloud) = &cloud {
        let what = match &opts.input {
            BoxesInput::Cloud(path) => path.display().to_string(),
            BoxesInput::Recording { recording, frame } => {
                format!("{} frame {frame}", recording.display())
            }
        };
        if boxes.boxes.is_empty() && mode != BoxMode::File {
            // One warning, with the likely cause (an implausible unit first), rather than
            // the bare fact and a separate scale warning.
            tracing::warn!(
                "{what}: no person found (mode {}); likely cause: {}",
                mode.name(),
                likely_cause(&cloud.positions_m, floor_found)
            );
        } else {
            if matches!(opts.input, BoxesInput::Cloud(_)) {
                warn_all(cloud_scale_warning(cloud, &what));
            }
            warn_all(boxes_warnings(&boxes.boxes, cloud, &what));
        }
    }
    stages.push(Stage::new(
        "boxes",
        took,
        format!(
            "{} (mode {})",
            plural(boxes.boxes.len(), "person box", "person boxes"),
            mode.name()
        ),
    ));

    let preview = opts.preview.as_deref();
    let (_, write) = write_stage(&opts.out, cfg, opts.write_resolved_config, preview, || {
        if let (Some(path), Some(cloud)) = (preview, &cloud) {
            let (w, h, rgb) = top_view(cloud, &boxes.boxes);
            bodyseg_io::write_rgb_png(path, w, h, &rgb).context("preview (--preview)")?;
        }
        bodyseg_io::write_boxes(&opts.out, &boxes).context("person boxes (--out)")
    })?;
    stages.push(write);
    Ok(BoxesSummary {
        boxes,
        stages,
        notes,
    })
}

/// Whether `path` names a PCD file (by extension, any case).
fn is_pcd(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pcd"))
}

/// Pixels per metre of the preview.
const PREVIEW_PX_PER_M: f32 = 100.0;
/// Longest side of the preview, pixels (the scale shrinks for larger clouds).
const PREVIEW_MAX_PX: f32 = 1200.0;
/// Colour of the box outlines (yellow).
const BOX_COLOR: [u8; 3] = [255, 220, 0];

/// A top view of `cloud` (x right, y up; points coloured by the class palette, higher
/// points drawn over lower ones; background points grey, unknown ones dark grey) with the
/// outline of every box's footprint: `(width, height, RGB bytes)`.
pub fn top_view(cloud: &LabeledCloud, boxes: &[PersonBox]) -> (u32, u32, Vec<u8>) {
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    let corners: Vec<[[f32; 2]; 4]> = boxes.iter().map(footprint).collect();
    let all = cloud
        .positions_m
        .iter()
        .map(|p| [p[0], p[1]])
        .chain(corners.iter().flatten().copied());
    for p in all {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if !(lo[0].is_finite() && lo[1].is_finite()) {
        lo = [-1.0, -1.0];
        hi = [1.0, 1.0];
    }
    let margin = 0.2;
    let span = [hi[0] - lo[0] + 2.0 * margin, hi[1] - lo[1] + 2.0 * margin];
    let scale = PREVIEW_PX_PER_M.min(PREVIEW_MAX_PX / span[0].max(span[1]));
    let w = (span[0] * scale).ceil().max(1.0) as u32;
    let h = (span[1] * scale).ceil().max(1.0) as u32;
    let to_px = |p: [f32; 2]| {
        let u = (p[0] - lo[0] + margin) * scale;
        let v = (hi[1] + margin - p[1]) * scale;
        (u, v)
    };
    let mut rgb = vec![24u8; (w * h * 3) as usize];
    let mut top = vec![f32::NEG_INFINITY; (w * h) as usize];
    let put = |rgb: &mut [u8], u: i64, v: i64, c: [u8; 3]| {
        if u >= 0 && v >= 0 && (u as u32) < w && (v as u32) < h {
            let k = (v as usize) * w as usize + u as usize;
            rgb[3 * k..3 * k + 3].copy_from_slice(&c);
        }
    };
    for (p, label) in cloud.positions_m.iter().zip(&cloud.labels) {
        let (u, v) = to_px([p[0], p[1]]);
        let (u, v) = (u.floor() as i64, v.floor() as i64);
        if u < 0 || v < 0 || u >= i64::from(w) || v >= i64::from(h) {
            continue;
        }
        let k = v as usize * w as usize + u as usize;
        if p[2] < top[k] {
            continue;
        }
        top[k] = p[2];
        let c = match label.class() {
            Some(Class::Background) => [110, 110, 110],
            Some(c) => c.color().map(|x| x.saturating_add(60)),
            None => [60, 60, 60],
        };
        put(&mut rgb, u, v, c);
    }
    for quad in &corners {
        for i in 0..4 {
            let (a, b) = (to_px(quad[i]), to_px(quad[(i + 1) % 4]));
            let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
            for s in 0..=steps {
                let t = s as f32 / steps as f32;
                let u = a.0 + t * (b.0 - a.0);
                let v = a.1 + t * (b.1 - a.1);
                put(&mut rgb, u.floor() as i64, v.floor() as i64, BOX_COLOR);
            }
        }
    }
    (w, h, rgb)
}

/// The corners of a box's footprint, world x y.
fn footprint(b: &PersonBox) -> [[f32; 2]; 4] {
    let (s, c) = b.yaw_rad.sin_cos();
    let [hx, hy, _] = b.half_extents_m;
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(a, k): (f32, f32)| {
        let (u, v) = (a * hx, k * hy);
        [b.center_m[0] + c * u - s * v, b.center_m[1] + s * u + c * v]
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::{Label, PointOrigin};

    #[test]
    fn preview_draws_points_and_box_outlines() {
        let cloud = LabeledCloud {
            positions_m: vec![[0.0, 0.0, 1.0], [0.5, 0.5, 1.0]],
            labels: vec![Label::from(Class::Head), Label::UNKNOWN],
            colors: None,
            origins: vec![
                PointOrigin {
                    camera: 0,
                    pixel: 0
                };
                2
            ],
        };
        let b = PersonBox {
            id: 0,
            center_m: [0.0, 0.0, 0.9],
            half_extents_m: [0.3, 0.2, 0.9],
            yaw_rad: 0.3,
        };
        let (w, h, rgb) = top_view(&cloud, &[b]);
        assert_eq!(rgb.len(), (w * h * 3) as usize);
        let count = |c: [u8; 3]| rgb.chunks_exact(3).filter(|p| *p == c).count();
        assert!(count(BOX_COLOR) > 100, "box outline drawn");
        assert_eq!(count(Class::Head.color().map(|x| x.saturating_add(60))), 1);
    }
}
