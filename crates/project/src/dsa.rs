//! The per-camera projection: naive look-up and the DSA checks (ALGORITHM.md §3).

use bodyseg_calib::RgbdCamera;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabelImage, NUM_CLASSES, PointOrigin};
use rayon::prelude::*;

use crate::{ProjectConfig, ProjectError, ProjectMode};

/// Where a point lands in the colour image.
#[derive(Clone, Copy)]
struct Hit {
    /// Nearest colour pixel, row-major index.
    pixel: usize,
    u: u32,
    v: u32,
    /// Depth along the colour camera's z, metres.
    z_color_m: f64,
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
            let u = (uv[0].round().max(0.0) as u32).min(color.width - 1);
            let v = (uv[1].round().max(0.0) as u32).min(color.height - 1);
            Some(Hit {
                pixel: v as usize * color.width as usize + u as usize,
                u,
                v,
                z_color_m: p_color[2],
            })
        })
        .collect();

    let naive: Vec<Label> = hits
        .iter()
        .map(|h| h.map_or(Label::UNKNOWN, |h| labels.labels[h.pixel]))
        .collect();
    if cfg.mode == ProjectMode::Naive {
        return Ok(naive);
    }

    let zbuffer = cfg.occlusion.then(|| splat_zbuffer(&hits, labels, cfg));
    let depth_w = camera.depth.width as usize;
    let depth_h = camera.depth.height as usize;
    // Depth in metres per depth pixel, NaN where there is none, converted once: the edge
    // test and the vote read each pixel up to 9 times.
    let depth_table_m: Vec<f64> = depth_raw
        .par_iter()
        .map(|&raw| camera.depth_m(raw).filter(|&z| z > 0.0).unwrap_or(f64::NAN))
        .collect();
    let depth_at = |pixel: usize| Some(depth_table_m[pixel]).filter(|z| !z.is_nan());

    let checked: Vec<Label> = (0..hits.len())
        .into_par_iter()
        .map(|i| {
            let Some(hit) = hits[i] else {
                return Label::UNKNOWN;
            };
            if let Some(zb) = &zbuffer
                && hit.z_color_m > f64::from(zb[hit.pixel]) + cfg.occlusion_tol_m
            {
                return Label::UNKNOWN;
            }
            let pixel = origins[i].pixel as usize;
            if cfg.depth_edge
                && let Some(z) = depth_at(pixel)
            {
                let r = cfg.edge_radius_px as usize;
                let jump = cfg.edge_jump_ratio * z;
                // The centre (|Δz| = 0 ≤ jump) and pixels without depth (NaN compares
                // false) are no jump.
                let on_edge = any_row_in_square(pixel, depth_w, depth_h, r, |row| {
                    depth_table_m[row].iter().any(|&zn| (zn - z).abs() > jump)
                });
                if on_edge {
                    return Label::UNKNOWN;
                }
            }
            if cfg.min_probability > 0.0
                && let Some(probs) = &labels.probs
                && probs[hit.pixel] < cfg.min_probability
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
    let voted = (0..hits.len())
        .into_par_iter()
        .map(|i| {
            let own = checked[i];
            let (Some(hit), Some(own_class)) = (hits[i], own.class()) else {
                return own;
            };
            let r = cfg.boundary_radius_px as usize;
            // The centre holds `own` (the checks only ever make a label unknown), so
            // scanning whole rows of the square is the same test.
            let (w, h) = (labels.width as usize, labels.height as usize);
            let near_change = any_row_in_square(hit.pixel, w, h, r, |row| {
                labels.labels[row].iter().any(|&l| l != own)
            });
            if !near_change {
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
/// splat squares of all points; +∞ where no point lands.
fn splat_zbuffer(hits: &[Option<Hit>], labels: &LabelImage, cfg: &ProjectConfig) -> Vec<f32> {
    let (w, h) = (labels.width as usize, labels.height as usize);
    let mut zb = vec![f32::INFINITY; w * h];
    let r = cfg.splat_radius_px as usize;
    for hit in hits.iter().flatten() {
        let z = hit.z_color_m as f32;
        let (u, v) = (hit.u as usize, hit.v as usize);
        for vn in v.saturating_sub(r)..=(v + r).min(h - 1) {
            for un in u.saturating_sub(r)..=(u + r).min(w - 1) {
                let cell = &mut zb[vn * w + un];
                if z < *cell {
                    *cell = z;
                }
            }
        }
    }
    zb
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
