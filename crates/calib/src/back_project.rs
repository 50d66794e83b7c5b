//! Depth image → points (ALGORITHM.md §1): every valid depth pixel becomes
//! `z · (x', y', 1)`, with (x', y') the undistorted normalised ray of the pixel, optionally
//! moved into the world frame. Each point keeps its origin (camera, pixel).
//!
//! Parallelism (rayon): one image is cut into chunks of rows ([`PIXELS_PER_CHUNK`]
//! pixels each) projected in parallel and concatenated in row-major order, so the output is
//! the sequential one bit for bit ([`DepthBackProjector::back_project_sequential`] is the
//! reference); a rig's cameras run in parallel too ([`RigBackProjector`]).

use std::ops::Range;

use bodyseg_core::PointOrigin;
use bodyseg_core::math::Vec3;
use rayon::prelude::*;

use crate::{CalibError, Intrinsics, RgbdCamera, Rig};

/// About how many pixels one parallel chunk of rows holds (16 rows of a 512-pixel Kinect v2
/// depth image): large enough that rayon's per-task cost (~µs) is small against the chunk's
/// work, small enough that two to sixteen cores each get several chunks of a 512×424 image.
pub const PIXELS_PER_CHUNK: usize = 8192;

/// The frame back-projected points are expressed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CloudFrame {
    /// The camera's depth sensor frame (OpenCV optical, metres).
    Depth,
    /// The world frame, through the camera's `world_from_depth` (z up, metres).
    #[default]
    World,
}

/// Which depth pixels become points, and in which frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackProjectOptions {
    /// Depths below this (metres, after scale and shift) give no point. Default 0: any
    /// positive depth is kept.
    pub depth_min_m: f64,
    /// Depths above this (metres) give no point. Default +∞ (no limit); Kinect v2 data is
    /// unreliable beyond ~4.5 m.
    pub depth_max_m: f64,
    /// Keep every `stride`-th pixel along rows and columns (pixels with `u % stride == 0`
    /// and `v % stride == 0`). Default 1 (every pixel).
    pub stride: u32,
    /// Frame of the output points. Default [`CloudFrame::World`].
    pub frame: CloudFrame,
}

impl Default for BackProjectOptions {
    fn default() -> Self {
        BackProjectOptions {
            depth_min_m: 0.0,
            depth_max_m: f64::INFINITY,
            stride: 1,
            frame: CloudFrame::World,
        }
    }
}

impl BackProjectOptions {
    /// Checks `stride >= 1`, `depth_min_m` finite and ≥ 0, `depth_max_m >= depth_min_m`.
    pub fn validate(&self) -> Result<(), CalibError> {
        if self.stride == 0 {
            return Err(CalibError::invalid("stride", "must be >= 1, got 0"));
        }
        if !(self.depth_min_m.is_finite() && self.depth_min_m >= 0.0) {
            return Err(CalibError::invalid(
                "depth_min_m",
                format!("must be finite and >= 0, got {}", self.depth_min_m),
            ));
        }
        if self.depth_max_m.is_nan() || self.depth_max_m < self.depth_min_m {
            return Err(CalibError::invalid(
                "depth_max_m",
                format!(
                    "must be >= depth_min_m ({}), got {}",
                    self.depth_min_m, self.depth_max_m
                ),
            ));
        }
        Ok(())
    }
}

/// Points of one depth image with their origins (same length, row-major pixel order).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BackProjected {
    /// Point positions, metres, in the frame the options asked for.
    pub points_m: Vec<Vec3>,
    /// Origin of each point: camera index in the rig and row-major depth pixel index.
    pub origins: Vec<PointOrigin>,
}

impl BackProjected {
    /// The parts one after another, in order: one cloud from row chunks or from cameras.
    fn concat(parts: Vec<BackProjected>) -> Self {
        let n = parts.iter().map(|p| p.points_m.len()).sum();
        let mut out = BackProjected {
            points_m: Vec::with_capacity(n),
            origins: Vec::with_capacity(n),
        };
        for part in parts {
            out.points_m.extend_from_slice(&part.points_m);
            out.origins.extend_from_slice(&part.origins);
        }
        out
    }
}

/// The undistorted normalised ray `(x', y')` of every pixel of a sensor, row-major;
/// `None` where undistortion does not converge.
#[derive(Debug, Clone, PartialEq)]
pub struct RayTable {
    width: u32,
    height: u32,
    /// NaN where there is no ray: 16 bytes a pixel instead of an `Option`'s 24, which
    /// the back-projection streams through once per frame.
    rays: Vec<[f64; 2]>,
}

impl RayTable {
    /// Computes the table (one Newton undistortion per pixel).
    pub fn new(intrinsics: &Intrinsics) -> Self {
        let mut rays = Vec::with_capacity(intrinsics.num_pixels());
        for v in 0..intrinsics.height {
            for u in 0..intrinsics.width {
                rays.push(
                    intrinsics
                        .unproject(f64::from(u), f64::from(v))
                        .map_or([f64::NAN; 2], |[x, y, _]| [x, y]),
                );
            }
        }
        RayTable {
            width: intrinsics.width,
            height: intrinsics.height,
            rays,
        }
    }

    /// The ray `(x', y')` of pixel (u, v); `None` outside the image or where
    /// undistortion failed.
    pub fn ray(&self, u: u32, v: u32) -> Option<[f64; 2]> {
        if u >= self.width || v >= self.height {
            return None;
        }
        let ray = self.rays[v as usize * self.width as usize + u as usize];
        (!ray[0].is_nan()).then_some(ray)
    }
}

/// Back-projects depth images of one camera, with its ray table computed once.
#[derive(Debug, Clone)]
pub struct DepthBackProjector {
    camera: RgbdCamera,
    camera_index: u8,
    rays: RayTable,
    /// `camera.depth_m(raw)` for every raw value (NaN for none): a look-up instead of a
    /// division per pixel, the same values bit for bit.
    depth_lut: Box<[f64; 1 << 16]>,
}

impl DepthBackProjector {
    /// Validates the camera and computes its ray table. `camera_index` is the camera's
    /// place in the rig, stored in every point's origin.
    pub fn new(camera: &RgbdCamera, camera_index: u8) -> Result<Self, CalibError> {
        camera.validate()?;
        let depth_lut: Vec<f64> = (0..=u16::MAX)
            .map(|raw| camera.depth_m(raw).unwrap_or(f64::NAN))
            .collect();
        Ok(DepthBackProjector {
            camera: camera.clone(),
            camera_index,
            rays: RayTable::new(&camera.depth),
            depth_lut: depth_lut
                .into_boxed_slice()
                .try_into()
                .expect("one entry per u16"),
        })
    }

    /// The camera this projector was built for.
    pub fn camera(&self) -> &RgbdCamera {
        &self.camera
    }

    /// The camera's ray table.
    pub fn rays(&self) -> &RayTable {
        &self.rays
    }

    /// Back-projects one depth image (raw `u16` values, row-major, the depth sensor's
    /// size). Raw 0, depths outside `[depth_min_m, depth_max_m]`, non-positive depths
    /// after the shift and pixels without a ray give no point.
    ///
    /// Chunks of rows run in parallel on rayon's current pool; the output (points and
    /// origins, row-major) is bit for bit that of [`Self::back_project_sequential`].
    pub fn back_project(
        &self,
        depth_raw: &[u16],
        opts: &BackProjectOptions,
    ) -> Result<BackProjected, CalibError> {
        self.check(depth_raw, opts)?;
        let rows = self.strided_rows(opts);
        let w = self.camera.depth.width as usize;
        let rows_per_chunk = (PIXELS_PER_CHUNK / w.max(1)).max(1);
        let chunks: Vec<Range<usize>> = (0..rows.len())
            .step_by(rows_per_chunk)
            .map(|start| start..(start + rows_per_chunk).min(rows.len()))
            .collect();
        if chunks.len() <= 1 {
            return Ok(self.project_rows(depth_raw, opts, &rows));
        }
        let parts: Vec<BackProjected> = chunks
            .into_par_iter()
            .map(|range| self.project_rows(depth_raw, opts, &rows[range]))
            .collect();
        Ok(BackProjected::concat(parts))
    }

    /// [`Self::back_project`] on the calling thread only: the reference the parallel
    /// version is tested against.
    pub fn back_project_sequential(
        &self,
        depth_raw: &[u16],
        opts: &BackProjectOptions,
    ) -> Result<BackProjected, CalibError> {
        self.check(depth_raw, opts)?;
        Ok(self.project_rows(depth_raw, opts, &self.strided_rows(opts)))
    }

    fn check(&self, depth_raw: &[u16], opts: &BackProjectOptions) -> Result<(), CalibError> {
        opts.validate()?;
        if depth_raw.len() != self.camera.depth.num_pixels() {
            return Err(CalibError::DepthSize {
                camera: self.camera.name.clone(),
                got: depth_raw.len(),
                want_w: self.camera.depth.width,
                want_h: self.camera.depth.height,
            });
        }
        Ok(())
    }

    /// The rows `v` visited with this stride.
    fn strided_rows(&self, opts: &BackProjectOptions) -> Vec<u32> {
        (0..self.camera.depth.height)
            .step_by(opts.stride as usize)
            .collect()
    }

    /// Points of the given rows, row-major. `depth_raw` has the sensor's size (checked).
    fn project_rows(
        &self,
        depth_raw: &[u16],
        opts: &BackProjectOptions,
        rows: &[u32],
    ) -> BackProjected {
        let w = self.camera.depth.width;
        let step = opts.stride as usize;
        // Upper bound (every visited pixel valid): no reallocation while pushing.
        let cap = rows.len() * (w as usize).div_ceil(step);
        let mut out = BackProjected {
            points_m: Vec::with_capacity(cap),
            origins: Vec::with_capacity(cap),
        };
        let pose = &self.camera.world_from_depth;
        let (min, max) = (opts.depth_min_m, opts.depth_max_m);
        for &v in rows {
            let row = v as usize * w as usize..(v as usize + 1) * w as usize;
            let (depth, rays) = (&depth_raw[row.clone()], &self.rays.rays[row]);
            for u in (0..w as usize).step_by(step) {
                let z = self.depth_lut[usize::from(depth[u])];
                let [x, y] = rays[u];
                // NaN (no measurement, no ray) fails every comparison.
                if !(z > 0.0 && z >= min && z <= max && !x.is_nan()) {
                    continue;
                }
                let p_depth = [z * x, z * y, z];
                let p = match opts.frame {
                    CloudFrame::Depth => p_depth,
                    CloudFrame::World => pose.transform_point(p_depth),
                };
                // Clouds store f32 positions: ~0.1 µm rounding at a few metres.
                out.points_m.push(p.map(|c| c as f32));
                out.origins.push(PointOrigin {
                    camera: self.camera_index,
                    // Fits: `Intrinsics::validate` (run in `new`) caps the pixel count
                    // at u32::MAX.
                    pixel: (v as usize * w as usize + u) as u32,
                });
            }
        }
        out
    }
}

/// Back-projects the depth images of all cameras of a rig, one [`DepthBackProjector`] per
/// camera (ray tables computed once), cameras in parallel (rayon) and, within each, chunks
/// of rows in parallel.
#[derive(Debug, Clone)]
pub struct RigBackProjector {
    projectors: Vec<DepthBackProjector>,
}

impl RigBackProjector {
    /// Validates the rig and computes each camera's ray table; camera `i` of the rig gets
    /// index `i` in the points' origins.
    pub fn new(rig: &Rig) -> Result<Self, CalibError> {
        rig.validate()?;
        let projectors = rig
            .cameras
            .par_iter()
            .enumerate()
            .map(|(i, cam)| {
                // Fits: `Rig::validate` caps the rig at `Rig::MAX_CAMERAS` = 256.
                DepthBackProjector::new(cam, i as u8)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(RigBackProjector { projectors })
    }

    /// The per-camera projectors, in rig order.
    pub fn projectors(&self) -> &[DepthBackProjector] {
        &self.projectors
    }

    /// Back-projects one depth image per camera (`depths[i]` belongs to camera `i`), each
    /// in the frame `opts.frame` asks for; the result is in rig order. Errors: a count of
    /// images other than the number of cameras, or any camera's error (wrong image size).
    pub fn back_project_each(
        &self,
        depths: &[&[u16]],
        opts: &BackProjectOptions,
    ) -> Result<Vec<BackProjected>, CalibError> {
        if depths.len() != self.projectors.len() {
            return Err(CalibError::invalid(
                "depths",
                format!(
                    "one depth image per camera: the rig has {} cameras, got {} images",
                    self.projectors.len(),
                    depths.len()
                ),
            ));
        }
        self.projectors
            .par_iter()
            .zip(depths.par_iter())
            .map(|(p, d)| p.back_project(d, opts))
            .collect()
    }

    /// One world-frame cloud of all cameras: the clouds of [`Self::back_project_each`]
    /// concatenated in rig order, each point with its origin (camera, pixel).
    /// `opts.frame` must be [`CloudFrame::World`] (points of different depth frames cannot
    /// share a cloud); anything else is an error on `frame`.
    pub fn back_project(
        &self,
        depths: &[&[u16]],
        opts: &BackProjectOptions,
    ) -> Result<BackProjected, CalibError> {
        if opts.frame != CloudFrame::World {
            return Err(CalibError::invalid(
                "frame",
                "a cloud of several cameras must be in the world frame",
            ));
        }
        let parts = self.back_project_each(depths, opts)?;
        Ok(BackProjected::concat(parts))
    }
}

/// Back-projects one depth image per camera of `rig` into one world-frame cloud, in rig
/// order (see [`RigBackProjector::back_project`]). Builds every ray table each call; keep
/// a [`RigBackProjector`] to project many frames.
pub fn back_project_rig(
    depths: &[&[u16]],
    rig: &Rig,
    opts: &BackProjectOptions,
) -> Result<BackProjected, CalibError> {
    RigBackProjector::new(rig)?.back_project(depths, opts)
}

/// Back-projects one depth image of `camera` (see [`DepthBackProjector::back_project`]).
/// Builds the camera's ray table each call; keep a [`DepthBackProjector`] to project many
/// frames of one camera.
pub fn back_project(
    depth_raw: &[u16],
    camera: &RgbdCamera,
    camera_index: u8,
    opts: &BackProjectOptions,
) -> Result<BackProjected, CalibError> {
    DepthBackProjector::new(camera, camera_index)?.back_project(depth_raw, opts)
}
