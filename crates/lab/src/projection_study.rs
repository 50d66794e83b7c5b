//! How well label projection does on synthetic frames, against the exact truth of every
//! depth pixel (issue 4's naive-vs-DSA report; `examples/projection_report.rs`).

use anyhow::Result;
use bodyseg_calib::BackProjectOptions;
use bodyseg_calib::Rig;
use bodyseg_core::{Label, LabelImage};
use bodyseg_project::{CameraImages, FrameProjector, ProjectConfig};
use bodyseg_synth::{NO_SURFACE, Synth, SynthFrame};

/// Counts of one projection configuration over some frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjectionStats {
    /// Points projected (valid depth pixels with a true surface).
    pub points: usize,
    /// Points left `unknown`.
    pub unknown: usize,
    /// Labelled points whose label differs from the truth.
    pub wrong: usize,
    /// Points whose true class is a body part.
    pub body_points: usize,
    /// Of those, labelled with another class.
    pub body_wrong: usize,
    /// Of those, left `unknown`.
    pub body_unknown: usize,
}

impl ProjectionStats {
    /// Labelled (not unknown) points.
    pub fn labelled(&self) -> usize {
        self.points - self.unknown
    }

    /// Wrong labelled points over all points.
    pub fn wrong_fraction(&self) -> f64 {
        self.wrong as f64 / self.points.max(1) as f64
    }

    /// Correct points over labelled points.
    pub fn labelled_accuracy(&self) -> f64 {
        (self.labelled() - self.wrong) as f64 / self.labelled().max(1) as f64
    }

    /// Unknown points over all points.
    pub fn unknown_fraction(&self) -> f64 {
        self.unknown as f64 / self.points.max(1) as f64
    }

    /// Wrong body points over body points.
    pub fn body_wrong_fraction(&self) -> f64 {
        self.body_wrong as f64 / self.body_points.max(1) as f64
    }

    /// Sum of two counts.
    pub fn add(&mut self, o: &ProjectionStats) {
        self.points += o.points;
        self.unknown += o.unknown;
        self.wrong += o.wrong;
        self.body_points += o.body_points;
        self.body_wrong += o.body_wrong;
        self.body_unknown += o.body_unknown;
    }
}

/// Projects frames `frames` of `synth` (its written rig and its predicted `parsing`
/// labels) with each of `configs`, and counts against the per-depth-pixel truth.
pub fn projection_stats(
    synth: &Synth,
    frames: &[usize],
    configs: &[ProjectConfig],
) -> Result<Vec<ProjectionStats>> {
    let rig = synth.written_rig();
    let projector = FrameProjector::new(rig)?;
    let mut stats = vec![ProjectionStats::default(); configs.len()];
    for &index in frames {
        let frame = synth.frame(index);
        let label_images = parsing_images(rig, &frame);
        let images = camera_images(&frame, &label_images);
        for (cfg, s) in configs.iter().zip(&mut stats) {
            let cloud = projector.project_frame(&images, &BackProjectOptions::default(), cfg)?;
            for (label, origin) in cloud.labels.iter().zip(&cloud.origins) {
                let truth =
                    frame.cameras[usize::from(origin.camera)].depth_labels[origin.pixel as usize];
                if truth == NO_SURFACE {
                    continue;
                }
                let body = truth != 0;
                s.points += 1;
                s.body_points += usize::from(body);
                if *label == Label::UNKNOWN {
                    s.unknown += 1;
                    s.body_unknown += usize::from(body);
                } else if label.id() != truth {
                    s.wrong += 1;
                    s.body_wrong += usize::from(body);
                }
            }
        }
    }
    Ok(stats)
}

/// The simulated parser's label images of a synthetic frame (its `parsing`), one per
/// camera of `rig` (the synth's written rig); ids that are not classes become unknown.
pub fn parsing_images(rig: &Rig, frame: &SynthFrame) -> Vec<LabelImage> {
    rig.cameras
        .iter()
        .zip(&frame.cameras)
        .map(|(camera, images)| LabelImage {
            width: camera.color.width,
            height: camera.color.height,
            labels: images
                .parsing
                .iter()
                .map(|&l| Label::from_id(l).unwrap_or(Label::UNKNOWN))
                .collect(),
            probs: None,
        })
        .collect()
}

/// The projector's input for a synthetic frame: its depth images and `labels`.
pub fn camera_images<'a>(frame: &'a SynthFrame, labels: &'a [LabelImage]) -> Vec<CameraImages<'a>> {
    frame
        .cameras
        .iter()
        .zip(labels)
        .map(|(c, labels)| CameraImages {
            depth_raw: &c.depth_mm,
            labels,
        })
        .collect()
}
