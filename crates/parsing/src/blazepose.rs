//! BlazePose landmarks + segmentation mask → the 7 classes (issue 29), pure functions.
//!
//! The rule of `docs/notes/2026-12-02-blazepose-rule.md`, ported from its reference,
//! `scripts/blazepose_prototype.py`: a square, rotated region of interest (ROI) per person
//! is cropped into the landmark model's 256×256 input ([`Roi`], [`crop`]); the model's
//! landmarks are refined on its heatmaps ([`refine_from_heatmap`]) and mapped back to the
//! image ([`decode`]); bones are built from them ([`bones`]: a torso quad and capsules
//! around the head, arms and legs); each pixel of the person's mask takes the class of the
//! nearest bone surface ([`label_person`]), with a probability = mask × a bone-margin
//! confidence; people are merged by the nearer bone ([`merge_people`]).
//!
//! This first phase has no ONNX session here: the `Segmenter` that runs the model on
//! person regions comes with the pipeline integration (second phase).
//!
//! # Conventions
//! - Image pixels (u, v) = (column, row), integer coordinates are pixel centres.
//! - Tensor coordinates of the 256×256 input are pixel edges (0..256): tensor pixel
//!   (i, j) has its centre at (i + 0.5, j + 0.5), as MediaPipe's landmark outputs.
//! - A ROI's `angle_rad` rotates its axes: right = (cos a, sin a), down = (−sin a, cos a)
//!   in image pixels; 0 = upright.

pub use crate::segmenter::PixelBox;

mod bone;
mod decode;
#[cfg(test)]
pub(crate) mod figure;
mod label;
pub mod landmark;
mod model;
mod roi;

pub use bone::{Bone, BoneShape, BoneStart, RuleConfig, bones, polygon_distance, segment_distance};
pub use decode::{
    DecodedPose, average_masks, decode, mirror_crop, refine_from_heatmap, unmirror_outputs,
};
pub(crate) use decode::{decode_landmarks, mask_from_logits};
pub use label::{PersonLabels, SIDE_BY_SIDE_M, label_person, merge_people};
pub use model::{HEATMAP, INPUT, NUM_LANDMARKS};
pub use roi::{Roi, blank_outside, crop, crop_into};

#[cfg(test)]
mod tests;
