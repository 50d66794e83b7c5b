//! How well the box finder does on synthetic frames, against their true boxes (issue 6's
//! report, `examples/boxes_report.rs`, and its test `tests/boxes_on_synth.rs`).

use crate::projection_study::{camera_images, parsing_images};
use anyhow::Result;
use bodyseg_calib::BackProjectOptions;
use bodyseg_core::{LabeledCloud, PersonBox, RgbImage};
use bodyseg_people::{BoxesConfig, find_boxes};
pub use bodyseg_people::{FrameMatch, MATCH_IOU, match_boxes};
use bodyseg_project::{FrameProjector, ProjectConfig};
use bodyseg_synth::{Synth, SynthFrame};

/// Totals of one box-finder configuration over some frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoxStats {
    /// Frames scored.
    pub frames: usize,
    /// Frames where [`FrameMatch::is_good`].
    pub good_frames: usize,
    /// True people over all frames.
    pub people: usize,
    /// Of those, matched.
    pub matched: usize,
    /// Boxes found over all frames.
    pub found: usize,
    /// Sum of the best IoU of every true person (for the mean).
    pub iou_sum: f64,
    /// Indices of the frames that were not good (for inspection).
    pub bad_frames: Vec<usize>,
}

impl BoxStats {
    /// Good frames over frames.
    pub fn good_fraction(&self) -> f64 {
        self.good_frames as f64 / self.frames.max(1) as f64
    }

    /// Counts one frame, `index`, scored as `m`.
    pub fn add_frame(&mut self, index: usize, m: &FrameMatch) {
        self.frames += 1;
        self.good_frames += usize::from(m.is_good());
        if !m.is_good() {
            self.bad_frames.push(index);
            tracing::debug!(index, ?m, "frame not matched");
        }
        self.people += m.people;
        self.matched += m.matched;
        self.found += m.found;
        self.iou_sum += m.best_iou.iter().map(|&v| f64::from(v)).sum::<f64>();
    }

    /// Adds `other`'s counts; its bad frame indices are shifted by `frame_offset` (to tell
    /// sequences apart, e.g. `seed * 10_000`).
    pub fn absorb(&mut self, other: &BoxStats, frame_offset: usize) {
        self.frames += other.frames;
        self.good_frames += other.good_frames;
        self.people += other.people;
        self.matched += other.matched;
        self.found += other.found;
        self.iou_sum += other.iou_sum;
        self.bad_frames
            .extend(other.bad_frames.iter().map(|f| f + frame_offset));
    }

    /// Mean best IoU per true person.
    pub fn mean_iou(&self) -> f64 {
        self.iou_sum / self.people.max(1) as f64
    }
}

/// Frame `index` of `synth` and its cloud as the box studies see it: the written rig, the
/// simulated parser's predicted labels, DSA projection with default settings
/// (`projector` is `synth`'s written rig's).
///
/// # Errors
/// The projection fails.
pub fn study_frame(
    synth: &Synth,
    projector: &FrameProjector,
    index: usize,
) -> Result<(SynthFrame, LabeledCloud)> {
    let frame = synth.frame(index);
    let rig = synth.written_rig();
    let labels = parsing_images(rig, &frame);
    let images = camera_images(&frame, &labels);
    // The points' camera colours, as a coloured cloud (a PCD) would have them.
    let color: Vec<RgbImage> = rig
        .cameras
        .iter()
        .zip(&frame.cameras)
        .map(|(camera, images)| RgbImage {
            width: camera.color.width,
            height: camera.color.height,
            rgb: images.color.clone(),
        })
        .collect();
    let color: Vec<&RgbImage> = color.iter().collect();
    let cloud = projector.project_frame_colored(
        &images,
        &color,
        &BackProjectOptions::default(),
        &ProjectConfig::default(),
    )?;
    Ok((frame, cloud))
}

/// Projects frames `frames` of `synth` (written rig, the simulated parser's predicted
/// labels, DSA projection with default settings), finds boxes with each of `configs`,
/// and scores them against the frame's true boxes.
pub fn box_stats(
    synth: &Synth,
    frames: &[usize],
    configs: &[BoxesConfig],
) -> Result<Vec<BoxStats>> {
    let projector = FrameProjector::new(synth.written_rig())?;
    let mut stats = vec![BoxStats::default(); configs.len()];
    for &index in frames {
        let (frame, cloud) = study_frame(synth, &projector, index)?;
        for (cfg, s) in configs.iter().zip(&mut stats) {
            let found = find_boxes(&cloud, cfg)?;
            s.add_frame(index, &match_boxes(&frame.boxes.boxes, &found.boxes));
        }
    }
    Ok(stats)
}

/// One line describing a box for the box studies' tools: id, centre, size (full extents)
/// and yaw, metres and radians, and its top.
pub fn describe_box(b: &PersonBox) -> String {
    format!(
        "#{} c=({:.2},{:.2},{:.2}) size=({:.2},{:.2},{:.2}) yaw={:.2} top={:.2}",
        b.id,
        b.center_m[0],
        b.center_m[1],
        b.center_m[2],
        2.0 * b.half_extents_m[0],
        2.0 * b.half_extents_m[1],
        2.0 * b.half_extents_m[2],
        b.yaw_rad,
        b.center_m[2] + b.half_extents_m[2],
    )
}
