//! How well the box finder does on synthetic frames, against their true boxes (issue 6's
//! report, `examples/boxes_report.rs`, and its test `tests/boxes_on_synth.rs`).

use crate::projection_study::{camera_images, parsing_images};
use anyhow::Result;
use bodyseg_calib::BackProjectOptions;
use bodyseg_core::{LabeledCloud, PersonBox};
use bodyseg_people::{BoxesConfig, box_iou, find_boxes};
use bodyseg_project::{FrameProjector, ProjectConfig};
use bodyseg_synth::{Synth, SynthFrame};

/// A found box matches a true one when their IoU is at least this (issue 6).
pub const MATCH_IOU: f32 = 0.5;

/// How one frame's boxes compare with the truth.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameMatch {
    /// True people matched by exactly one box (IoU ≥ [`MATCH_IOU`]) that matches no other.
    pub matched: usize,
    /// True people.
    pub people: usize,
    /// Boxes found.
    pub found: usize,
    /// Per true person, the best IoU of any found box (0 when none overlaps).
    pub best_iou: Vec<f32>,
}

impl FrameMatch {
    /// Every true person matched by exactly one box, and no extra box.
    pub fn is_good(&self) -> bool {
        self.matched == self.people && self.found == self.people
    }
}

/// Compares `found` with `truth`: a true person is matched when exactly one found box
/// has IoU ≥ [`MATCH_IOU`] with it and that box has IoU ≥ [`MATCH_IOU`] with no other
/// true person.
pub fn match_boxes(truth: &[PersonBox], found: &[PersonBox]) -> FrameMatch {
    let iou: Vec<Vec<f32>> = truth
        .iter()
        .map(|t| found.iter().map(|f| box_iou(t, f)).collect())
        .collect();
    let mut matched = 0;
    for row in &iou {
        let hits: Vec<usize> = (0..found.len()).filter(|&j| row[j] >= MATCH_IOU).collect();
        if let [j] = hits[..] {
            let claims = iou.iter().filter(|r| r[j] >= MATCH_IOU).count();
            matched += usize::from(claims == 1);
        }
    }
    FrameMatch {
        matched,
        people: truth.len(),
        found: found.len(),
        best_iou: iou
            .iter()
            .map(|r| r.iter().copied().fold(0.0, f32::max))
            .collect(),
    }
}

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
    let labels = parsing_images(synth.written_rig(), &frame);
    let images = camera_images(&frame, &labels);
    let cloud = projector.project_frame(
        &images,
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
            let m = match_boxes(&frame.boxes.boxes, &found.boxes);
            s.frames += 1;
            s.good_frames += usize::from(m.is_good());
            if !m.is_good() {
                s.bad_frames.push(index);
                tracing::debug!(index, ?m, "frame not matched");
            }
            s.people += m.people;
            s.matched += m.matched;
            s.found += m.found;
            s.iou_sum += m.best_iou.iter().map(|&v| f64::from(v)).sum::<f64>();
        }
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(id: u32, x: f32) -> PersonBox {
        PersonBox {
            id,
            center_m: [x, 0.0, 0.9],
            half_extents_m: [0.3, 0.2, 0.9],
            yaw_rad: 0.0,
        }
    }

    #[test]
    fn matching_needs_one_box_per_person_and_no_extra() {
        let truth = [b(0, 0.0), b(1, 1.0)];
        assert!(match_boxes(&truth, &[b(7, 0.02), b(8, 1.01)]).is_good());
        // Missing person.
        assert!(!match_boxes(&truth, &[b(7, 0.0)]).is_good());
        // Extra box.
        assert!(!match_boxes(&truth, &[b(7, 0.0), b(8, 1.0), b(9, 3.0)]).is_good());
        // Two boxes on one person.
        let m = match_boxes(&truth[..1], &[b(7, 0.0), b(8, 0.01)]);
        assert_eq!(m.matched, 0);
    }
}
