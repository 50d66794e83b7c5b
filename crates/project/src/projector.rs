//! [`FrameProjector`]: the fused back-projection and label projection of a rig's frames
//! (naive or DSA), with the tables built once per rig and the buffers kept between
//! frames; [`project_frame`] for a single frame. The multi-view vote is in `vote`.

mod vote;

use bodyseg_calib::{BackProjectOptions, CalibError, RgbdCamera, Rig, RigBackProjector};
use bodyseg_core::{Label, LabeledCloud, PointOrigin, RgbImage};
use std::sync::Mutex;

use rayon::prelude::*;

use crate::color::{ColorProjection, Hits};
use crate::config::{ProjectConfig, ProjectError, ProjectMode};
use crate::dsa::{DepthLut, DsaScratch, apply_dsa, check_images, depth_lut, naive_labels};
use crate::images::CameraImages;

/// What one camera needs per frame, computed once.
#[derive(Debug, Clone)]
struct CameraTables {
    camera: RgbdCamera,
    /// Undistorted normalised ray `(x', y')` per depth pixel, row-major (the
    /// back-projection's `RayTable`); NaN where undistortion failed (no point there).
    rays: Vec<[f64; 2]>,
    /// Per depth pixel: whether it has a ray (undistortion converged).
    has_ray: Vec<bool>,
    /// [`depth_lut`]: metres per raw depth value, NaN for none.
    depth_lut: Box<DepthLut>,
    color: ColorProjection,
}

/// Projects the labels of many frames of one rig: back-projection ray tables, depth
/// look-up tables and the f32 colour projections are built once, and the large
/// per-frame buffers of the DSA checks are kept from one frame to the next.
#[derive(Debug)]
pub struct FrameProjector {
    cameras: Vec<CameraTables>,
    /// Reused by [`FrameProjector::project_frame`]; a call that finds it in use (another
    /// thread) or poisoned (a panic) works on fresh buffers instead.
    scratch: Mutex<FrameScratch>,
}

impl Clone for FrameProjector {
    fn clone(&self) -> Self {
        FrameProjector {
            cameras: self.cameras.clone(),
            scratch: Mutex::default(),
        }
    }
}

/// Buffers of one frame, kept so that they are neither allocated nor cleared per frame
/// (a z-buffer is 8 MB per Kinect v2 camera).
#[derive(Default)]
struct FrameScratch {
    /// Where every point lands in its colour image (contents overwritten every frame).
    hits: Hits,
    /// Per camera the DSA stage's buffers (z-buffer, edge map, labels per pixel).
    dsa: Vec<DsaScratch>,
}

impl std::fmt::Debug for FrameScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameScratch")
            .field("points", &self.hits.u.len())
            .field("cameras", &self.dsa.len())
            .finish()
    }
}

/// Depth rows per parallel task of the fused back-projection + projection pass (about
/// [`bodyseg_calib::PIXELS_PER_CHUNK`] pixels of a Kinect v2 depth image).
fn rows_per_chunk(width: u32) -> usize {
    (bodyseg_calib::PIXELS_PER_CHUNK / (width as usize).max(1)).max(1)
}

impl FrameProjector {
    /// Validates the rig and builds its ray tables.
    pub fn new(rig: &Rig) -> Result<Self, ProjectError> {
        let back_projector = RigBackProjector::new(rig)?;
        let cameras = back_projector
            .projectors()
            .par_iter()
            .map(|p| {
                let camera = p.camera().clone();
                let (w, h) = (camera.depth.width, camera.depth.height);
                let rays: Vec<[f64; 2]> = (0..h)
                    .flat_map(|v| (0..w).map(move |u| (u, v)))
                    .map(|(u, v)| p.rays().ray(u, v).unwrap_or([f64::NAN; 2]))
                    .collect();
                let has_ray = rays.iter().map(|r: &[f64; 2]| !r[0].is_nan()).collect();
                CameraTables {
                    depth_lut: depth_lut(&camera),
                    has_ray,
                    color: ColorProjection::new(&camera),
                    rays,
                    camera,
                }
            })
            .collect();
        Ok(FrameProjector {
            cameras,
            scratch: Mutex::default(),
        })
    }

    /// Back-projects every camera's depth image (`opts`' range limits and stride;
    /// `opts.frame` is ignored: the output is always the world frame), projects the
    /// labels with `cfg`, and concatenates the cameras in rig order. Cameras run in
    /// parallel (rayon); the result does not depend on the thread count.
    ///
    /// The same points, positions and labels as `bodyseg_calib::back_project` into the
    /// depth frame, [`project_labels`] on those points and `world_from_depth` applied to
    /// them (in f64, stored as f32), bit for bit; done in one pass per chunk of depth
    /// rows that writes straight into the output.
    pub fn project_frame(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
    ) -> Result<LabeledCloud, ProjectError> {
        let mut out = LabeledCloud::default();
        self.project_frame_into(images, opts, cfg, &mut out)?;
        Ok(out)
    }

    /// [`FrameProjector::project_frame`] into `out`, whose allocations are reused: a
    /// caller that projects frame after frame (one cloud per worker) skips the
    /// allocation and first-touch page faults of ~12 MB per 3-camera frame (the
    /// `_reused` cases of the `project` bench). On error `out` is left empty.
    pub fn project_frame_into(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
        out: &mut LabeledCloud,
    ) -> Result<(), ProjectError> {
        let result = self.fill_frame(images, opts, cfg, out, None);
        if result.is_err() {
            *out = LabeledCloud::default();
        }
        result
    }

    /// [`FrameProjector::project_frame_into`] that also hands out where every point of
    /// `out` landed in its own camera's colour image (`hits`, one entry per point, in the
    /// cloud's order; allocations reused): the projection computes them anyway, and a
    /// caller that draws the labels back into the colour images then needs no second
    /// projection. On error both `out` and `hits` are left empty.
    pub fn project_frame_keeping_hits(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
        out: &mut LabeledCloud,
        hits: &mut Hits,
    ) -> Result<(), ProjectError> {
        let result = self.fill_frame(images, opts, cfg, out, Some(&mut *hits));
        if result.is_err() {
            *out = LabeledCloud::default();
            hits.clear();
        }
        result
    }

    /// [`FrameProjector::project_frame`] with every point's camera colour in the cloud's
    /// `colors`: the colour at its colour pixel in its camera's image (`colour[camera]`,
    /// [`Hits::colors_of`]; black where it has none), as a coloured cloud (a PCD) has them.
    pub fn project_frame_colored(
        &self,
        images: &[CameraImages<'_>],
        color: &[&RgbImage],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
    ) -> Result<LabeledCloud, ProjectError> {
        let (mut cloud, mut hits) = (LabeledCloud::default(), Hits::default());
        self.project_frame_keeping_hits(images, opts, cfg, &mut cloud, &mut hits)?;
        cloud.colors = Some(hits.colors_of(&cloud, color));
        Ok(cloud)
    }

    /// The checks of every frame's inputs: the configurations, one camera's images per
    /// rig camera, each of its sensors' size (in the order of back-projecting every
    /// camera then projecting each one's labels, so the errors are those).
    pub(crate) fn check_inputs(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
    ) -> Result<(), ProjectError> {
        cfg.validate()?;
        opts.validate()?;
        if images.len() != self.cameras.len() {
            return Err(ProjectError::CameraCount {
                got: images.len(),
                want: self.cameras.len(),
            });
        }
        for (t, img) in self.cameras.iter().zip(images) {
            if img.depth_raw.len() != t.camera.depth.num_pixels() {
                return Err(CalibError::DepthSize {
                    camera: t.camera.name.clone(),
                    got: img.depth_raw.len(),
                    want_w: t.camera.depth.width,
                    want_h: t.camera.depth.height,
                }
                .into());
            }
        }
        for (t, img) in self.cameras.iter().zip(images) {
            check_images(&t.camera, img.depth_raw, img.labels)?;
        }
        Ok(())
    }

    fn fill_frame(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
        out: &mut LabeledCloud,
        keep_hits: Option<&mut Hits>,
    ) -> Result<(), ProjectError> {
        self.check_inputs(images, opts, cfg)?;
        let stride = opts.stride as usize;

        // Pass 1: points per chunk of rows, so that pass 2 can write each chunk's points
        // straight to their place in the output.
        struct Chunk {
            camera: usize,
            rows: std::ops::Range<usize>,
            len: usize,
        }
        let mut chunks: Vec<Chunk> = Vec::new();
        for (c, t) in self.cameras.iter().enumerate() {
            let h = t.camera.depth.height as usize;
            let step = rows_per_chunk(t.camera.depth.width) * stride;
            chunks.extend((0..h).step_by(step).map(|v0| Chunk {
                camera: c,
                rows: v0..(v0 + step).min(h),
                len: 0,
            }));
        }
        let kept: Vec<KeptRaw> = self.cameras.iter().map(|t| t.kept_raw(opts)).collect();
        chunks.par_iter_mut().for_each(|ch| {
            let t = &self.cameras[ch.camera];
            let w = t.camera.depth.width as usize;
            let depth = images[ch.camera].depth_raw;
            let keep = kept[ch.camera];
            ch.len = ch
                .rows
                .clone()
                .step_by(stride)
                .map(|v| {
                    let row = v * w..(v + 1) * w;
                    let (depth, has_ray) = (&depth[row.clone()], &t.has_ray[row]);
                    if stride == 1 {
                        // Plain loop: vectorises.
                        depth
                            .iter()
                            .zip(has_ray)
                            .map(|(&raw, &ray)| usize::from(keep.contains(raw) & ray))
                            .sum::<usize>()
                    } else {
                        (0..w)
                            .step_by(stride)
                            .filter(|&u| keep.contains(depth[u]) & has_ray[u])
                            .count()
                    }
                })
                .sum();
        });

        let total: usize = chunks.iter().map(|c| c.len).sum();
        // Every entry below `total` is overwritten by pass 2: a reused buffer is only
        // truncated or grown, never cleared. Grown in parallel, so that a fresh cloud's
        // ~12 MB (3 Kinect v2 cameras) are first touched, page faults included, on every
        // thread rather than on this one.
        out.colors = None;
        grow_to(&mut out.positions_m, total, [0.0; 3]);
        grow_to(&mut out.labels, total, Label::UNKNOWN);
        grow_to(
            &mut out.origins,
            total,
            PointOrigin {
                camera: 0,
                pixel: 0,
            },
        );
        // Where the points land, for the DSA checks (naive mode needs only the labels).
        let dsa = cfg.mode == ProjectMode::Dsa;
        let mut fresh = None;
        let mut guard = self.scratch.try_lock().ok();
        let scratch = match guard.as_deref_mut() {
            Some(s) => s,
            None => fresh.insert(FrameScratch::default()),
        };
        let FrameScratch {
            hits: own_hits,
            dsa: dsa_scratch,
        } = scratch;
        // The caller's hits when it keeps them (then stored in naive mode too), else ours.
        let store = dsa || keep_hits.is_some();
        let hits = keep_hits.unwrap_or(own_hits);
        if store {
            // Every entry below `total` is overwritten by pass 2.
            hits.u.resize(total, 0);
            hits.v.resize(total, 0);
            hits.z_color_m.resize(total, 0.0);
        }

        // Pass 2: back-projection, world transform, colour projection, naive label.
        {
            let mut parts = Vec::with_capacity(chunks.len());
            let mut rest = Parts {
                positions_m: &mut out.positions_m,
                labels: &mut out.labels,
                origins: &mut out.origins,
                hits: store.then_some(HitsMut {
                    u: &mut hits.u,
                    v: &mut hits.v,
                    z_color_m: &mut hits.z_color_m,
                }),
            };
            for ch in &chunks {
                let (head, tail) = rest.split_at(ch.len);
                parts.push((ch, head));
                rest = tail;
            }
            parts.into_par_iter().for_each(|(ch, part)| {
                let t = &self.cameras[ch.camera];
                t.fill(
                    ch.camera,
                    ch.rows.clone(),
                    &images[ch.camera],
                    opts,
                    kept[ch.camera],
                    part,
                );
            });
        }

        if dsa {
            // Per camera: its points are contiguous, in rig order.
            let mut ranges = Vec::with_capacity(self.cameras.len());
            let mut start = 0;
            for c in 0..self.cameras.len() {
                let n: usize = chunks
                    .iter()
                    .filter(|ch| ch.camera == c)
                    .map(|ch| ch.len)
                    .sum();
                ranges.push(start..start + n);
                start += n;
            }
            let mut label_parts = Vec::with_capacity(ranges.len());
            let mut rest = &mut out.labels[..];
            for r in &ranges {
                let (head, tail) = rest.split_at_mut(r.len());
                label_parts.push(head);
                rest = tail;
            }
            dsa_scratch.resize_with(self.cameras.len(), DsaScratch::default);
            let hits = &*hits;
            label_parts
                .into_par_iter()
                .zip(ranges.into_par_iter())
                .zip(dsa_scratch.par_iter_mut())
                .enumerate()
                .for_each(|(c, ((labels_out, range), dsa_scratch))| {
                    let t = &self.cameras[c];
                    apply_dsa(
                        &t.camera,
                        &t.depth_lut,
                        hits.slice(range.clone()),
                        &out.origins[range],
                        images[c].depth_raw,
                        images[c].labels,
                        cfg,
                        stride,
                        dsa_scratch,
                        labels_out,
                    );
                });
        }
        Ok(())
    }
}

/// Truncates or grows `v` to `len` entries, new ones `fill`, written in parallel.
fn grow_to<T: Clone + Send + Sync>(v: &mut Vec<T>, len: usize, fill: T) {
    v.truncate(len);
    let more = len - v.len();
    if more > 0 {
        v.par_extend(rayon::iter::repeat_n(fill, more));
    }
}

/// The raw depth values `lo..end` that give a point (see [`CameraTables::kept_raw`]).
#[derive(Debug, Clone, Copy)]
struct KeptRaw {
    lo: u32,
    end: u32,
}

impl KeptRaw {
    #[inline]
    fn contains(self, raw: u16) -> bool {
        (u32::from(raw) >= self.lo) & (u32::from(raw) < self.end)
    }
}

/// Disjoint output slices of one chunk of rows.
struct Parts<'a> {
    positions_m: &'a mut [[f32; 3]],
    labels: &'a mut [Label],
    origins: &'a mut [PointOrigin],
    /// Where the points land in the colour image, kept for the DSA checks only.
    hits: Option<HitsMut<'a>>,
}

/// A mutable range of [`Hits`].
struct HitsMut<'a> {
    u: &'a mut [u32],
    v: &'a mut [u32],
    z_color_m: &'a mut [f32],
}

impl<'a> HitsMut<'a> {
    fn split_at(self, n: usize) -> (HitsMut<'a>, HitsMut<'a>) {
        let (u0, u1) = self.u.split_at_mut(n);
        let (v0, v1) = self.v.split_at_mut(n);
        let (z0, z1) = self.z_color_m.split_at_mut(n);
        (
            HitsMut {
                u: u0,
                v: v0,
                z_color_m: z0,
            },
            HitsMut {
                u: u1,
                v: v1,
                z_color_m: z1,
            },
        )
    }
}

impl<'a> Parts<'a> {
    fn split_at(self, n: usize) -> (Parts<'a>, Parts<'a>) {
        let (p0, p1) = self.positions_m.split_at_mut(n);
        let (l0, l1) = self.labels.split_at_mut(n);
        let (o0, o1) = self.origins.split_at_mut(n);
        let (h0, h1) = match self.hits.map(|h| h.split_at(n)) {
            Some((h0, h1)) => (Some(h0), Some(h1)),
            None => (None, None),
        };
        (
            Parts {
                positions_m: p0,
                labels: l0,
                origins: o0,
                hits: h0,
            },
            Parts {
                positions_m: p1,
                labels: l1,
                origins: o1,
                hits: h1,
            },
        )
    }
}

impl CameraTables {
    /// The raw depth values that give a point under `opts` (as in
    /// `DepthBackProjector::back_project`: a measurement, depth > 0 and within the
    /// options' range): an interval, as metres are non-decreasing in the raw value.
    fn kept_raw(&self, opts: &BackProjectOptions) -> KeptRaw {
        let lut = &self.depth_lut[..];
        // NaN (no measurement, depth ≤ 0) only on a prefix; NaN fails both tests.
        let first = lut.partition_point(|z| z.is_nan());
        let lo = first + lut[first..].partition_point(|&z| z < opts.depth_min_m);
        let end = first + lut[first..].partition_point(|&z| z <= opts.depth_max_m);
        KeptRaw {
            lo: lo as u32,
            end: end as u32,
        }
    }

    /// Pass 2 of [`FrameProjector::project_frame`] over `rows` (multiples of the stride
    /// apart): `part` has exactly as many entries as those rows keep points.
    fn fill(
        &self,
        camera_index: usize,
        rows: std::ops::Range<usize>,
        images: &CameraImages<'_>,
        opts: &BackProjectOptions,
        keep: KeptRaw,
        mut part: Parts<'_>,
    ) {
        let w = self.camera.depth.width as usize;
        let stride = opts.stride as usize;
        let pose = &self.camera.world_from_depth;
        // One row's points at a time, as structure of arrays, so that each step below is
        // a plain loop that vectorises.
        let (mut x, mut y, mut z) = (vec![0.0; w], vec![0.0; w], vec![0.0; w]);
        let mut cols = vec![0u32; w];
        let mut hits = Hits::zeroed(if part.hits.is_some() { 0 } else { w });
        let mut k = 0;
        for v in rows.step_by(stride) {
            let row = v * w..(v + 1) * w;
            let (depth, rays) = (&images.depth_raw[row.clone()], &self.rays[row.clone()]);
            let has_ray = &self.has_ray[row];
            // Compaction without a branch (holes are random, a branch would mispredict):
            // every pixel is written at the next free slot, which only advances when
            // the pixel keeps a point. Slot n ≤ pixels visited so far < w.
            let mut n = 0;
            let mut u = 0;
            while u < w {
                let raw = depth[u];
                let z_m = self.depth_lut[usize::from(raw)];
                let [rx, ry] = rays[u];
                // As `DepthBackProjector`: z · (x', y', 1) in f64, stored as f32.
                (x[n], y[n], z[n]) = ((z_m * rx) as f32, (z_m * ry) as f32, z_m as f32);
                cols[n] = u as u32;
                n += usize::from(keep.contains(raw) & has_ray[u]);
                u += stride;
            }
            let (x, y, z, cols) = (&x[..n], &y[..n], &z[..n], &cols[..n]);
            let out = k..k + n;
            k += n;
            for (p, ((&x, &y), &z)) in part.positions_m[out.clone()]
                .iter_mut()
                .zip(x.iter().zip(y).zip(z))
            {
                let p_depth = [f64::from(x), f64::from(y), f64::from(z)];
                *p = pose.transform_point(p_depth).map(|c| c as f32);
            }
            for (o, &u) in part.origins[out.clone()].iter_mut().zip(cols) {
                *o = PointOrigin {
                    // Fits: `Rig::validate` caps the rig at 256 cameras.
                    camera: camera_index as u8,
                    // Fits: `Intrinsics::validate` caps the pixel count at u32::MAX.
                    pixel: (v * w) as u32 + u,
                };
            }
            // Straight into the frame's hits when the DSA checks need them, else into
            // this row's.
            let (hu, hv, hz) = match part.hits.as_mut() {
                Some(all) => (
                    &mut all.u[out.clone()],
                    &mut all.v[out.clone()],
                    &mut all.z_color_m[out.clone()],
                ),
                None => (&mut hits.u[..n], &mut hits.v[..n], &mut hits.z_color_m[..n]),
            };
            self.color.project_batch(x, y, z, hu, hv, hz);
            naive_labels(hu, hv, images.labels, &mut part.labels[out]);
        }
        debug_assert_eq!(k, part.labels.len());
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
