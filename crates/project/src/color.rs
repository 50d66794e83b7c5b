//! Depth point → nearest colour pixel, in f32 over batches of points (ALGORITHM.md §3,
//! step 1).
//!
//! Why f32: the batch loop below has no branches, so it compiles to 4-wide SIMD on
//! baseline x86-64 (SSE2), twice the f64 width, and this look-up is the per-point work of
//! every frame. The cost is rounding: against [`Intrinsics::project`] in f64 on the same
//! f32 depth point, the pixel coordinates differ by at most [`F32_TOLERANCE_PX`]
//! (measured 2.4e-4 px on a Kinect v2 calibration over 0.5–8 m; the test
//! `f32_projection_stays_within_tolerance_of_f64` checks it). A point that close to a
//! half-pixel boundary may therefore take the neighbouring colour pixel: 1 point in
//! 20 898 in that test (≤ 1 in 10⁴ is asserted), and its label changes only where the
//! two pixels' labels differ. On the `project` bench frame (553 877 points) the labels
//! are identical to the former f64 path in both modes.

use bodyseg_calib::{Intrinsics, Pose, RgbdCamera};
use bodyseg_core::{LabeledCloud, RgbImage};

/// Largest difference, colour pixels, between [`ColorProjection`] and the f64
/// [`bodyseg_calib::Intrinsics::project`] of the same depth point, over the image.
/// f32 keeps 24 bits: ~1e-7 relative on `R·p`, the division and the distortion
/// polynomial, times a focal length of ~1000 px, a few 1e-4 px at most.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) const F32_TOLERANCE_PX: f64 = 1e-3;

/// `u` of a point that lands outside the colour image or behind the colour camera.
pub const NO_HIT: u32 = u32::MAX;

/// A pose into the colour frame (`color_from_depth` for the projection; any
/// `color_from_x`, e.g. `color_from_world` to draw a world cloud back into a camera) and
/// the colour intrinsics, in f32: where a point lands in the colour image.
#[derive(Debug, Clone)]
pub struct ColorProjection {
    rotation: [[f32; 3]; 3],
    translation_m: [f32; 3],
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    /// OpenCV's `k1 k2 p1 p2 k3 k4 k5 k6` (k4..k6 = 0 for Brown-Conrady).
    distortion: [f32; 8],
    /// Whether the model is rational: the batch loop then divides by its denominator
    /// (a separate instantiation, so Brown-Conrady cameras run the loop they always ran).
    rational: bool,
    /// Image width and height, pixels.
    width: u32,
    height: u32,
}

/// Where points land in their camera's colour image, one entry per point (structure of
/// arrays). [`crate::FrameProjector::project_frame_keeping_hits`] hands them out, so that
/// a caller drawing the cloud back into the colour images does not project it again.
#[derive(Debug, Clone, Default)]
pub struct Hits {
    /// Nearest colour pixel's column, or [`NO_HIT`].
    pub(crate) u: Vec<u32>,
    /// Nearest colour pixel's row (meaningless where `u` is [`NO_HIT`]).
    pub(crate) v: Vec<u32>,
    /// Depth along the colour camera's z, metres.
    pub(crate) z_color_m: Vec<f32>,
}

/// A borrowed range of [`Hits`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct HitsView<'a> {
    pub u: &'a [u32],
    pub v: &'a [u32],
    pub z_color_m: &'a [f32],
}

impl<'a> HitsView<'a> {
    pub(crate) fn slice(self, r: std::ops::Range<usize>) -> HitsView<'a> {
        HitsView {
            u: &self.u[r.clone()],
            v: &self.v[r.clone()],
            z_color_m: &self.z_color_m[r],
        }
    }
}

impl Hits {
    /// Points.
    pub fn len(&self) -> usize {
        self.u.len()
    }

    /// Whether there is no point.
    pub fn is_empty(&self) -> bool {
        self.u.is_empty()
    }

    /// Per point: the nearest colour pixel's column, or [`NO_HIT`] (outside the image
    /// or behind the colour camera).
    pub fn columns(&self) -> &[u32] {
        &self.u
    }

    /// Per point: the nearest colour pixel's row (meaningless where the column is
    /// [`NO_HIT`]).
    pub fn rows(&self) -> &[u32] {
        &self.v
    }

    /// Per point: its depth along the colour camera's z, metres.
    pub fn z_color_m(&self) -> &[f32] {
        &self.z_color_m
    }

    /// Per point of `cloud` (which these hits were kept for): the colour at its colour pixel
    /// in its camera's colour image (`colour[origin.camera]`); black where it has no hit.
    pub fn colors_of(&self, cloud: &LabeledCloud, color: &[&RgbImage]) -> Vec<[u8; 3]> {
        cloud
            .origins
            .iter()
            .zip(self.u.iter().zip(&self.v))
            .map(|(origin, (&u, &v))| {
                let Some(image) = color.get(usize::from(origin.camera)) else {
                    return [0; 3];
                };
                if u == NO_HIT {
                    return [0; 3];
                }
                let at = 3 * (v as usize * image.width as usize + u as usize);
                image
                    .rgb
                    .get(at..at + 3)
                    .map_or([0; 3], |c| [c[0], c[1], c[2]])
            })
            .collect()
    }

    /// Per point of `cloud` (which these hits were kept for): the parser's probability of
    /// the point's label, read at its colour pixel in its camera's label image
    /// (`images[origin.camera]`). 1 where that is not known: no hit, no probabilities in
    /// that image, an unknown label, or a label the pixel does not have (DSA's boundary
    /// vote took a neighbour's). For `noise = "probability"` of the refinement.
    pub fn label_probs_into(
        &self,
        cloud: &LabeledCloud,
        images: &[crate::CameraImages<'_>],
        out: &mut Vec<f32>,
    ) {
        out.clear();
        out.extend(
            cloud
                .labels
                .iter()
                .zip(&cloud.origins)
                .zip(self.u.iter().zip(&self.v))
                .map(|((&label, origin), (&u, &v))| {
                    let Some(image) = images.get(usize::from(origin.camera)) else {
                        return 1.0;
                    };
                    let image = image.labels;
                    let pixel = v as usize * image.width as usize + u as usize;
                    match &image.probs {
                        Some(probs)
                            if u != NO_HIT
                                && !label.is_unknown()
                                && image.labels.get(pixel) == Some(&label) =>
                        {
                            probs.get(pixel).copied().unwrap_or(1.0)
                        }
                        _ => 1.0,
                    }
                }),
        );
    }

    /// Forgets every point (keeps the allocations).
    pub(crate) fn clear(&mut self) {
        self.u.clear();
        self.v.clear();
        self.z_color_m.clear();
    }

    pub(crate) fn zeroed(n: usize) -> Self {
        Hits {
            u: vec![0; n],
            v: vec![0; n],
            z_color_m: vec![0.0; n],
        }
    }

    pub(crate) fn view(&self) -> HitsView<'_> {
        HitsView {
            u: &self.u,
            v: &self.v,
            z_color_m: &self.z_color_m,
        }
    }

    pub(crate) fn slice(&self, r: std::ops::Range<usize>) -> HitsView<'_> {
        self.view().slice(r)
    }
}

impl ColorProjection {
    /// The projection of `camera`'s depth-frame points (`color_from_depth`).
    pub fn new(camera: &RgbdCamera) -> Self {
        Self::from_pose(&camera.color_from_depth, &camera.color)
    }

    /// The projection of points of frame `x` into the colour image described by
    /// `color`, through `color_from_x`.
    pub fn from_pose(color_from_x: &Pose, color: &Intrinsics) -> Self {
        let (c, pose) = (color, color_from_x);
        ColorProjection {
            rotation: pose.rotation().map(|row| row.map(|x| x as f32)),
            translation_m: pose.translation_m().map(|x| x as f32),
            fx: c.fx as f32,
            fy: c.fy as f32,
            cx: c.cx as f32,
            cy: c.cy as f32,
            distortion: c.distortion.rational_coefficients().map(|x| x as f32),
            rational: c.distortion.is_rational(),
            width: c.width,
            height: c.height,
        }
    }

    /// Projects the depth-frame points `(x[i], y[i], z[i])` (metres) to their nearest
    /// colour pixel `(out_u[i], out_v[i])` and colour-frame depth `z_color_m[i]`; all
    /// slices have the same length. Nearest pixel as
    /// `dsa::project_labels` documents (rounding half away from zero, image spans
    /// `[-0.5, w - 0.5)`); behind the camera or outside the image → [`NO_HIT`].
    pub(crate) fn project_batch(
        &self,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        out_u: &mut [u32],
        out_v: &mut [u32],
        z_color_m: &mut [f32],
    ) {
        if self.rational {
            self.batch::<true>([x, y, z], (out_u, out_v, z_color_m));
        } else {
            self.batch::<false>([x, y, z], (out_u, out_v, z_color_m));
        }
    }

    /// [`ColorProjection::project_batch`] for one distortion model.
    #[inline(always)]
    fn batch<const RATIONAL: bool>(
        &self,
        [x, y, z]: [&[f32]; 3],
        (out_u, out_v, z_color_m): (&mut [u32], &mut [u32], &mut [f32]),
    ) {
        let n = x.len();
        // Equal lengths up front so the loop below has no bounds checks and vectorises.
        let (y, z) = (&y[..n], &z[..n]);
        let (out_u, out_v, z_color_m) = (&mut out_u[..n], &mut out_v[..n], &mut z_color_m[..n]);
        let bounds = self.bounds();
        for i in 0..n {
            let (u, v, zc) = self.hit::<RATIONAL>([x[i], y[i], z[i]], &bounds);
            out_u[i] = u;
            out_v[i] = v;
            z_color_m[i] = zc;
        }
    }

    /// The image bounds [`ColorProjection::hit`] tests against: `[u_end, v_end, w_last,
    /// h_last]`.
    #[inline(always)]
    fn bounds(&self) -> [f32; 4] {
        // Clamped to 2²³ (f32 pixel coordinates are whole numbers from there on: no camera
        // is that wide) so that `round_index` stays exact.
        [
            self.width as f32 - 0.5,
            self.height as f32 - 0.5,
            (self.width - 1).min(1 << 23) as f32,
            (self.height - 1).min(1 << 23) as f32,
        ]
    }

    /// Nearest pixel (u = [`NO_HIT`] outside the image or behind the camera) and
    /// colour-frame z of one point.
    #[inline(always)]
    fn hit<const RATIONAL: bool>(&self, p: [f32; 3], bounds: &[f32; 4]) -> (u32, u32, f32) {
        let [u_end, v_end, w_last, h_last] = *bounds;
        let [u, v, zc] = self.uv_z::<RATIONAL>(p);
        // NaN and ±∞ (zc = 0, non-finite input) fail every comparison.
        let inside = (zc > 0.0) & (u >= -0.5) & (v >= -0.5) & (u < u_end) & (v < v_end);
        let (ui, vi) = (round_index(u, w_last), round_index(v, h_last));
        (if inside { ui } else { NO_HIT }, vi, zc)
    }

    /// The nearest colour pixel (column, row) of one point and its depth along the
    /// colour camera's z, metres; `None` behind the camera or outside the image. The same
    /// rule as the projection's batches.
    pub fn nearest_pixel(&self, p: [f32; 3]) -> Option<(u32, u32, f32)> {
        let (u, v, z) = if self.rational {
            self.hit::<true>(p, &self.bounds())
        } else {
            self.hit::<false>(p, &self.bounds())
        };
        (u != NO_HIT).then_some((u, v, z))
    }

    /// Width and height of the colour image, pixels.
    pub fn size_px(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

impl ColorProjection {
    /// Pixel coordinates (u, v) and colour-frame z (metres) of a depth-frame point;
    /// non-finite coordinates where a rational model's denominator is ≤ 0 (no image
    /// there).
    #[inline(always)]
    fn uv_z<const RATIONAL: bool>(&self, p: [f32; 3]) -> [f32; 3] {
        let (r, t) = (&self.rotation, &self.translation_m);
        let [px, py, pz] = p;
        let xc = r[0][0] * px + r[0][1] * py + r[0][2] * pz + t[0];
        let yc = r[1][0] * px + r[1][1] * py + r[1][2] * pz + t[1];
        let zc = r[2][0] * px + r[2][1] * py + r[2][2] * pz + t[2];
        let (xn, yn) = (xc / zc, yc / zc);
        // OpenCV's Brown-Conrady or rational model, as `Distortion::distort`.
        let [k1, k2, p1, p2, k3, k4, k5, k6] = self.distortion;
        let r2 = xn * xn + yn * yn;
        let mut radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        if RATIONAL {
            let den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
            // Where the denominator is ≤ 0 the division by 0 gives ±∞ (or NaN) and the
            // point no hit; no branch or select, so the loop still vectorises.
            radial /= den.max(0.0);
        }
        let xd = xn * radial + 2.0 * p1 * xn * yn + p2 * (r2 + 2.0 * xn * xn);
        let yd = yn * radial + p1 * (r2 + 2.0 * yn * yn) + 2.0 * p2 * xn * yn;
        [self.fx * xd + self.cx, self.fy * yd + self.cy, zc]
    }
}

/// 2²³: from here on every f32 is an integer.
const TWO_POW_23: f32 = 8_388_608.0;

/// Nearest integer of `x` (`x.round()`, halves away from zero) for `x` in [-0.5, 2²³),
/// clamped to `[0, last]`, as `u32`. Only float arithmetic and a bit cast, no libm call
/// and no saturating cast, so the loop calling it vectorises (SSE2 has neither a packed
/// round nor a packed unsigned conversion); every step is exact in this range. NaN and
/// values outside it give some integer in `[0, last]` that the caller discards.
#[inline(always)]
fn round_index(x: f32, last: f32) -> u32 {
    // `max`/`min` map NaN to the other operand.
    let x = x.max(0.0).min(last);
    // n = x rounded to nearest-even (adding 2²³ drops the fraction), trunc(x) from it.
    let n = (x + TWO_POW_23) - TWO_POW_23;
    let t = if n > x { n - 1.0 } else { n };
    let r = if x - t >= 0.5 { t + 1.0 } else { t };
    // The bits of 2²³ + r hold r in the mantissa; r ≤ last ≤ 2²³ - 1.
    (r.min(last) + TWO_POW_23).to_bits() - TWO_POW_23.to_bits()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_calib::{Distortion, Intrinsics, Pose};

    /// The iai_kinect2 calibration of the bench data (`196605135147`), rounded.
    fn kinect() -> RgbdCamera {
        let depth = Intrinsics::pinhole(512, 424, 365.4, 365.4, 257.9, 206.8)
            .with_distortion(Distortion::BrownConrady([0.0905, -0.272, 0.0, 0.0, 0.0967]));
        let color = Intrinsics::pinhole(1920, 1080, 1059.9, 1058.6, 968.4, 548.1).with_distortion(
            Distortion::BrownConrady([0.0391, -0.0311, 0.00071, 0.00025, 0.0]),
        );
        let mut cam = RgbdCamera::new("k", depth, color);
        let (s, c) = 0.01_f64.sin_cos();
        cam.color_from_depth = Pose::from_rotation_translation(
            [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            [-0.052, 0.0004, 0.0012],
        )
        .expect("a rotation about y");
        cam
    }

    /// Points of every `step`-th depth pixel (both axes) at depths 0.5..8 m, depth
    /// frame, f32.
    fn depth_points(cam: &RgbdCamera, step: usize) -> Vec<[f32; 3]> {
        let mut out = Vec::new();
        for v in (0..cam.depth.height).step_by(step) {
            for u in (0..cam.depth.width).step_by(step) {
                let ray = cam
                    .depth
                    .unproject(f64::from(u), f64::from(v))
                    .expect("ray");
                let d = 0.5 + 7.5 * f64::from((u * 7 + v * 13) % 100) / 100.0;
                out.push(ray.map(|c| (c * d) as f32));
            }
        }
        out
    }

    #[test]
    fn round_index_matches_round() {
        for x in [
            -0.5f32, -0.49, -0.0, 0.0, 0.49999997, 0.5, 1.5, 2.4999998, 2.5, 1918.5, 1919.49,
            1919.5, 4095.5,
        ] {
            assert_eq!(round_index(x, 1919.0), (x.round() as u32).min(1919), "{x}");
        }
    }

    #[test]
    fn f32_projection_stays_within_tolerance_of_f64() {
        let cam = kinect();
        let proj = ColorProjection::new(&cam);
        // Every 3rd depth pixel at depths 0.5..8 m: the whole image and range.
        let points = depth_points(&cam, 3);
        let x: Vec<f32> = points.iter().map(|p| p[0]).collect();
        let y: Vec<f32> = points.iter().map(|p| p[1]).collect();
        let z: Vec<f32> = points.iter().map(|p| p[2]).collect();
        let mut hits = Hits::zeroed(x.len());
        proj.project_batch(&x, &y, &z, &mut hits.u, &mut hits.v, &mut hits.z_color_m);
        let (mut worst_px, mut worst_z) = (0.0f64, 0.0f64);
        let mut inside = 0;
        let mut other_pixel = 0usize;
        for i in 0..x.len() {
            let p = [x[i], y[i], z[i]].map(f64::from);
            let p_color = cam.color_from_depth.transform_point(p);
            let uv = cam.color.project(p_color).expect("in front");
            if !cam.color.contains(uv) {
                continue;
            }
            inside += 1;
            let [u32_, v32, z32] = proj.uv_z::<false>([x[i], y[i], z[i]]);
            worst_px = worst_px
                .max((f64::from(u32_) - uv[0]).abs())
                .max((f64::from(v32) - uv[1]).abs());
            worst_z = worst_z.max((f64::from(z32) - p_color[2]).abs());
            // The f64 path's nearest pixel (what a label would be read from).
            let f64_pixel = (uv[0].round().max(0.0), uv[1].round().max(0.0));
            if f64_pixel != (f64::from(hits.u[i]), f64::from(hits.v[i])) {
                other_pixel += 1;
            }
            // The batch gives the nearest pixel of those coordinates.
            let got = (hits.u[i], hits.v[i]);
            let want = (
                (u32_.round() as u32).min(1919),
                (v32.round() as u32).min(1079),
            );
            if proj_contains(u32_, v32) {
                assert_eq!(got, want, "point {i} at {uv:?}");
            } else {
                assert_eq!(got.0, NO_HIT, "point {i} at {uv:?}");
            }
        }
        assert!(inside > x.len() / 2, "{inside} of {}", x.len());
        eprintln!(
            "f32 vs f64 projection: worst {worst_px:e} px, z {worst_z:e} m, \
             {other_pixel} of {inside} points on another pixel"
        );
        // Only near-ties flip: ≤ 1 point in 10⁴ (the labels of those can only differ
        // where the two pixels' labels do).
        assert!(other_pixel * 10_000 <= inside, "{other_pixel} of {inside}");
        assert!(
            worst_px < F32_TOLERANCE_PX,
            "pixel coordinates differ by {worst_px:e} px"
        );
        // z: f32 rounding of a few metres.
        assert!(worst_z < 1e-5, "z differs by {worst_z:e} m");
    }

    #[test]
    fn f32_rational_projection_stays_within_tolerance_of_f64() {
        // The Kinect's geometry with an Azure Kinect colour sensor's rational model
        // (tests/fixtures/calib/azure_kinect/pyk4a_calibration.json, 720P).
        let mut cam = kinect();
        cam.color = Intrinsics::pinhole(
            1280,
            720,
            611.7953491210938,
            611.927001953125,
            639.3043212890625,
            365.8529052734375,
        )
        .with_distortion(bodyseg_calib::testing::AZURE_COLOR_DISTORTION);
        let proj = ColorProjection::new(&cam);
        let (mut worst, mut inside, mut other_pixel) = (0.0f64, 0usize, 0usize);
        for p in depth_points(&cam, 2) {
            let p_color = cam.color_from_depth.transform_point(p.map(f64::from));
            let uv = cam.color.project(p_color).expect("in front");
            let hit = proj.nearest_pixel(p);
            if !cam.color.contains(uv) {
                // Outside by more than the f32 tolerance: no hit.
                let margin = (-0.5 - uv[0])
                    .max(uv[0] - 1279.5)
                    .max(-0.5 - uv[1])
                    .max(uv[1] - 719.5);
                if margin > F32_TOLERANCE_PX {
                    assert!(hit.is_none(), "{uv:?}");
                }
                continue;
            }
            inside += 1;
            let [u32_, v32, _] = proj.uv_z::<true>(p);
            worst = worst
                .max((f64::from(u32_) - uv[0]).abs())
                .max((f64::from(v32) - uv[1]).abs());
            let f64_pixel = (uv[0].round().max(0.0) as u32, uv[1].round().max(0.0) as u32);
            if hit.map(|(u, v, _)| (u, v)) != Some(f64_pixel) {
                other_pixel += 1;
            }
        }
        assert!(inside > 10_000, "{inside}");
        assert!(worst < F32_TOLERANCE_PX, "{worst:e} px");
        assert!(other_pixel * 10_000 <= inside, "{other_pixel} of {inside}");
    }

    #[test]
    fn rational_pole_gives_no_hit() {
        // Denominator 1 - r² (k4 = -1): ≤ 0 from r = 1 on (45° off the colour axis).
        let mut cam = kinect();
        cam.color_from_depth = Pose::identity();
        cam.color.distortion = Distortion::Rational([0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0]);
        let proj = ColorProjection::new(&cam);
        assert!(proj.nearest_pixel([0.1, 0.1, 2.0]).is_some());
        // r = 1 exactly (division by 0), and r = 10, which the unguarded model would map
        // into the image (radial factor 1/(1 - 100): about 100 px from the centre).
        for p in [[2.0f32, 0.0, 2.0], [0.0, 20.0, 2.0], [20.0, 0.0, 2.0]] {
            assert!(proj.nearest_pixel(p).is_none(), "{p:?}");
        }
    }

    fn proj_contains(u: f32, v: f32) -> bool {
        u >= -0.5 && v >= -0.5 && u < 1919.5 && v < 1079.5
    }
}
