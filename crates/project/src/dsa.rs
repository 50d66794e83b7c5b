//! The per-camera projection: naive look-up and the DSA checks (ALGORITHM.md §3).

use bodyseg_calib::RgbdCamera;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabelImage, NUM_CLASSES, PointOrigin};
use rayon::prelude::*;

use crate::{ProjectConfig, ProjectError, ProjectMode};

/// Where a point lands in the colour image.
#[derive(Clone, Copy)]
struct Hit {
    /// Nearest colour pixel, column and row.
    u: u32,
    v: u32,
    /// Depth along the colour camera's z, metres.
    z_color_m: f64,
}

impl Hit {
    /// Nearest colour pixel, row-major index in an image `w` wide.
    #[inline]
    fn pixel(&self, w: usize) -> usize {
        self.v as usize * w + self.u as usize
    }
}

/// Labels of one camera's depth points, in their order (ALGORITHM.md §3).
///
/// - `depth_points_m`: the points in the depth sensor frame, metres (as
///   `bodyseg_calib::back_project` gives them with `CloudFrame::Depth`);
/// - `origins`: each point's depth pixel (only `pixel` is read);
/// - `depth_raw`: the raw depth image they came from (depth sensor size), read by the
///   depth-edge test and the label-boundary vote;
/// - `labels`: the parser's label image (colour sensor size).
///
/// A point behind the colour camera or projecting outside the colour image is `unknown`
/// in both modes. In `dsa` mode, in this order, from the nearest colour pixel's label:
/// 1. *occlusion* — every point is splatted into a colour z-buffer (a square of
///    `splat_radius_px`, keeping the nearest z); a point more than `occlusion_tol_m`
///    behind the z-buffer at its pixel is `unknown`;
/// 2. *depth edge* — a point with a neighbouring depth pixel (square of
///    `edge_radius_px`) whose depth differs by more than `edge_jump_ratio · z` is
///    `unknown` (neighbours without a measurement are not a jump);
/// 3. *probability* — with `min_probability > 0` and probabilities in the label image,
///    a label below it is `unknown`;
/// 4. *label boundary* — a labelled point whose colour pixel has a different label
///    within `boundary_radius_px` takes the label held by strictly more of its labelled,
///    depth-consistent (`|Δz| ≤ edge_jump_ratio · z`) 8-neighbours in the depth image
///    than any other label; the vote reads the labels after steps 1–3, so it is one
///    deterministic pass. Only direct neighbours vote: with a back-projection stride > 1
///    they hold no points and the vote does nothing.
pub fn project_labels(
    camera: &RgbdCamera,
    depth_points_m: &[Vec3],
    origins: &[PointOrigin],
    depth_raw: &[u16],
    labels: &LabelImage,
    cfg: &ProjectConfig,
) -> Result<Vec<Label>, ProjectError> {
    cfg.validate()?;
    check_inputs(camera, depth_points_m, origins, depth_raw, labels)?;

    let color = &camera.color;
    let color_w = color.width as usize;
    let hits: Vec<Option<Hit>> = depth_points_m
        .par_iter()
        .map(|p| {
            let p_color = camera.color_from_depth.transform_point(p.map(f64::from));
            let uv = color.project(p_color)?;
            if !color.contains(uv) {
                return None;
            }
            // `contains` keeps u in [-0.5, w - 0.5): rounding gives 0..w (the clamp only
            // guards the half-open edge against rounding up).
            let u = round_index(uv[0]).min(color.width - 1);
            let v = round_index(uv[1]).min(color.height - 1);
            Some(Hit {
                u,
                v,
                z_color_m: p_color[2],
            })
        })
        .collect();

    let naive: Vec<Label> = hits
        .iter()
        .map(|h| h.map_or(Label::UNKNOWN, |h| labels.labels[h.pixel(color_w)]))
        .collect();
    if cfg.mode == ProjectMode::Naive {
        return Ok(naive);
    }

    let zbuffer = cfg
        .occlusion
        .then(|| ZBuffer::splat(&hits, cfg.splat_radius_px as usize));
    let depth_w = camera.depth.width as usize;
    let depth_h = camera.depth.height as usize;
    // Depth in metres per depth pixel, NaN where there is none, converted once: the edge
    // test and the vote read each pixel up to 9 times.
    let depth_table_m: Vec<f64> = depth_raw
        .par_iter()
        .map(|&raw| camera.depth_m(raw).filter(|&z| z > 0.0).unwrap_or(f64::NAN))
        .collect();
    let depth_at = |pixel: usize| Some(depth_table_m[pixel]).filter(|z| !z.is_nan());
    let on_edge = cfg.depth_edge.then(|| {
        edge_map(
            &depth_table_m,
            depth_w,
            depth_h,
            cfg.edge_radius_px as usize,
            cfg.edge_jump_ratio,
        )
    });

    let checked: Vec<Label> = (0..hits.len())
        .into_par_iter()
        .map(|i| {
            let Some(hit) = hits[i] else {
                return Label::UNKNOWN;
            };
            if let Some(zb) = &zbuffer
                && hit.z_color_m > f64::from(zb.at(hit.u, hit.v)) + cfg.occlusion_tol_m
            {
                return Label::UNKNOWN;
            }
            if let Some(edge) = &on_edge
                && edge[origins[i].pixel as usize]
            {
                return Label::UNKNOWN;
            }
            if cfg.min_probability > 0.0
                && let Some(probs) = &labels.probs
                && probs[hit.pixel(color_w)] < cfg.min_probability
            {
                return Label::UNKNOWN;
            }
            naive[i]
        })
        .collect();
    if !cfg.label_boundary {
        return Ok(checked);
    }

    // Labels before the vote, per depth pixel (unknown where no point).
    let mut by_pixel = vec![Label::UNKNOWN; depth_w * depth_h];
    for (o, &l) in origins.iter().zip(&checked) {
        by_pixel[o.pixel as usize] = l;
    }
    let near_change = label_change_map(
        &labels.labels,
        labels.width as usize,
        labels.height as usize,
        cfg.boundary_radius_px as usize,
    );
    let voted = (0..hits.len())
        .into_par_iter()
        .map(|i| {
            let own = checked[i];
            let (Some(hit), Some(own_class)) = (hits[i], own.class()) else {
                return own;
            };
            // `own` is the label at `hit.pixel` (the checks only ever make a label
            // unknown), so "a different label within the radius" is "the square is not
            // uniform".
            if !near_change[hit.pixel(color_w)] {
                return own;
            }
            let pixel = origins[i].pixel as usize;
            let Some(z) = depth_at(pixel) else {
                return own;
            };
            let tol = cfg.edge_jump_ratio * z;
            let mut counts = [0u32; NUM_CLASSES];
            for n in window(pixel, depth_w, depth_h, 1) {
                let Some(c) = by_pixel[n].class() else {
                    continue;
                };
                if depth_at(n).is_some_and(|zn| (zn - z).abs() <= tol) {
                    counts[c.index()] += 1;
                }
            }
            let (best, &best_count) = counts
                .iter()
                .enumerate()
                .max_by_key(|&(k, &c)| (c, std::cmp::Reverse(k)))
                .expect("NUM_CLASSES > 0");
            let clear = counts
                .iter()
                .enumerate()
                .all(|(k, &c)| k == best || c < best_count);
            if clear && best != own_class.index() {
                // `best < NUM_CLASSES`, a class id.
                Label::from_id(best as u8).unwrap_or(own)
            } else {
                own
            }
        })
        .collect();
    Ok(voted)
}

/// `x.round().max(0.0) as u32` for `x` in [-0.5, 2³¹), without the `round` libm call:
/// for `x ≥ 0` the fraction `x − ⌊x⌋` is exact, and rounding takes half away from zero.
#[inline]
fn round_index(x: f64) -> u32 {
    if x <= 0.0 {
        return 0;
    }
    let t = x as u32;
    if x - f64::from(t) >= 0.5 { t + 1 } else { t }
}

/// The pixels of the square of radius `r` around `pixel` (row-major index in a `w × h`
/// image), clipped to the image, without `pixel` itself.
fn window(pixel: usize, w: usize, h: usize, r: usize) -> impl Iterator<Item = usize> {
    let (u, v) = (pixel % w, pixel / w);
    let (u0, u1) = (u.saturating_sub(r), (u + r).min(w - 1));
    let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
    (v0..=v1)
        .flat_map(move |vn| (u0..=u1).map(move |un| vn * w + un))
        .filter(move |&p| p != pixel)
}

/// Whether `f` holds for one row segment of the square of radius `r` around `pixel`
/// (row-major index in a `w × h` image), clipped to the image, centre included; each
/// segment is given as a range of row-major indices.
#[cfg(test)]
fn any_row_in_square(
    pixel: usize,
    w: usize,
    h: usize,
    r: usize,
    mut f: impl FnMut(std::ops::Range<usize>) -> bool,
) -> bool {
    let (u, v) = (pixel % w, pixel / w);
    let (u0, u1) = (u.saturating_sub(r), (u + r).min(w - 1));
    let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
    (v0..=v1).any(|vn| f(vn * w + u0..vn * w + u1 + 1))
}

/// Nearest colour-frame depth (metres, f32 to halve the buffer) per colour pixel over the
/// splat squares of all points, over the bounding box of the points' pixels (the only
/// pixels read); +∞ where no point lands.
struct ZBuffer {
    u0: u32,
    v0: u32,
    w: usize,
    h: usize,
    /// Splat radius.
    r: usize,
    /// Nearest z of the points whose pixel this is (the centres of the splats).
    z: Vec<f32>,
}

impl ZBuffer {
    /// The nearest z per pixel; [`ZBuffer::at`] takes the minimum over the square of
    /// radius `r` around a pixel, the same as splatting every point's square (z is
    /// finite, never NaN: `project` rejects non-finite points, so the order of the minima
    /// does not matter).
    fn splat(hits: &[Option<Hit>], r: usize) -> Self {
        let (mut u0, mut v0, mut u1, mut v1) = (u32::MAX, u32::MAX, 0, 0);
        for h in hits.iter().flatten() {
            u0 = u0.min(h.u);
            v0 = v0.min(h.v);
            u1 = u1.max(h.u);
            v1 = v1.max(h.v);
        }
        if u0 > u1 {
            return ZBuffer {
                u0: 0,
                v0: 0,
                w: 0,
                h: 0,
                r,
                z: Vec::new(),
            };
        }
        let w = (u1 - u0 + 1) as usize;
        let h = (v1 - v0 + 1) as usize;
        let mut centre = vec![f32::INFINITY; w * h];
        for hit in hits.iter().flatten() {
            let z = hit.z_color_m as f32;
            let cell = &mut centre[(hit.v - v0) as usize * w + (hit.u - u0) as usize];
            if z < *cell {
                *cell = z;
            }
        }
        ZBuffer {
            u0,
            v0,
            w,
            h,
            r,
            z: centre,
        }
    }

    /// The z-buffer at colour pixel (u, v), one of the points' pixels.
    fn at(&self, u: u32, v: u32) -> f32 {
        let (u, v) = ((u - self.u0) as usize, (v - self.v0) as usize);
        let (ua, ub) = (u.saturating_sub(self.r), (u + self.r).min(self.w - 1));
        let mut best = f32::INFINITY;
        for vn in v.saturating_sub(self.r)..=(v + self.r).min(self.h - 1) {
            for &z in &self.z[vn * self.w + ua..=vn * self.w + ub] {
                best = if z < best { z } else { best };
            }
        }
        best
    }
}

/// Per depth pixel: whether the depth-edge test flags it, i.e. it has depth z and some
/// pixel of the square of radius `r` around it (clipped) has depth zn with
/// `|zn - z| > ratio · z` (pixels without depth, NaN, never do). Exactly the per-pixel
/// test: the rounded difference is monotonic in zn, so testing the window's largest and
/// smallest depths (NaN skipped; separable) is the same.
fn edge_map(depth_m: &[f64], w: usize, h: usize, r: usize, ratio: f64) -> Vec<bool> {
    if w == 0 || h == 0 {
        return vec![false; w * h];
    }
    // Smallest and largest depth over the square, pixels without depth skipped (as +∞
    // and −∞); separable: rows, then columns.
    let mut lo = vec![0.0; w * h];
    let mut hi = vec![0.0; w * h];
    lo.par_chunks_mut(w)
        .zip(hi.par_chunks_mut(w))
        .zip(depth_m.par_chunks(w))
        .for_each(|((lo, hi), src)| {
            for ((l, h), &z) in lo.iter_mut().zip(hi.iter_mut()).zip(src) {
                let none = z.is_nan();
                *l = if none { f64::INFINITY } else { z };
                *h = if none { f64::NEG_INFINITY } else { z };
            }
            let (l0, h0) = (lo.to_vec(), hi.to_vec());
            for k in 1..=r.min(w - 1) {
                min_into(&mut lo[k..], &l0[..w - k]);
                min_into(&mut lo[..w - k], &l0[k..]);
                max_into(&mut hi[k..], &h0[..w - k]);
                max_into(&mut hi[..w - k], &h0[k..]);
            }
        });
    let mut out = vec![false; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(v, dst)| {
        let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
        let mut a = lo[v0 * w..(v0 + 1) * w].to_vec();
        let mut b = hi[v0 * w..(v0 + 1) * w].to_vec();
        for vn in v0 + 1..=v1 {
            min_into(&mut a, &lo[vn * w..(vn + 1) * w]);
            max_into(&mut b, &hi[vn * w..(vn + 1) * w]);
        }
        for (((d, &z), &a), &b) in dst
            .iter_mut()
            .zip(&depth_m[v * w..(v + 1) * w])
            .zip(&a)
            .zip(&b)
        {
            // A pixel with depth is in its own square, so a ≤ z ≤ b, both finite, and
            // the largest |zn − z| is b − z or z − a (rounding is monotonic).
            let jump = ratio * z;
            *d = !z.is_nan() && ((b - z).abs() > jump || (a - z).abs() > jump);
        }
    });
    out
}

fn min_into(dst: &mut [f64], src: &[f64]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = if s < *d { s } else { *d };
    }
}

fn max_into(dst: &mut [f64], src: &[f64]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = if s > *d { s } else { *d };
    }
}

/// Per colour pixel: whether the square of radius `r` around it (clipped to the image)
/// holds more than one label. The square is connected, so it is not uniform iff it holds
/// two 4-neighbours with different labels: a horizontal pair (u, u + 1) with both in the
/// square, i.e. u in [u_c - r, u_c + r - 1] and row in [v_c - r, v_c + r], or a vertical
/// pair (v, v + 1) with column in [u_c - r, u_c + r], v in [v_c - r, v_c + r - 1]. Pairs
/// that would leave the image do not exist, so clipping the offsets to the image is exact.
fn label_change_map(labels: &[Label], w: usize, h: usize, r: usize) -> Vec<bool> {
    if r == 0 || w == 0 || h == 0 {
        return vec![false; w * h];
    }
    // Per row: horizontal changes dilated over columns [-r, r - 1], vertical changes
    // (with the next row) dilated over columns [-r, r].
    let mut hd = vec![false; w * h];
    let mut vd = vec![false; w * h];
    hd.par_chunks_mut(w)
        .zip(vd.par_chunks_mut(w))
        .enumerate()
        .for_each(|(v, (hrow, vrow))| {
            let row = &labels[v * w..(v + 1) * w];
            let mut raw = vec![false; w];
            for (d, pair) in raw.iter_mut().zip(row.windows(2)) {
                *d = pair[0] != pair[1];
            }
            dilate_row(&raw, hrow, r, r - 1);
            if v + 1 < h {
                let next = &labels[(v + 1) * w..(v + 2) * w];
                for ((d, a), b) in raw.iter_mut().zip(row).zip(next) {
                    *d = a != b;
                }
                dilate_row(&raw, vrow, r, r);
            }
        });
    let mut out = vec![false; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(v, dst)| {
        for vn in v.saturating_sub(r)..=(v + r).min(h - 1) {
            for (d, &s) in dst.iter_mut().zip(&hd[vn * w..(vn + 1) * w]) {
                *d |= s;
            }
        }
        for vn in v.saturating_sub(r)..=(v + r - 1).min(h - 1) {
            for (d, &s) in dst.iter_mut().zip(&vd[vn * w..(vn + 1) * w]) {
                *d |= s;
            }
        }
    });
    out
}

/// `dst[u]` = OR of `src[u - left ..= u + right]`, clipped to the row.
fn dilate_row(src: &[bool], dst: &mut [bool], left: usize, right: usize) {
    let w = src.len();
    dst.fill(false);
    // Offset +k: dst[u] |= src[u + k].
    for k in 0..=right.min(w.saturating_sub(1)) {
        for (d, &s) in dst[..w - k].iter_mut().zip(&src[k..]) {
            *d |= s;
        }
    }
    for k in 1..=left.min(w.saturating_sub(1)) {
        for (d, &s) in dst[k..].iter_mut().zip(&src[..w - k]) {
            *d |= s;
        }
    }
}

fn check_inputs(
    camera: &RgbdCamera,
    depth_points_m: &[Vec3],
    origins: &[PointOrigin],
    depth_raw: &[u16],
    labels: &LabelImage,
) -> Result<(), ProjectError> {
    let name = || camera.name.clone();
    if origins.len() != depth_points_m.len() {
        return Err(ProjectError::SizeMismatch {
            camera: name(),
            what: "origins",
            got: origins.len(),
            want: depth_points_m.len(),
        });
    }
    let n_depth = camera.depth.num_pixels();
    if depth_raw.len() != n_depth {
        return Err(ProjectError::SizeMismatch {
            camera: name(),
            what: "depth image",
            got: depth_raw.len(),
            want: n_depth,
        });
    }
    if (labels.width, labels.height) != (camera.color.width, camera.color.height) {
        return Err(ProjectError::LabelImageSize {
            camera: name(),
            got_w: labels.width,
            got_h: labels.height,
            want_w: camera.color.width,
            want_h: camera.color.height,
        });
    }
    labels
        .validate()
        .map_err(|cause| ProjectError::LabelImage {
            camera: name(),
            cause,
        })?;
    if let Some(index) = origins.iter().position(|o| o.pixel as usize >= n_depth) {
        return Err(ProjectError::OriginOutside {
            camera: name(),
            index,
            pixel: origins[index].pixel,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_is_clipped_and_excludes_the_centre() {
        // 4×3 image; pixel (0, 0) has 3 neighbours, (1, 1) has 8.
        let mut corner: Vec<usize> = window(0, 4, 3, 1).collect();
        corner.sort_unstable();
        assert_eq!(corner, [1, 4, 5]);
        let mut inner: Vec<usize> = window(5, 4, 3, 1).collect();
        inner.sort_unstable();
        assert_eq!(inner, [0, 1, 2, 4, 6, 8, 9, 10]);
        // Radius 2 from the last pixel (3, 2): columns 1..=3, rows 0..=2, minus itself.
        assert_eq!(window(11, 4, 3, 2).count(), 8);
        // The same squares as row segments, centre included.
        let rows = |pixel, r| {
            let mut out = Vec::new();
            any_row_in_square(pixel, 4, 3, r, |row| {
                out.push(row);
                false
            });
            out
        };
        assert_eq!(rows(0, 1), [0..2, 4..6]);
        assert_eq!(rows(5, 1), [0..3, 4..7, 8..11]);
        assert_eq!(rows(11, 2), [1..4, 5..8, 9..12]);
    }
}
