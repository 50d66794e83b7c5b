//! bodyseg-project: 2D body-part labels → labelled 3D points (ALGORITHM.md §3).
//!
//! Place in the pipeline: after 2D human parsing. Each camera's depth image is
//! back-projected (`bodyseg-calib`), each point is looked up in that camera's
//! [`LabelImage`], and the clouds of all cameras are moved to the world frame and
//! concatenated: parsed frame (depth images + label images) → [`LabeledCloud`].
//! Depends on `bodyseg-core` and `bodyseg-calib` only.
//!
//! Two modes ([`ProjectMode`]):
//! - **naive** (the paper's baseline): the label of the nearest colour pixel;
//! - **dsa** (default): the same look-up guarded against depth–segmentation association
//!   errors by an occlusion z-buffer, a depth-edge / flying-pixel test, a probability
//!   threshold and a label-boundary vote, each switchable in [`ProjectConfig`].
//!
//! Beside the projected labels, and only when asked for,
//! [`FrameProjector::vote_labels`] gives the multi-view consistency vote: a point seen
//! by several cameras takes the label most of them agree on (module `vote`).
//!
//! # Conventions
//! - Frames: depth points are given in the depth sensor's optical frame (metres);
//!   `p_color = color_from_depth · p_depth` is projected with the colour intrinsics,
//!   distortion included; output clouds are in the world frame (`world_from_depth`).
//! - Pixels: integer coordinates are pixel centres; a point takes the colour pixel
//!   nearest to its projection (rounding), and is `unknown` when the projection lies
//!   outside `[-0.5, w - 0.5) × [-0.5, h - 0.5)` or the point is behind the colour camera.
//!   The projection is computed in f32 (SIMD), within 1e-3 px of the f64 one: on a
//!   near-tie a point may take the other of two neighbouring pixels (module `color`).
//! - Depth images: raw `u16` with the camera's `depth_scale` / `depth_shift_mm`, 0 = none.
//! - Output order: the input points' order; cameras in rig order; origins kept.

mod color;
mod config;
mod dsa;
mod images;
mod projector;

pub use color::{ColorProjection, Hits, NO_HIT};
pub use config::{MAX_RADIUS_PX, ProjectConfig, ProjectError, ProjectMode};
pub use dsa::project_labels;
pub use images::CameraImages;
pub use projector::{FrameProjector, project_frame};
