//! The per-camera projection: naive look-up and the DSA checks (ALGORITHM.md §3).

use bodyseg_calib::RgbdCamera;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label, LabelImage, NUM_CLASSES, PointOrigin};
use rayon::prelude::*;

use crate::color::{ColorProjection, Hits, HitsView, NO_HIT};
use crate::{ProjectConfig, ProjectError, ProjectMode};

/// Points per parallel task of the per-point passes: rayon's per-task cost (~µs) stays
/// small against the work, and two cores still get several tasks per camera.
pub(crate) const POINTS_PER_CHUNK: usize = 8192;

/// Labels of one camera's depth points, in their order (ALGORITHM.md §3).
///
/// - `depth_points_m`: the points in the depth sensor frame, metres (as
///   `bodyseg_calib::back_project` gives them with `CloudFrame::Depth`);
/// - `origins`: each point's depth pixel (only `pixel` is read);
/// - `depth_raw`: the raw depth image they came from (depth sensor size), read by the
///   depth-edge test and the label-boundary vote;
/// - `labels`: the parser's label image (colour sensor size).
///
/// The nearest colour pixel is computed in f32 (see the `color` module: within 1e-3 px
/// of the f64 projection, so a point on a near-tie between two pixels may take either).
/// A point behind the colour camera or projecting outside the colour image is `unknown`
/// in both modes. In `dsa` mode, in this order, from the nearest colour pixel's label:
/// 1. *occlusion* — every point is splatted into a colour z-buffer (a square of
///    `splat_radius_px`, keeping the nearest z); a point more than
///    `occlusion_tol_m + occlusion_tol_ratio · z` behind the z-buffer's z at its pixel is
///    `unknown`;
/// 2. *depth edge* — a point with a neighbouring depth pixel (square of
///    `edge_radius_px`) whose depth differs by more than `edge_jump_ratio · z` is
///    `unknown` (neighbours without a measurement are not a jump);
/// 3. *probability* — with `min_probability > 0` and probabilities in the label image,
///    a label below it is `unknown`;
/// 4. *label boundary* — a labelled point whose colour pixel has a different label
///    within `boundary_radius_px` takes the label held by strictly more of its labelled,
///    depth-consistent (`|Δz| ≤ edge_jump_ratio · z`) 8-neighbours in the depth image
///    than any other label; the vote reads the labels after steps 1–3, so it is one
///    deterministic pass. Here the neighbours are the adjacent depth pixels (points from
///    every pixel); [`crate::FrameProjector`] uses the neighbours on its stride's grid.
pub fn project_labels(
    camera: &RgbdCamera,
    depth_points_m: &[Vec3],
    origins: &[PointOrigin],
    depth_raw: &[u16],
    labels: &LabelImage,
    cfg: &ProjectConfig,
) -> Result<Vec<Label>, ProjectError> {
    cfg.validate()?;
    check_images(camera, depth_raw, labels)?;
    check_points(camera, depth_points_m, origins)?;

    let n = depth_points_m.len();
    let color = ColorProjection::new(camera);
    let mut hits = Hits::zeroed(n);
    let mut out = vec![Label::UNKNOWN; n];
    depth_points_m
        .par_chunks(POINTS_PER_CHUNK)
        .zip(hits.u.par_chunks_mut(POINTS_PER_CHUNK))
        .zip(hits.v.par_chunks_mut(POINTS_PER_CHUNK))
        .zip(hits.z_color_m.par_chunks_mut(POINTS_PER_CHUNK))
        .zip(out.par_chunks_mut(POINTS_PER_CHUNK))
        .for_each(|((((points, u), v), z), out)| {
            // Structure of arrays, so the projection loop vectorises.
            let x: Vec<f32> = points.iter().map(|p| p[0]).collect();
            let y: Vec<f32> = points.iter().map(|p| p[1]).collect();
            let zd: Vec<f32> = points.iter().map(|p| p[2]).collect();
            color.project_batch(&x, &y, &zd, u, v, z);
            naive_labels(u, v, labels, out);
        });
    if cfg.mode == ProjectMode::Dsa {
        let lut = depth_lut(camera);
        apply_dsa(
            camera,
            &lut,
            hits.view(),
            origins,
            depth_raw,
            labels,
            cfg,
            1,
            &mut DsaScratch::default(),
            &mut out,
        );
    }
    Ok(out)
}

/// `out[i]` = the label at colour pixel `(u[i], v[i])`, `unknown` where there is no hit.
pub(crate) fn naive_labels(u: &[u32], v: &[u32], labels: &LabelImage, out: &mut [Label]) {
    let w = labels.width as usize;
    for ((o, &u), &v) in out.iter_mut().zip(u).zip(v) {
        *o = if u == NO_HIT {
            Label::UNKNOWN
        } else {
            labels.labels[v as usize * w + u as usize]
        };
    }
}

/// Metres per raw depth value, see [`depth_lut`]. A fixed-size array: indexing it with a
/// `u16` needs no bounds check.
pub(crate) type DepthLut = [f64; 1 << 16];

/// Depth in metres of every raw value (`RgbdCamera::depth_m`), NaN for 0 and for
/// depths ≤ 0 after the shift: one division per raw value instead of one per pixel.
/// Non-decreasing where not NaN, and NaN only on a prefix (`depth_m` is monotonic).
pub(crate) fn depth_lut(camera: &RgbdCamera) -> Box<DepthLut> {
    let lut: Vec<f64> = (0..=u16::MAX)
        .map(|raw| camera.depth_m(raw).filter(|&z| z > 0.0).unwrap_or(f64::NAN))
        .collect();
    lut.into_boxed_slice()
        .try_into()
        .expect("one entry per u16")
}

/// Buffers of [`apply_dsa`] for one camera, kept from one frame to the next by
/// [`crate::FrameProjector`] so that they are neither allocated nor page-faulted per
/// frame (a fresh one works too).
#[derive(Debug, Default)]
pub(crate) struct DsaScratch {
    /// The z-buffer, all +∞ between calls (see [`ZBuffer`]).
    zbuffer: Vec<f32>,
    /// Depth-edge flags per depth pixel and the min/max filters behind them.
    edge: EdgeScratch,
    /// Labels before the vote, per depth pixel.
    by_pixel: Vec<Label>,
    /// Per chunk of points: the (chunk-local) indices of the points the vote looks at.
    candidates: Vec<Vec<u32>>,
}

/// Turns the naive labels `out` of one camera's points into the DSA labels (steps 1–4 of
/// [`project_labels`]); `hits` and `origins` are those points'. `lut` is
/// [`depth_lut`] of `camera`; `stride` is the back-projection's (points on every
/// `stride`-th pixel and row): the vote's neighbours are the points of that grid.
///
/// Steps 1–3 and the vote's label-change test run in one pass over the points, which
/// also records the labels per depth pixel (in parallel when the origins' pixels are
/// strictly increasing, as back-projection gives them) and the points the vote has to
/// look at; the vote then visits only those.
#[allow(clippy::too_many_arguments)]
pub(crate) fn apply_dsa(
    camera: &RgbdCamera,
    lut: &DepthLut,
    hits: HitsView<'_>,
    origins: &[PointOrigin],
    depth_raw: &[u16],
    labels: &LabelImage,
    cfg: &ProjectConfig,
    stride: usize,
    scratch: &mut DsaScratch,
    out: &mut [Label],
) {
    let DsaScratch {
        zbuffer,
        edge,
        by_pixel,
        candidates,
    } = scratch;
    let n = out.len();
    let color_w = labels.width as usize;
    let (color_h, image) = (labels.height as usize, &labels.labels[..]);
    let depth_w = camera.depth.width as usize;
    let depth_h = camera.depth.height as usize;
    let vote_on = cfg.label_boundary;
    let r_vote = cfg.boundary_radius_px as usize;

    // The z-buffer (serial) and the per-image tables (parallel) at once.
    let ((zbuffer, on_edge), blocks) = rayon::join(
        || {
            rayon::join(
                || {
                    cfg.occlusion.then(|| {
                        ZBuffer::splat(hits, cfg.splat_radius_px as usize, &camera.color, zbuffer)
                    })
                },
                || {
                    cfg.depth_edge.then(|| {
                        edge.compute(
                            depth_raw,
                            lut,
                            (depth_w, depth_h),
                            cfg.edge_radius_px as usize,
                            cfg.edge_jump_ratio,
                        )
                    })
                },
            )
        },
        || vote_on.then(|| UniformBlocks::new(image, color_w, color_h)),
    );
    let probs = labels
        .probs
        .as_deref()
        .filter(|_| cfg.min_probability > 0.0);

    // Chunks of points; with strictly increasing origins, chunk k's points own the depth
    // pixels from its first point's up to the next chunk's first point's.
    let chunk = POINTS_PER_CHUNK;
    let n_chunks = n.div_ceil(chunk);
    let sorted = vote_on && origins.windows(2).all(|p| p[0].pixel < p[1].pixel);
    if vote_on {
        by_pixel.resize(depth_w * depth_h, Label::UNKNOWN);
        if !sorted {
            by_pixel.fill(Label::UNKNOWN);
        }
    }
    candidates.resize_with(n_chunks, Vec::new);
    let mut pixel_parts: Vec<Option<(usize, &mut [Label])>> = Vec::with_capacity(n_chunks);
    {
        let mut rest = &mut by_pixel[..];
        let mut base = 0;
        for k in 0..n_chunks {
            if !sorted {
                pixel_parts.push(None);
                continue;
            }
            let end = if k + 1 < n_chunks {
                origins[(k + 1) * chunk].pixel as usize
            } else {
                depth_w * depth_h
            };
            let (head, tail) = rest.split_at_mut(end - base);
            pixel_parts.push(Some((base, head)));
            rest = tail;
            base = end;
        }
    }

    // Steps 1–3 (they only ever make a label unknown; points without a hit are unknown
    // already) and the vote's candidates.
    let checks = Checks {
        zbuffer: zbuffer.as_ref(),
        on_edge,
        probs,
        color_w,
        color_h,
        image,
        blocks: blocks.as_ref(),
        r_vote,
        tol_m: cfg.occlusion_tol_m,
        tol_ratio: cfg.occlusion_tol_ratio,
        min_probability: cfg.min_probability,
    };
    out.par_chunks_mut(chunk)
        .zip(candidates.par_iter_mut())
        .zip(pixel_parts.into_par_iter())
        .enumerate()
        .for_each(|(k, ((out, cands), pixels))| {
            let range = k * chunk..k * chunk + out.len();
            cands.clear();
            checks.run(
                hits.slice(range.clone()),
                &origins[range],
                out,
                pixels,
                cands,
            );
        });
    if !vote_on {
        return;
    }
    if !sorted {
        for (o, &l) in origins.iter().zip(out.iter()) {
            by_pixel[o.pixel as usize] = l;
        }
    }

    // Step 4 on the candidates, from the labels before the vote (`by_pixel`), while the
    // z-buffer is reset (serial) beside it.
    let by_pixel = &by_pixel[..];
    rayon::join(
        || drop(zbuffer),
        || {
            out.par_chunks_mut(chunk)
                .zip(candidates.par_iter())
                .enumerate()
                .for_each(|(k, (out, cands))| {
                    let origins = &origins[k * chunk..];
                    for &i in cands {
                        let i = i as usize;
                        let own = out[i].class();
                        if let Some(best) = vote(
                            origins[i].pixel as usize,
                            by_pixel,
                            (depth_raw, lut),
                            (depth_w, depth_h, stride),
                            cfg.edge_jump_ratio,
                        ) && Some(best) != own
                        {
                            out[i] = Label::from(best);
                        }
                    }
                });
        },
    );
}

/// The per-point checks of [`apply_dsa`] (steps 1–3 and the vote's label-change test),
/// each `None` when switched off.
struct Checks<'a> {
    zbuffer: Option<&'a ZBuffer<'a>>,
    on_edge: Option<&'a [bool]>,
    probs: Option<&'a [f32]>,
    color_w: usize,
    color_h: usize,
    image: &'a [Label],
    blocks: Option<&'a UniformBlocks>,
    r_vote: usize,
    tol_m: f64,
    tol_ratio: f64,
    min_probability: f32,
}

impl Checks<'_> {
    /// Steps 1–3 on one chunk of points; with `pixels = Some((first pixel, labels))`,
    /// the labels after them per depth pixel of the chunk's pixel range (unknown where
    /// no point); with the vote on, the chunk-local indices of the points whose colour
    /// pixel has a label change within the vote's radius pushed to `candidates`.
    fn run(
        &self,
        hits: HitsView<'_>,
        origins: &[PointOrigin],
        out: &mut [Label],
        pixels: Option<(usize, &mut [Label])>,
        candidates: &mut Vec<u32>,
    ) {
        let n = out.len();
        let (hu, hv, hz, origins) = (
            &hits.u[..n],
            &hits.v[..n],
            &hits.z_color_m[..n],
            &origins[..n],
        );
        if let Some(edge) = self.on_edge {
            for (label, o) in out.iter_mut().zip(origins) {
                if edge[o.pixel as usize] {
                    *label = Label::UNKNOWN;
                }
            }
        }
        if let Some(zb) = self.zbuffer {
            for i in 0..n {
                if hu[i] != NO_HIT && {
                    let nearest = f64::from(zb.at(hu[i], hv[i]));
                    f64::from(hz[i]) > nearest + self.tol_m + self.tol_ratio * nearest
                } {
                    out[i] = Label::UNKNOWN;
                }
            }
        }
        if let Some(probs) = self.probs {
            for i in 0..n {
                if hu[i] != NO_HIT
                    && probs[hv[i] as usize * self.color_w + hu[i] as usize] < self.min_probability
                {
                    out[i] = Label::UNKNOWN;
                }
            }
        }
        if let Some((base, pixels)) = pixels {
            pixels.fill(Label::UNKNOWN);
            for (o, &l) in origins.iter().zip(out.iter()) {
                pixels[o.pixel as usize - base] = l;
            }
        }
        let Some(blocks) = self.blocks else {
            return;
        };
        let r = self.r_vote;
        for i in 0..n {
            let own = out[i];
            if own.is_unknown() {
                continue;
            }
            // `own` is the label at the hit pixel (steps 1–3 only make labels unknown),
            // so "a different label within the radius" is "the square holds a label
            // other than `own`".
            let (u, v) = (hu[i] as usize, hv[i] as usize);
            if blocks.may_hold_other(u, v, r, own)
                && square_holds_other(self.image, self.color_w, self.color_h, (u, v), r, own)
            {
                // Fits: a chunk holds `POINTS_PER_CHUNK` points.
                candidates.push(i as u32);
            }
        }
    }
}

/// The label-boundary vote at depth pixel `pixel`: the class held by strictly more of its
/// labelled, depth-consistent (`|Δz| ≤ ratio · z`) 8-neighbours than any other, if any.
/// `by_pixel` holds the labels before the vote and `depth_raw` the raw depths of a
/// `w × h` depth image, `lut` their metres (NaN: none).
fn vote(
    pixel: usize,
    by_pixel: &[Label],
    (depth_raw, lut): (&[u16], &DepthLut),
    (w, h, step): (usize, usize, usize),
    ratio: f64,
) -> Option<Class> {
    let depth_m = |p: usize| lut[usize::from(depth_raw[p])];
    let z = depth_m(pixel);
    if z.is_nan() {
        return None;
    }
    let tol = ratio * z;
    let mut counts = [0u32; NUM_CLASSES];
    for n in grid_neighbours(pixel, w, h, step) {
        // NaN (no depth) fails the comparison.
        if let Some(c) = by_pixel[n].class()
            && (depth_m(n) - z).abs() <= tol
        {
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
    // `best < NUM_CLASSES`, a class id.
    clear.then(|| Class::from_id(best as u8)).flatten()
}

/// Per 8×8 block of a label image: its label when all its pixels hold it, else unknown
/// (also for blocks cut by the image border). A cheap exact pre-test for the
/// label-change square of the vote: most points lie inside uniform regions.
struct UniformBlocks {
    /// Blocks per row.
    bw: usize,
    /// Per block its label if uniform, else [`Label::UNKNOWN`] (which the tests below
    /// never take for a point's own label).
    labels: Vec<Label>,
    /// Per block: its label when it and its (up to 8) neighbouring blocks are all
    /// uniformly that label, else unknown. The square of radius ≤ [`UniformBlocks::SIDE`]
    /// around any pixel of the block lies within those blocks: one look-up per point.
    around: Vec<Label>,
}

impl UniformBlocks {
    /// Side of a block, pixels: one 8-byte word per block row.
    const SIDE: usize = 8;

    fn new(image: &[Label], w: usize, h: usize) -> Self {
        let s = Self::SIDE;
        let (bw, bh) = (w.div_ceil(s), h.div_ceil(s));
        let mut labels = vec![Label::UNKNOWN; bw * bh];
        // Per block, the label when its 3 blocks of the row (itself and the ones left
        // and right of it, where they exist) are all uniformly that label.
        let mut in_row = vec![Label::UNKNOWN; bw * bh];
        labels
            .par_chunks_mut(bw.max(1))
            .zip(in_row.par_chunks_mut(bw.max(1)))
            .enumerate()
            .for_each(|(by, (out, in_row))| {
                if (by + 1) * s > h {
                    return;
                }
                // Whole blocks of this block row (a block cut by the right border stays
                // unknown). Per column, the OR over the block row's rows of (label XOR
                // the top row's label): a plain byte loop, which vectorises; then a
                // block is uniform when its 8 columns are 0 there and its top row holds
                // one label.
                let rows = &image[by * s * w..(by + 1) * s * w];
                let top = &rows[..w];
                let mut diff = vec![0u8; w];
                for row in rows.chunks_exact(w).skip(1) {
                    for ((d, &l), &t) in diff.iter_mut().zip(row).zip(top) {
                        *d |= l.id() ^ t.id();
                    }
                }
                for ((out, d), t) in out
                    .iter_mut()
                    .zip(diff.chunks_exact(s))
                    .zip(top.chunks_exact(s))
                {
                    let first = u64::from_le_bytes([t[0].id(); 8]);
                    let d = u64::from_le_bytes(d.try_into().expect("8 columns"));
                    if d == 0 && word(t) == first {
                        *out = t[0];
                    }
                }
                for (bx, o) in in_row.iter_mut().enumerate() {
                    let l = out[bx];
                    let left = bx == 0 || out[bx - 1] == l;
                    let right = bx + 1 == out.len() || out[bx + 1] == l;
                    *o = if left && right { l } else { Label::UNKNOWN };
                }
            });
        // Then the same along columns, over the rows' results.
        let mut around = vec![Label::UNKNOWN; bw * bh];
        around
            .par_chunks_mut(bw.max(1))
            .enumerate()
            .for_each(|(by, out)| {
                let row = |y: usize| &in_row[y * bw..(y + 1) * bw];
                let here = row(by);
                let above = row(by.saturating_sub(1));
                let below = row((by + 1).min(bh - 1));
                for (((o, &l), &a), &b) in out.iter_mut().zip(here).zip(above).zip(below) {
                    *o = if a == l && b == l { l } else { Label::UNKNOWN };
                }
            });
        UniformBlocks { bw, labels, around }
    }

    /// False when the square of radius `r` around `(u, v)` (inside the image) certainly
    /// holds `own` (a class, not unknown) only: every block it touches is uniformly
    /// `own`.
    #[inline]
    fn may_hold_other(&self, u: usize, v: usize, r: usize, own: Label) -> bool {
        let s = Self::SIDE;
        if r <= s {
            return self.around[(v / s) * self.bw + u / s] != own;
        }
        let (bx0, bx1) = (u.saturating_sub(r) / s, (u + r) / s);
        let (by0, by1) = (v.saturating_sub(r) / s, (v + r) / s);
        if bx1 >= self.bw {
            return true;
        }
        let other = |by: usize, bx: usize| self.labels.get(by * self.bw + bx) != Some(&own);
        (by0..=by1).any(|by| (bx0..=bx1).any(|bx| other(by, bx)))
    }
}

/// The 8 labels of `b` as one little-endian word (one byte per label).
#[inline]
fn word(b: &[Label]) -> u64 {
    let b: &[Label; 8] = b.try_into().expect("8 labels");
    u64::from_le_bytes([
        b[0].id(),
        b[1].id(),
        b[2].id(),
        b[3].id(),
        b[4].id(),
        b[5].id(),
        b[6].id(),
        b[7].id(),
    ])
}

/// Whether the square of radius `r` around pixel `(u, v)` of a `w × h` label image
/// (clipped) holds a label other than `own`.
fn square_holds_other(
    image: &[Label],
    w: usize,
    h: usize,
    (u, v): (usize, usize),
    r: usize,
    own: Label,
) -> bool {
    let (u0, u1) = (u.saturating_sub(r), (u + r).min(w - 1));
    let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
    let len = u1 - u0 + 1;
    let last = v1 * w + u0;
    if len <= 8 && last + 8 <= image.len() {
        // Fast path (radius ≤ 3, the default 2): each row segment as one 8-byte word,
        // XOR-ed with `own` in every byte; the bytes past the segment are masked off.
        let own_bytes = u64::from_le_bytes([own.id(); 8]);
        let mask = u64::MAX >> (8 * (8 - len));
        let (mut diff, mut start) = (0, v0 * w + u0);
        while start <= last {
            diff |= word(&image[start..start + 8]) ^ own_bytes;
            start += w;
        }
        return diff & mask != 0;
    }
    (v0..=v1).any(|vn| image[vn * w + u0..=vn * w + u1].iter().any(|&l| l != own))
}

/// The 8 neighbours of `pixel` on a grid of spacing `step` (row-major index in a `w × h`
/// image), clipped to the image.
fn grid_neighbours(pixel: usize, w: usize, h: usize, step: usize) -> impl Iterator<Item = usize> {
    let (u, v) = (pixel % w, pixel / w);
    let offsets = [-1i64, 0, 1];
    offsets.into_iter().flat_map(move |dv| {
        offsets.into_iter().filter_map(move |du| {
            let (un, vn) = (u as i64 + du * step as i64, v as i64 + dv * step as i64);
            let inside = (du, dv) != (0, 0) && un >= 0 && vn >= 0 && un < w as i64 && vn < h as i64;
            inside.then(|| vn as usize * w + un as usize)
        })
    })
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

/// Nearest colour-frame depth per colour pixel over the splat squares of all points, on
/// a buffer of the colour image's size plus a margin of `r` pixels on every side (and one
/// more column), so that neither a splat nor a query clips.
///
/// The square is split in two: each point is splatted into the `2r + 1` cells of its
/// row centred on its pixel (for r = 1 one 4-wide SIMD min, the 4th lane +∞), and a query
/// takes the nearest over the `2r + 1` cells of its column centred on its pixel: the
/// nearest over the square, with `2r + 1` loads instead of `(2r + 1)²`.
///
/// Depths are stored as f32 metres, +∞ for "no point". The buffer is borrowed all +∞
/// and given back all +∞ (on drop, the splatted cells are reset): kept across frames, it
/// is neither allocated nor cleared per frame.
struct ZBuffer<'a> {
    /// Row length of `z_m`: the image width plus 2r + 1.
    stride: usize,
    /// Splat radius.
    r: usize,
    /// Per cell (row `v + r`, column `c`) the depth of the nearest point on row v whose
    /// column is within r of `c - r`.
    z_m: &'a mut [f32],
    hits: HitsView<'a>,
}

/// The smaller of `a` and `b` (`b` if equal): one `minss`, which `f32::min` is not (it
/// handles NaN, which the z-buffer never holds).
#[inline(always)]
fn min_f32(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

impl<'a> ZBuffer<'a> {
    /// Splats the hits; [`ZBuffer::at`] then takes the nearest over the square of radius
    /// `r` around a pixel, the same as splatting every point's square. The hits' z are
    /// positive and finite (`ColorProjection` gives no hit otherwise). `buffer` is all
    /// +∞ (any length).
    fn splat(
        hits: HitsView<'a>,
        r: usize,
        color: &bodyseg_calib::Intrinsics,
        buffer: &'a mut Vec<f32>,
    ) -> Self {
        let stride = color.width as usize + 2 * r + 1;
        let len = stride * (color.height as usize + 2 * r);
        if buffer.len() != len {
            buffer.clear();
            buffer.resize(len, f32::INFINITY);
        }
        let side = 2 * r + 1;
        for ((&u, &v), &z) in hits.u.iter().zip(hits.v).zip(hits.z_color_m) {
            if u != NO_HIT {
                // Columns u - r ..= u + r of row v, in the padded buffer.
                let start = (v as usize + r) * stride + u as usize;
                if r == 1 {
                    let cells: &mut [f32; 4] =
                        (&mut buffer[start..start + 4]).try_into().expect("4 wide");
                    let z4 = [z, z, z, f32::INFINITY];
                    for (c, z) in cells.iter_mut().zip(z4) {
                        *c = min_f32(*c, z);
                    }
                } else {
                    for c in &mut buffer[start..start + side] {
                        *c = min_f32(*c, z);
                    }
                }
            }
        }
        ZBuffer {
            stride,
            r,
            z_m: buffer,
            hits,
        }
    }

    /// The z-buffer at colour pixel (u, v), one of the points' pixels (so the square
    /// holds at least that point, and the result is finite).
    #[inline]
    fn at(&self, u: u32, v: u32) -> f32 {
        // Column u of rows v - r ..= v + r, in the padded buffer.
        let top = v as usize * self.stride + u as usize + self.r;
        if self.r == 1 {
            let s = self.stride;
            return min_f32(
                min_f32(self.z_m[top], self.z_m[top + s]),
                self.z_m[top + 2 * s],
            );
        }
        (0..=2 * self.r).fold(f32::INFINITY, |b, k| {
            min_f32(b, self.z_m[top + k * self.stride])
        })
    }
}

impl Drop for ZBuffer<'_> {
    fn drop(&mut self) {
        let (r, stride) = (self.r, self.stride);
        for (&u, &v) in self.hits.u.iter().zip(self.hits.v) {
            if u != NO_HIT {
                let start = (v as usize + r) * stride + u as usize;
                if r == 1 {
                    // All 4 lanes of the splat (the 4th is reset too, harmlessly).
                    let cells: &mut [f32; 4] = (&mut self.z_m[start..start + 4])
                        .try_into()
                        .expect("4 wide");
                    *cells = [f32::INFINITY; 4];
                } else {
                    self.z_m[start..start + 2 * r + 1].fill(f32::INFINITY);
                }
            }
        }
    }
}

/// Per depth pixel: whether the depth-edge test flags it, i.e. it has depth z and some
/// pixel of the square of radius `r` around it (clipped) has depth zn with
/// `|zn - z| > ratio · z` (pixels without depth never do). `lut` is [`depth_lut`].
///
/// Exactly the per-pixel test: the rounded difference is monotonic in zn, so testing the
/// window's largest and smallest depths is the same; and metres are a non-decreasing
/// function of the raw value (`lut`), so those are the depths of the window's largest
/// and smallest raw values. The min/max filter (separable) therefore runs on the raw
/// `u16`s, 8 to a SIMD register.
#[cfg(test)]
fn edge_map(
    depth_raw: &[u16],
    lut: &DepthLut,
    w: usize,
    h: usize,
    r: usize,
    ratio: f64,
) -> Vec<bool> {
    EdgeScratch::default()
        .compute(depth_raw, lut, (w, h), r, ratio)
        .to_vec()
}

/// The buffers of [`edge_map`]: its result and the min / max filters of the raw depths.
#[derive(Debug, Default)]
pub(crate) struct EdgeScratch {
    lo: Vec<u16>,
    hi: Vec<u16>,
    on_edge: Vec<bool>,
}

impl EdgeScratch {
    /// [`edge_map`] into these buffers (every entry overwritten).
    fn compute(
        &mut self,
        depth_raw: &[u16],
        lut: &DepthLut,
        (w, h): (usize, usize),
        r: usize,
        ratio: f64,
    ) -> &[bool] {
        let EdgeScratch { lo, hi, on_edge } = self;
        on_edge.resize(w * h, false);
        if w == 0 || h == 0 {
            return on_edge;
        }
        // Raw values with a depth are exactly those from the first one with a depth on
        // (non-decreasing metres: once > 0, always > 0).
        let first_valid = lut.iter().position(|z| !z.is_nan()).unwrap_or(lut.len()) as u32;
        // Pixels without depth are skipped: u16::MAX for the minimum, 0 for the maximum
        // (a pixel with depth is in its own window, so they never change its result).
        lo.resize(w * h, 0);
        hi.resize(w * h, 0);
        lo.par_chunks_mut(w)
            .zip(hi.par_chunks_mut(w))
            .zip(depth_raw.par_chunks(w))
            .for_each(|((lo, hi), src)| {
                for ((l, h), &raw) in lo.iter_mut().zip(hi.iter_mut()).zip(src) {
                    let valid = u32::from(raw) >= first_valid;
                    *l = if valid { raw } else { u16::MAX };
                    *h = if valid { raw } else { 0 };
                }
                let (l0, h0) = (lo.to_vec(), hi.to_vec());
                for k in 1..=r.min(w - 1) {
                    min_into(&mut lo[k..], &l0[..w - k]);
                    min_into(&mut lo[..w - k], &l0[k..]);
                    max_into(&mut hi[k..], &h0[..w - k]);
                    max_into(&mut hi[..w - k], &h0[k..]);
                }
            });
        let (lo, hi) = (&lo[..], &hi[..]);
        on_edge.par_chunks_mut(w).enumerate().for_each(|(v, dst)| {
            let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
            let mut a = lo[v0 * w..(v0 + 1) * w].to_vec();
            let mut b = hi[v0 * w..(v0 + 1) * w].to_vec();
            for vn in v0 + 1..=v1 {
                min_into(&mut a, &lo[vn * w..(vn + 1) * w]);
                max_into(&mut b, &hi[vn * w..(vn + 1) * w]);
            }
            for (((d, &raw), &a), &b) in dst
                .iter_mut()
                .zip(&depth_raw[v * w..(v + 1) * w])
                .zip(&a)
                .zip(&b)
            {
                // a ≤ raw ≤ b, all with depth; the largest |zn − z| is zb − z or z − za.
                let (z, za, zb) = (
                    lut[usize::from(raw)],
                    lut[usize::from(a)],
                    lut[usize::from(b)],
                );
                let jump = ratio * z;
                *d = u32::from(raw) >= first_valid
                    && ((zb - z).abs() > jump || (za - z).abs() > jump);
            }
        });
        on_edge
    }
}

fn min_into(dst: &mut [u16], src: &[u16]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = (*d).min(s);
    }
}

fn max_into(dst: &mut [u16], src: &[u16]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = (*d).max(s);
    }
}

/// The image sizes of one camera's inputs: the depth image the depth sensor's, the label
/// image the colour sensor's and consistent.
pub(crate) fn check_images(
    camera: &RgbdCamera,
    depth_raw: &[u16],
    labels: &LabelImage,
) -> Result<(), ProjectError> {
    let name = || camera.name.clone();
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
    labels.validate().map_err(|cause| ProjectError::LabelImage {
        camera: name(),
        cause,
    })
}

fn check_points(
    camera: &RgbdCamera,
    depth_points_m: &[Vec3],
    origins: &[PointOrigin],
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
mod tests;
