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
//! # Conventions
//! - Frames: depth points are given in the depth sensor's optical frame (metres);
//!   `p_color = color_from_depth · p_depth` is projected with the colour intrinsics,
//!   distortion included; output clouds are in the world frame (`world_from_depth`).
//! - Pixels: integer coordinates are pixel centres; a point takes the colour pixel
//!   nearest to its projection (rounding), and is `unknown` when the projection lies
//!   outside `[-0.5, w - 0.5) × [-0.5, h - 0.5)` or the point is behind the colour camera.
//! - Depth images: raw `u16` with the camera's `depth_scale` / `depth_shift_mm`, 0 = none.
//! - Output order: the input points' order; cameras in rig order; origins kept.

mod config;
mod dsa;

pub use config::{MAX_RADIUS_PX, ProjectConfig, ProjectError, ProjectMode};
pub use dsa::project_labels;

use bodyseg_calib::{BackProjectOptions, CloudFrame, RgbdCamera, Rig, RigBackProjector};
use bodyseg_core::{LabelImage, LabeledCloud};
use rayon::prelude::*;

/// One camera's images of a frame: the raw depth image (depth sensor size) and the
/// parser's label image (colour sensor size).
#[derive(Debug, Clone, Copy)]
pub struct CameraImages<'a> {
    /// Raw depth, row-major, `u16`, 0 = no measurement.
    pub depth_raw: &'a [u16],
    /// Labels of the colour image.
    pub labels: &'a LabelImage,
}

/// Projects the labels of many frames of one rig: back-projection ray tables are built
/// once.
#[derive(Debug, Clone)]
pub struct FrameProjector {
    cameras: Vec<RgbdCamera>,
    back_projector: RigBackProjector,
}

impl FrameProjector {
    /// Validates the rig and builds its ray tables.
    pub fn new(rig: &Rig) -> Result<Self, ProjectError> {
        Ok(FrameProjector {
            cameras: rig.cameras.clone(),
            back_projector: RigBackProjector::new(rig)?,
        })
    }

    /// Back-projects every camera's depth image (`opts`' range limits and stride;
    /// `opts.frame` is ignored: the output is always the world frame), projects the
    /// labels with `cfg`, and concatenates the cameras in rig order. Cameras run in
    /// parallel (rayon); the result does not depend on the thread count.
    pub fn project_frame(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
    ) -> Result<LabeledCloud, ProjectError> {
        cfg.validate()?;
        if images.len() != self.cameras.len() {
            return Err(ProjectError::CameraCount {
                got: images.len(),
                want: self.cameras.len(),
            });
        }
        let depth_opts = BackProjectOptions {
            frame: CloudFrame::Depth,
            ..*opts
        };
        let depths: Vec<&[u16]> = images.iter().map(|i| i.depth_raw).collect();
        let clouds = self
            .back_projector
            .back_project_each(&depths, &depth_opts)?;
        let parts: Vec<LabeledCloud> = clouds
            .into_par_iter()
            .zip(self.cameras.par_iter())
            .zip(images.par_iter())
            .map(|((cloud, camera), img)| {
                let labels = project_labels(
                    camera,
                    &cloud.points_m,
                    &cloud.origins,
                    img.depth_raw,
                    img.labels,
                    cfg,
                )?;
                let positions_m = cloud
                    .points_m
                    .iter()
                    .map(|p| {
                        camera
                            .world_from_depth
                            .transform_point(p.map(f64::from))
                            .map(|c| c as f32)
                    })
                    .collect();
                Ok(LabeledCloud {
                    positions_m,
                    labels,
                    colors: None,
                    origins: cloud.origins,
                })
            })
            .collect::<Result<_, ProjectError>>()?;
        let total: usize = parts.iter().map(|p| p.labels.len()).sum();
        let mut out = LabeledCloud {
            positions_m: Vec::with_capacity(total),
            labels: Vec::with_capacity(total),
            colors: None,
            origins: Vec::with_capacity(total),
        };
        for part in parts {
            out.positions_m.extend_from_slice(&part.positions_m);
            out.labels.extend_from_slice(&part.labels);
            out.origins.extend_from_slice(&part.origins);
        }
        Ok(out)
    }
}

/// Projects one frame of `rig` into one labelled world-frame cloud (see
/// [`FrameProjector::project_frame`]); builds the ray tables each call.
pub fn project_frame(
    rig: &Rig,
    images: &[CameraImages<'_>],
    opts: &BackProjectOptions,
    cfg: &ProjectConfig,
) -> Result<LabeledCloud, ProjectError> {
    FrameProjector::new(rig)?.project_frame(images, opts, cfg)
}
