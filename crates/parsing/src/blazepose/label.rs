//! Labelling the pixels of one person from its bones and mask, and merging people.

use super::bone::{PreparedBone, RuleConfig, bones};
use super::decode::DecodedPose;
use super::model::INPUT;
use super::roi::{P2, Roi, dot, sub};
use bodyseg_core::{Label, LabelImage};
use rayon::prelude::*;

/// One person's labels over a window of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct PersonLabels {
    /// Window: columns `u0..u1`, rows `v0..v1` of the image.
    pub u0: usize,
    /// End column (exclusive).
    pub u1: usize,
    /// First row.
    pub v0: usize,
    /// End row (exclusive).
    pub v1: usize,
    /// Class id per window pixel, row-major; 0 where not this person's.
    pub class: Vec<u8>,
    /// Probability of that class, [0, 1]: on the person's pixels the mask value × the
    /// bone-margin confidence; elsewhere the background's, 1 − the mask value.
    pub prob: Vec<f32>,
    /// The best bone score (smaller = nearer); +∞ where not this person's.
    pub score: Vec<f32>,
    /// The person's depth from the camera, metres, when known (from its region): the
    /// person in front wins where two overlap ([`merge_people`]).
    pub depth_m: Option<f64>,
}

/// The mask at image point `q`, bilinear on the ROI grid (tensor pixel centres), 0 outside
/// the ROI. `axes` = `pose.roi.axes()`, computed once by the caller.
pub(crate) fn mask_at(pose: &DecodedPose, axes: (P2, P2), q: P2) -> f64 {
    let (right, down) = axes;
    let d = sub(q, pose.roi.centre_px);
    let k = INPUT as f64 / pose.roi.side_px;
    let tx = dot(d, right) * k + INPUT as f64 / 2.0 - 0.5;
    let ty = dot(d, down) * k + INPUT as f64 / 2.0 - 0.5;
    let last = (INPUT - 1) as f64;
    if !(-0.5..=last + 0.5).contains(&tx) || !(-0.5..=last + 0.5).contains(&ty) {
        return 0.0;
    }
    let (tx, ty) = (tx.clamp(0.0, last), ty.clamp(0.0, last));
    // In [0, 255] after the clamp: the casts are the floor (without a libm call).
    let ix = (tx as usize).min(INPUT - 2);
    let iy = (ty as usize).min(INPUT - 2);
    let (fx, fy) = (tx - ix as f64, ty - iy as f64);
    let m = |x: usize, y: usize| f64::from(pose.mask[y * INPUT + x]);
    (m(ix, iy) * (1.0 - fx) + m(ix + 1, iy) * fx) * (1.0 - fy)
        + (m(ix, iy + 1) * (1.0 - fx) + m(ix + 1, iy + 1) * fx) * fy
}

/// The window of the image a pose's ROI covers: its bounding box, clipped; `None` when it
/// misses the image.
pub(crate) fn roi_window(
    roi: &Roi,
    width: usize,
    height: usize,
) -> Option<(usize, usize, usize, usize)> {
    let corners =
        [[0.0, 0.0], [256.0, 0.0], [0.0, 256.0], [256.0, 256.0]].map(|t| roi.tensor_to_image(t));
    let lo = |k: usize| corners.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
    let hi = |k: usize| {
        corners
            .iter()
            .map(|c| c[k])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    if !(lo(0).is_finite() && lo(1).is_finite() && hi(0).is_finite() && hi(1).is_finite()) {
        return None;
    }
    let u0 = lo(0).floor().max(0.0) as usize;
    let v0 = lo(1).floor().max(0.0) as usize;
    let u1 = ((hi(0).ceil() + 1.0).max(0.0) as usize).min(width);
    let v1 = ((hi(1).ceil() + 1.0).max(0.0) as usize).min(height);
    (u1 > u0 && v1 > v0).then_some((u0, u1, v0, v1))
}

/// Side of the pixel blocks in which [`label_person`] culls bones, px.
pub(crate) const BLOCK: usize = 8;

/// The class of a pixel from its per-class scores: (class, e1, e2) with e1 ≤ e2 the two
/// smallest scores (e2 = e1 + 10 with one class).
pub(crate) fn best_two(per_class: &[f64; 7]) -> (usize, f64, f64) {
    let (mut c1, mut e1, mut e2) = (0usize, f64::INFINITY, f64::INFINITY);
    for (c, &e) in per_class.iter().enumerate() {
        if e < e1 {
            e2 = e1;
            e1 = e;
            c1 = c;
        } else if e < e2 {
            e2 = e;
        }
    }
    if !e2.is_finite() {
        e2 = e1 + 10.0;
    }
    (c1, e1, e2)
}

/// Labels one person over the bounding box of its ROI in an image of `width`×`height`
/// (§4 of the note). `None` when the ROI misses the image or the pose has no bone.
///
/// Every pixel is scored against the bones that can be nearest or second nearest there:
/// the window is cut into 8×8 blocks, and a bone whose score at the block centre minus
/// the block's half-diagonal (a score moves by at most distance / body scale) exceeds the
/// second-smallest class upper bound of the block is skipped. The result equals scoring
/// every bone (a property test checks it against that reference).
pub fn label_person(
    pose: &DecodedPose,
    cfg: &RuleConfig,
    width: usize,
    height: usize,
) -> Option<PersonLabels> {
    if pose.mask.len() < INPUT * INPUT {
        return None;
    }
    let (u0, u1, v0, v1) = roi_window(&pose.roi, width, height)?;
    let bl: Vec<PreparedBone> = bones(pose, cfg, width, height)
        .iter()
        .map(PreparedBone::new)
        .collect();
    if bl.is_empty() {
        return None;
    }
    let ww = u1 - u0;
    let n = ww * (v1 - v0);
    let mut class = vec![0u8; n];
    let mut prob = vec![1.0f32; n];
    let mut score = vec![f32::INFINITY; n];
    let axes = pose.roi.axes();
    // Bands of BLOCK rows are labelled in parallel: every pixel's result depends only on
    // the pose, so the output is the same with any number of threads (a person of a
    // 960×540 view is ~20 ms of labelling on one core, the model runs ~20 ms each).
    let band = ww * BLOCK;
    class
        .par_chunks_mut(band)
        .zip(prob.par_chunks_mut(band))
        .zip(score.par_chunks_mut(band))
        .enumerate()
        .for_each(|(i, ((class, prob), score))| {
            let bv = v0 + i * BLOCK;
            let out = Band { class, prob, score };
            label_band(
                pose,
                cfg,
                &bl,
                axes,
                (u0, u1),
                (bv, (bv + BLOCK).min(v1)),
                out,
            );
        });
    Some(PersonLabels {
        u0,
        u1,
        v0,
        v1,
        class,
        prob,
        score,
        depth_m: None,
    })
}

/// One band's rows of [`label_person`]'s output (`class`, `prob`, `score` of rows
/// `bv..bv1`, window columns `u0..u1`).
struct Band<'a> {
    class: &'a mut [u8],
    prob: &'a mut [f32],
    score: &'a mut [f32],
}

/// Labels rows `bv..bv1` of a person's window (one band of 8×8 blocks, see
/// [`label_person`]) into `out`, whose index 0 is pixel (u0, bv).
fn label_band(
    pose: &DecodedPose,
    cfg: &RuleConfig,
    bl: &[PreparedBone],
    axes: (P2, P2),
    (u0, u1): (usize, usize),
    (bv, bv1): (usize, usize),
    out: Band<'_>,
) {
    let ww = u1 - u0;
    let mut mask = [0.0f64; BLOCK * BLOCK];
    let mut keep: Vec<usize> = Vec::with_capacity(bl.len());
    let mut lower_of = Vec::with_capacity(bl.len());
    for bu in (u0..u1).step_by(BLOCK) {
        let bu1 = (bu + BLOCK).min(u1);
        // The mask first: most of a window is not the person's.
        let mut any = false;
        for v in bv..bv1 {
            for u in bu..bu1 {
                let m = mask_at(pose, axes, [u as f64, v as f64]);
                mask[(v - bv) * BLOCK + (u - bu)] = m;
                out.prob[(v - bv) * ww + (u - u0)] = (1.0 - m).clamp(0.0, 1.0) as f32;
                any |= m >= cfg.mask_threshold;
            }
        }
        if !any {
            continue;
        }
        // Bounds of every bone's score over the block.
        let centre = [(bu + bu1 - 1) as f64 / 2.0, (bv + bv1 - 1) as f64 / 2.0];
        let half_diag = ((bu1 - bu) as f64).hypot((bv1 - bv) as f64) / 2.0;
        let mut upper = [f64::INFINITY; 7];
        lower_of.clear();
        for b in bl {
            let s = b.score(centre);
            let slack = half_diag / b.scale_px;
            let c = usize::from(b.class);
            upper[c] = upper[c].min(s + slack);
            lower_of.push(s - slack);
        }
        if lower_of.iter().all(|&l| l > cfg.max_score) {
            continue; // no pixel of the block is near enough to a bone
        }
        let (_, _, u_second) = best_two(&upper);
        let bound = if upper.iter().filter(|u| u.is_finite()).count() >= 2 {
            u_second
        } else {
            f64::INFINITY
        };
        keep.clear();
        keep.extend((0..bl.len()).filter(|&k| lower_of[k] <= bound));
        for v in bv..bv1 {
            for u in bu..bu1 {
                let m = mask[(v - bv) * BLOCK + (u - bu)];
                if m < cfg.mask_threshold {
                    continue;
                }
                let q = [u as f64, v as f64];
                let mut per_class = [f64::INFINITY; 7];
                for &k in &keep {
                    let b = &bl[k];
                    let s = b.score(q);
                    let c = usize::from(b.class);
                    per_class[c] = per_class[c].min(s);
                }
                let (c1, e1, e2) = best_two(&per_class);
                if e1 > cfg.max_score {
                    continue;
                }
                let conf = 1.0 - 0.5 * (-(e2 - e1) / cfg.margin_scale).exp();
                let k = (v - bv) * ww + (u - u0);
                out.class[k] = c1 as u8;
                out.prob[k] = (m * conf).clamp(0.0, 1.0) as f32;
                out.score[k] = e1 as f32;
            }
        }
    }
}

/// Two people whose depths differ by at most this are "side by side": where they overlap
/// in the image, the nearer bone decides, not the depth, metres. A person's depth is its
/// box centre's, and the bodies of two people one behind the other are more than a torso
/// apart (≈ 0.3 m), while a hand-over brings two box centres within ≈ 0.6 m.
pub const SIDE_BY_SIDE_M: f64 = 0.3;

/// The people of one view merged into a label image with probabilities. Where two people
/// overlap, the one in front wins (depths known and more than [`SIDE_BY_SIDE_M`] apart),
/// else the one with the smaller score (the nearer bone); ties go to the earlier person.
/// Pixels of no person are background, with probability 1 − the largest mask value there
/// (1 outside every window).
pub fn merge_people(width: usize, height: usize, people: &[PersonLabels]) -> LabelImage {
    let mut labels = vec![Label::BACKGROUND; width * height];
    let mut probs = vec![1.0f32; width * height];
    // Front to back (unknown depths last), stable: ties keep the given order.
    let mut order: Vec<usize> = (0..people.len()).collect();
    order.sort_by(|&a, &b| {
        let key = |p: &PersonLabels| p.depth_m.unwrap_or(f64::INFINITY);
        key(&people[a]).total_cmp(&key(&people[b]))
    });
    // Rows are merged in parallel: a pixel's result depends on that pixel of each person
    // alone, taken in `order`, so it is the same on any number of threads.
    labels
        .par_chunks_mut(width.max(1))
        .zip(probs.par_chunks_mut(width.max(1)))
        .enumerate()
        .for_each_init(
            // The row's best score and who won each pixel (index into `people`, for the
            // depth test).
            || (vec![f32::INFINITY; width], vec![usize::MAX; width]),
            |(best, owner), (v, (labels, probs))| {
                best.fill(f32::INFINITY);
                owner.fill(usize::MAX);
                for &index in &order {
                    let p = &people[index];
                    if !(p.v0..p.v1).contains(&v) {
                        continue;
                    }
                    let start = (v - p.v0) * (p.u1 - p.u0);
                    for u in p.u0..p.u1.min(width) {
                        let k = start + (u - p.u0);
                        if !p.score[k].is_finite() {
                            if owner[u] == usize::MAX {
                                probs[u] = probs[u].min(p.prob[k]);
                            }
                            continue;
                        }
                        let behind = owner[u] != usize::MAX
                            && match (people[owner[u]].depth_m, p.depth_m) {
                                (Some(front), Some(me)) => me - front > SIDE_BY_SIDE_M,
                                _ => false,
                            };
                        if !behind && p.score[k] < best[u] {
                            best[u] = p.score[k];
                            labels[u] = Label::from_id_or_unknown(p.class[k]);
                            probs[u] = p.prob[k];
                            owner[u] = index;
                        }
                    }
                }
            },
        );
    LabelImage {
        width: width as u32,
        height: height as u32,
        labels,
        probs: Some(probs),
    }
}
