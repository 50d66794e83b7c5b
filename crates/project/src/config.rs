//! [`ProjectConfig`] and the crate's error type.

use bodyseg_calib::CalibError;
use bodyseg_core::ImageError;
use serde::{Deserialize, Serialize};

/// Why a projection could not run.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    /// A [`ProjectConfig`] field is out of range.
    #[error("project.{field} {problem}")]
    InvalidConfig {
        /// The field's name.
        field: &'static str,
        /// What is wrong, with the offending value.
        problem: String,
    },
    /// A per-point or per-pixel input has the wrong length.
    #[error("camera {camera}: {what} has {got} entries, expected {want}")]
    SizeMismatch {
        /// Camera name.
        camera: String,
        /// Which input (`origins`, `depth image`).
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length it must have.
        want: usize,
    },
    /// The label image's size differs from the colour sensor's.
    #[error("camera {camera}: label image is {got_w}x{got_h}, calibration says {want_w}x{want_h}")]
    LabelImageSize {
        /// Camera name.
        camera: String,
        /// Label image width, pixels.
        got_w: u32,
        /// Label image height, pixels.
        got_h: u32,
        /// Colour sensor width, pixels.
        want_w: u32,
        /// Colour sensor height, pixels.
        want_h: u32,
    },
    /// The label image is inconsistent (array lengths, probabilities).
    #[error("camera {camera}: {cause}")]
    LabelImage {
        /// Camera name.
        camera: String,
        /// What is wrong with it.
        cause: ImageError,
    },
    /// A point's origin lies outside the depth image.
    #[error("camera {camera}: point {index} has origin pixel {pixel}, outside the depth image")]
    OriginOutside {
        /// Camera name.
        camera: String,
        /// Index of the point.
        index: usize,
        /// Its origin pixel.
        pixel: u32,
    },
    /// The number of per-camera inputs differs from the rig's camera count.
    #[error("{got} camera inputs for a rig of {want} cameras")]
    CameraCount {
        /// Inputs given.
        got: usize,
        /// Cameras in the rig.
        want: usize,
    },
    /// Back-projection or the rig failed.
    #[error(transparent)]
    Calib(#[from] CalibError),
}

/// Which projection to run (ALGORITHM.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProjectMode {
    /// The paper's baseline: the label of the nearest colour pixel, nothing else.
    Naive,
    /// Nearest colour pixel plus the DSA checks switched on in [`ProjectConfig`].
    #[default]
    Dsa,
}

/// Configuration of the label projection (`[project]` in a pipeline config).
///
/// Every check only applies in [`ProjectMode::Dsa`]; each can be switched off on its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProjectConfig {
    /// `naive` or `dsa`. Default `dsa`.
    pub mode: ProjectMode,
    /// Occlusion test: a point more than `occlusion_tol_m` behind the nearest depth point
    /// that lands on its colour pixel is `unknown` (the colour camera sees another
    /// surface there: the colour/depth parallax). Default true.
    pub occlusion: bool,
    /// Slack of the occlusion test, metres, along the colour camera's z. Default 0.03:
    /// above Kinect v2 depth noise at 1–3 m (~1 cm) plus the depth change across the
    /// splat footprint on a surface at 60° to the view, well below the gap between a
    /// person and what is behind them.
    pub occlusion_tol_m: f64,
    /// Depth-proportional slack of the occlusion test, added to `occlusion_tol_m`: the
    /// test allows `occlusion_tol_m + occlusion_tol_ratio · z` (z of the nearest surface,
    /// colour camera frame). Depth noise and the depth change across a splat on a
    /// slanted surface both grow with distance (noise ∝ z², slant ∝ z): a constant 3 cm
    /// hides far floor seen at a grazing angle. Default 0.01 (5.6 cm in all at 2.6 m).
    pub occlusion_tol_ratio: f64,
    /// Half-width of the square each depth point is splatted into in the colour z-buffer,
    /// colour pixels. Default 1 (3×3): the colour image is denser than the depth image
    /// (Kinect v2: ~2.9 colour px between neighbouring depth samples at equal depth, 2 in
    /// a 2× fixture), so single-pixel splats leave holes through which hidden points
    /// would look visible. Raise it for sparser depth (stride > 1).
    pub splat_radius_px: u32,
    /// Depth-edge test: a point within `edge_radius_px` of a depth discontinuity (a
    /// neighbouring depth pixel whose depth differs by more than `edge_jump_ratio · z`)
    /// is `unknown`; this also catches flying pixels, which sit on such jumps. Default
    /// true.
    pub depth_edge: bool,
    /// Radius of the depth-edge test, depth pixels (square window). Default 1: the
    /// mixed/flying pixels of a ToF sensor lie on the pixel next to the jump.
    pub edge_radius_px: u32,
    /// Relative depth jump that counts as a discontinuity, and the depth consistency of
    /// the label-boundary vote, a fraction of the point's depth. Default 0.05 (5 cm at
    /// 1 m): above the depth change between neighbouring pixels of a surface at up to
    /// ~70° to the view at Kinect resolution, below body-to-background gaps.
    pub edge_jump_ratio: f64,
    /// Label-boundary vote: a point whose colour pixel lies within `boundary_radius_px`
    /// of a label change and whose label disagrees with the clear majority of its
    /// depth-consistent 8-neighbours (depth image) takes that majority label (a
    /// joint-bilateral vote, one pass, from the labels before the vote). Default true.
    pub label_boundary: bool,
    /// Radius of the label-change test, colour pixels (square window). Default 2: the
    /// width over which parsers usually misplace part boundaries.
    pub boundary_radius_px: u32,
    /// When the label image carries probabilities, a label whose probability is below
    /// this becomes `unknown`. In [0, 1]; default 0 (off).
    pub min_probability: f32,
}

impl Default for ProjectConfig {
    fn default() -> Self {
        ProjectConfig {
            mode: ProjectMode::Dsa,
            occlusion: true,
            occlusion_tol_m: 0.03,
            occlusion_tol_ratio: 0.01,
            splat_radius_px: 1,
            depth_edge: true,
            edge_radius_px: 1,
            edge_jump_ratio: 0.05,
            label_boundary: true,
            boundary_radius_px: 2,
            min_probability: 0.0,
        }
    }
}

/// Largest window radius accepted, pixels: beyond this a check would cost (2r+1)² look-ups
/// per point for no plausible benefit.
pub const MAX_RADIUS_PX: u32 = 16;

impl ProjectConfig {
    /// The naive (paper baseline) configuration.
    pub fn naive() -> Self {
        ProjectConfig {
            mode: ProjectMode::Naive,
            ..Default::default()
        }
    }

    /// Checks every field's range; the error names the field (`project.occlusion_tol_m`).
    pub fn validate(&self) -> Result<(), ProjectError> {
        let bad = |field, problem: String| Err(ProjectError::InvalidConfig { field, problem });
        if !(self.occlusion_tol_m.is_finite() && self.occlusion_tol_m >= 0.0) {
            return bad(
                "occlusion_tol_m",
                format!("must be a finite number >= 0, got {}", self.occlusion_tol_m),
            );
        }
        if !(self.occlusion_tol_ratio.is_finite()
            && (0.0..=1.0).contains(&self.occlusion_tol_ratio))
        {
            return bad(
                "occlusion_tol_ratio",
                format!("must be in [0, 1], got {}", self.occlusion_tol_ratio),
            );
        }
        if !(self.edge_jump_ratio.is_finite() && self.edge_jump_ratio > 0.0) {
            return bad(
                "edge_jump_ratio",
                format!("must be a finite number > 0, got {}", self.edge_jump_ratio),
            );
        }
        for (field, r) in [
            ("splat_radius_px", self.splat_radius_px),
            ("edge_radius_px", self.edge_radius_px),
            ("boundary_radius_px", self.boundary_radius_px),
        ] {
            if !(1..=MAX_RADIUS_PX).contains(&r) {
                return bad(
                    field,
                    format!(
                        "must be in 1..={MAX_RADIUS_PX} (switch the check off instead of 0), got {r}"
                    ),
                );
            }
        }
        if !(0.0..=1.0).contains(&self.min_probability) {
            return bad(
                "min_probability",
                format!("must be in [0, 1], got {}", self.min_probability),
            );
        }
        Ok(())
    }
}
