//! The simulated 2D parser: predicted label images made from the exact ones by the
//! errors real parsing networks make (ALGORITHM.md §2–§3; the paper's SCHP observations).
//!
//! [`predict_labels`] turns the exact label image of one colour view into a prediction by
//! applying, in this order:
//! 1. **miss** — each small part instance (forearm + hand, or shin + foot, of one limb of one
//!    person) is missed with probability `miss_prob`: its pixels become background.
//! 2. **swap** — for each limb, with probability `swap_prob`, the elbow/knee appears moved
//!    along the limb: on one side of it (chosen at random) the limb's pixels within
//!    `swap_band_px` of the other segment take that segment's class (3↔4 arms, 5↔6 legs).
//! 3. **dilation** — head, torso, upper arms and upper legs grow by `part_dilation_px` into
//!    the background (nearest part wins); then lower arms and lower legs grow by
//!    `small_part_dilation_px` into everything (background and neighbouring labels).
//! 4. **jitter** — every label boundary moves by up to `boundary_jitter_px` along a smooth
//!    random displacement field (value noise, [`JITTER_CORRELATION_PX`] correlation length).
//!
//! Why this order: miss and swap are the network's *semantic* errors (which class a region
//! has), dilation and jitter its *localisation* errors (where it draws the boundaries), so
//! the latter act on the regions the former leave. A missed part is background that the
//! neighbours' dilation may then creep into, as into any background; it is missed before the
//! swap so a missed lower part leaves no joint boundary to swap across. A swapped band is
//! dilated as the class it now carries. Jitter comes last so that it also roughens the
//! boundaries dilation moved (it would otherwise be smoothed away by the dilation).
//!
//! # Conventions
//! - Images are row-major, `width * height` entries; pixel (u, v) = (column, row).
//! - Pixel sizes in [`ParserMistakesConfig`] are for a 1920-wide image and are scaled by
//!   `width / 1920`. Distances are Euclidean between pixel centres (exact distance
//!   transform, Felzenszwalb & Huttenlocher 2012, "Distance transforms of sampled
//!   functions").
//! - Randomness: every decision is a SplitMix64 hash of (seed, what, person, limb) or
//!   (seed, what, grid node), so the decision for one limb does not depend on who else is in
//!   view, and a prediction is a pure function of (truth, config, seed).
//! - Background (0) pixels of the truth stay background except where dilation or jitter move
//!   a body label onto them.

use crate::config::ParserMistakesConfig;
use crate::geometry::{Limb, Segment};
use crate::hash::mix;
use bodyseg_core::Class;

/// The exact 2D truth of one colour view, row-major, `width * height` entries each.
#[derive(Clone, Copy, Debug)]
pub struct TruthView<'a> {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Class id per pixel (ALGORITHM.md §0; 0 = background).
    pub labels: &'a [u8],
    /// Person id per pixel (1-based; 0 = no person).
    pub person: &'a [u8],
    /// Body segment id per pixel ([`crate::geometry::Segment::id`]; 0 = none).
    pub segment: &'a [u8],
}

/// Image width the pixel sizes of [`ParserMistakesConfig`] refer to, pixels.
pub const REFERENCE_WIDTH_PX: f64 = 1920.0;

/// Correlation length (grid spacing of the value noise) of the boundary-jitter
/// displacement field at [`REFERENCE_WIDTH_PX`], pixels: about the width of a forearm at
/// 2–3 m, so a boundary bends smoothly over a body part rather than fraying pixel by pixel.
pub const JITTER_CORRELATION_PX: f64 = 40.0;

const BACKGROUND: u8 = Class::Background as u8;
const UPPER_ARMS: u8 = Class::UpperArms as u8;
const LOWER_ARMS: u8 = Class::LowerArms as u8;
const UPPER_LEGS: u8 = Class::UpperLegs as u8;
const LOWER_LEGS: u8 = Class::LowerLegs as u8;

/// Hash tags: one independent random stream per kind of decision.
const TAG_MISS: u64 = 0x6d69_7373;
const TAG_SWAP: u64 = 0x7377_6170;
const TAG_SWAP_SIDE: u64 = 0x7369_6465;
const TAG_JITTER_X: u64 = 0x6a69_7478;
const TAG_JITTER_Y: u64 = 0x6a69_7479;

/// Number of limbs per person ([`Limb`]).
const LIMBS: usize = 4;

/// The predicted label image of one view: the truth with the errors of `config`
/// (pixel sizes given for a 1920-wide image, scaled by `width / 1920`). Deterministic in
/// `seed`. With every knob at zero it equals `truth.labels`.
///
/// Bad input never panics: if `width * height` overflows, is 0, or differs from
/// `labels.len()`, the labels are returned unchanged. If only `person` or `segment` has the
/// wrong length, the per-limb errors (miss, swap) are skipped and dilation and jitter,
/// which need the labels alone, are still applied. Negative or non-finite knobs count as 0.
pub fn predict_labels(truth: &TruthView<'_>, config: &ParserMistakesConfig, seed: u64) -> Vec<u8> {
    let mut labels = truth.labels.to_vec();
    let (Ok(width), Ok(height)) = (usize::try_from(truth.width), usize::try_from(truth.height))
    else {
        return labels;
    };
    let Some(n) = width.checked_mul(height) else {
        return labels;
    };
    if n == 0 || labels.len() != n {
        return labels;
    }
    let img = Dims { width, height };
    let scale = width as f64 / REFERENCE_WIDTH_PX;
    let px = |v: f64| {
        if v.is_finite() && v > 0.0 {
            v * scale
        } else {
            0.0
        }
    };

    if truth.person.len() == n && truth.segment.len() == n {
        let miss = config.miss_prob > 0.0;
        let swap_band_px = px(config.swap_band_px);
        let swap = config.swap_prob > 0.0 && swap_band_px > 0.0;
        if miss || swap {
            let limbs = LimbTable::scan(truth, img);
            let at = LimbScene {
                truth,
                limbs: &limbs,
                img,
                seed,
            };
            if miss {
                apply_miss(&mut labels, &at, config.miss_prob);
            }
            if swap {
                apply_swap(&mut labels, &at, config.swap_prob, swap_band_px);
            }
        }
    }
    dilate(
        &mut labels,
        img,
        px(config.small_part_dilation_px),
        px(config.part_dilation_px),
    );
    jitter(&mut labels, img, px(config.boundary_jitter_px), scale, seed);
    labels
}

/// Fraction of the pixels where `truth` or `pred` is a body label (non-zero) at which the
/// two differ: the parser's error rate on people pixels. 0 when neither has a body pixel.
/// Only the common prefix of the two slices is compared.
pub fn mismatch_fraction(truth: &[u8], pred: &[u8]) -> f64 {
    let (mut body, mut differ) = (0u64, 0u64);
    for (&t, &p) in truth.iter().zip(pred) {
        if t != BACKGROUND || p != BACKGROUND {
            body += 1;
            differ += u64::from(t != p);
        }
    }
    if body == 0 {
        0.0
    } else {
        differ as f64 / body as f64
    }
}

// ---------------------------------------------------------------------------------------
// Small helpers: image size, boxes, hashing.

#[derive(Clone, Copy, Debug)]
struct Dims {
    width: usize,
    height: usize,
}

/// A half-open pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

impl Rect {
    fn width(self) -> usize {
        self.x1 - self.x0
    }
    fn height(self) -> usize {
        self.y1 - self.y0
    }
}

/// An inclusive bounding box of pixels, possibly empty.
#[derive(Clone, Copy, Debug)]
struct BBox {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

impl BBox {
    const EMPTY: BBox = BBox {
        x0: usize::MAX,
        y0: usize::MAX,
        x1: 0,
        y1: 0,
    };

    fn add(&mut self, x: usize, y: usize) {
        self.x0 = self.x0.min(x);
        self.y0 = self.y0.min(y);
        self.x1 = self.x1.max(x);
        self.y1 = self.y1.max(y);
    }

    fn is_empty(&self) -> bool {
        self.x0 > self.x1 || self.y0 > self.y1
    }

    fn union(self, o: BBox) -> BBox {
        BBox {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }

    /// The box grown by `r` pixels on every side and clipped to the image; `None` if empty.
    fn grow(self, r: usize, img: Dims) -> Option<Rect> {
        if self.is_empty() {
            return None;
        }
        Some(Rect {
            x0: self.x0.saturating_sub(r),
            y0: self.y0.saturating_sub(r),
            x1: self.x1.saturating_add(r).saturating_add(1).min(img.width),
            y1: self.y1.saturating_add(r).saturating_add(1).min(img.height),
        })
    }
}

/// Bounding box of the pixels for which `keep(label)` holds.
fn bbox_where(labels: &[u8], img: Dims, keep: impl Fn(u8) -> bool) -> BBox {
    let mut b = BBox::EMPTY;
    for (y, row) in labels.chunks_exact(img.width).enumerate() {
        let first = row.iter().position(|&l| keep(l));
        if let Some(x0) = first {
            let x1 = row.iter().rposition(|&l| keep(l)).unwrap_or(x0);
            b.add(x0, y);
            b.add(x1, y);
        }
    }
    b
}

/// Whole pixels needed to cover a distance of `d` pixels.
fn radius_px(d: f64) -> usize {
    // `as` saturates for huge values; `d` is finite and >= 0 here.
    d.ceil() as usize
}

/// A uniform number in `[0, 1)` determined by `(seed, tag, a, b)`.
fn unit(seed: u64, tag: u64, a: u64, b: u64) -> f64 {
    let h = mix(mix(mix(seed ^ mix(tag)) ^ a) ^ b.rotate_left(32));
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

// ---------------------------------------------------------------------------------------
// Limbs of people: which pixels belong to which limb part.

fn limb_index(limb: Limb) -> usize {
    match limb {
        Limb::ArmLeft => 0,
        Limb::ArmRight => 1,
        Limb::LegLeft => 2,
        Limb::LegRight => 3,
    }
}

/// (upper class, lower class) of limb `limb` (arms first, then legs).
fn limb_classes(limb: usize) -> (u8, u8) {
    if limb < 2 {
        (UPPER_ARMS, LOWER_ARMS)
    } else {
        (UPPER_LEGS, LOWER_LEGS)
    }
}

/// Code of one limb part: `1 + 2 * limb + lower` (0 = not a limb segment).
fn part_code(limb: usize, lower: bool) -> u8 {
    // limb < 4, so this fits in u8.
    1 + 2 * (limb as u8) + u8::from(lower)
}

/// Per segment id, its [`part_code`].
fn part_lut() -> [u8; 256] {
    let mut lut = [0u8; 256];
    for s in Segment::ALL {
        if let Some(limb) = s.limb() {
            let lower = matches!(s.class(), Class::LowerArms | Class::LowerLegs);
            lut[usize::from(s.id())] = part_code(limb_index(limb), lower);
        }
    }
    lut
}

/// Bounding boxes of the upper and lower part of every limb of every person.
struct LimbTable {
    lut: [u8; 256],
    /// Index `(person * LIMBS + limb) * 2 + lower`.
    boxes: Vec<BBox>,
}

impl LimbTable {
    fn scan(truth: &TruthView<'_>, img: Dims) -> LimbTable {
        let lut = part_lut();
        let mut boxes = vec![BBox::EMPTY; 256 * LIMBS * 2];
        let rows = truth
            .segment
            .chunks_exact(img.width)
            .zip(truth.person.chunks_exact(img.width));
        for (y, (seg_row, person_row)) in rows.enumerate() {
            for (x, (&s, &p)) in seg_row.iter().zip(person_row).enumerate() {
                let code = lut[usize::from(s)];
                if code != 0 && p != 0 {
                    let slot = usize::from(p) * LIMBS * 2 + usize::from(code - 1);
                    boxes[slot].add(x, y);
                }
            }
        }
        LimbTable { lut, boxes }
    }

    fn part(&self, person: usize, limb: usize, lower: bool) -> BBox {
        self.boxes[(person * LIMBS + limb) * 2 + usize::from(lower)]
    }
}

/// What the limb mistakes (miss, swap) read: the truth, its limb table, the image size
/// and the frame's seed.
#[derive(Clone, Copy)]
struct LimbScene<'a> {
    truth: &'a TruthView<'a>,
    limbs: &'a LimbTable,
    img: Dims,
    seed: u64,
}

/// Miss: each lower limb part (forearm + hand, shin + foot) of each person becomes
/// background with probability `prob`.
fn apply_miss(labels: &mut [u8], at: &LimbScene<'_>, prob: f64) {
    let (truth, limbs, img, seed) = (at.truth, at.limbs, at.img, at.seed);
    for person in 1..256usize {
        for limb in 0..LIMBS {
            let Some(rect) = limbs.part(person, limb, true).grow(0, img) else {
                continue;
            };
            if unit(seed, TAG_MISS, person as u64, limb as u64) >= prob {
                continue;
            }
            let code = part_code(limb, true);
            let (_, lower_class) = limb_classes(limb);
            for y in rect.y0..rect.y1 {
                for i in y * img.width + rect.x0..y * img.width + rect.x1 {
                    let mine = usize::from(truth.person[i]) == person
                        && limbs.lut[usize::from(truth.segment[i])] == code;
                    if mine && labels[i] == lower_class {
                        labels[i] = BACKGROUND;
                    }
                }
            }
        }
    }
}

/// Swap: for each limb with probability `prob`, the pixels of one part (upper or lower, at
/// random) within `band_px` of the other part of the same limb take the other part's class.
fn apply_swap(labels: &mut [u8], at: &LimbScene<'_>, prob: f64, band_px: f64) {
    let (truth, limbs, img, seed) = (at.truth, at.limbs, at.img, at.seed);
    let cap = radius_px(band_px);
    let band2 = band_px * band_px;
    for person in 1..256usize {
        for limb in 0..LIMBS {
            let upper = limbs.part(person, limb, false);
            let lower = limbs.part(person, limb, true);
            if upper.is_empty() || lower.is_empty() {
                continue;
            }
            let (p, l) = (person as u64, limb as u64);
            if unit(seed, TAG_SWAP, p, l) >= prob {
                continue;
            }
            let (upper_class, lower_class) = limb_classes(limb);
            let upper_part = (part_code(limb, false), upper_class);
            let lower_part = (part_code(limb, true), lower_class);
            // `moved` takes `other`'s class near `other`.
            let (moved, other) = if unit(seed, TAG_SWAP_SIDE, p, l) < 0.5 {
                (upper_part, lower_part)
            } else {
                (lower_part, upper_part)
            };
            let Some(rect) = upper.union(lower).grow(0, img) else {
                continue;
            };
            let is_part = |i: usize, (code, class): (u8, u8), labels: &[u8]| {
                usize::from(truth.person[i]) == person
                    && limbs.lut[usize::from(truth.segment[i])] == code
                    && labels[i] == class
            };
            let field = {
                let labels: &[u8] = labels;
                distance_field(rect, img.width, cap, |i| {
                    if is_part(i, other, labels) {
                        other.1
                    } else {
                        0
                    }
                })
            };
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let i = y * img.width + x;
                    let (d2, _) = field.at(x, y);
                    if f64::from(d2) <= band2 && is_part(i, moved, labels) {
                        labels[i] = other.1;
                    }
                }
            }
        }
    }
}

/// Dilation: other body parts grow by `part_px` into the background (nearest part wins),
/// then lower arms and lower legs grow by `small_px` into every other label. Both grow from
/// the labels as they were before this step.
fn dilate(labels: &mut [u8], img: Dims, small_px: f64, part_px: f64) {
    if small_px <= 0.0 && part_px <= 0.0 {
        return;
    }
    let is_small = |l: u8| l == LOWER_ARMS || l == LOWER_LEGS;
    let src = labels.to_vec();
    if part_px > 0.0 {
        let r = radius_px(part_px);
        if let Some(rect) = bbox_where(&src, img, |l| l != BACKGROUND).grow(r, img) {
            let field = distance_field(rect, img.width, r, |i| src[i]);
            let lim = part_px * part_px;
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let i = y * img.width + x;
                    let (d2, site) = field.at(x, y);
                    if src[i] == BACKGROUND && f64::from(d2) <= lim {
                        labels[i] = site;
                    }
                }
            }
        }
    }
    if small_px > 0.0 {
        let r = radius_px(small_px);
        if let Some(rect) = bbox_where(&src, img, is_small).grow(r, img) {
            let field = distance_field(rect, img.width, r, |i| {
                if is_small(src[i]) { src[i] } else { 0 }
            });
            let lim = small_px * small_px;
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let i = y * img.width + x;
                    let (d2, site) = field.at(x, y);
                    if !is_small(src[i]) && f64::from(d2) <= lim {
                        labels[i] = site;
                    }
                }
            }
        }
    }
}

/// Jitter: every pixel within `amp_px` of a label boundary takes the label found at its
/// position displaced by a smooth random field of length at most `amp_px` (value noise on a
/// grid of [`JITTER_CORRELATION_PX`]` * scale`, smoothstep-interpolated, one field per axis).
/// Elsewhere the displaced position has the pixel's own label, so only the pixels near a
/// boundary ([`near_boundary`]) inside the body's bounding box grown by `amp_px` are visited.
fn jitter(labels: &mut [u8], img: Dims, amp_px: f64, scale: f64, seed: u64) {
    if amp_px <= 0.0 {
        return;
    }
    let r = radius_px(amp_px);
    let Some(rect) = bbox_where(labels, img, |l| l != BACKGROUND).grow(r.saturating_add(1), img)
    else {
        return;
    };
    let src = labels.to_vec();
    let near = near_boundary(&src, img.width, rect, r);
    let cell = (JITTER_CORRELATION_PX * scale).max(1.0);
    // Grid node index and smoothstep weight of every column / row of the rectangle.
    let axis = |from: usize, to: usize| -> (usize, Vec<(usize, f64)>) {
        let first = (from as f64 / cell).floor() as usize;
        let nodes = (from..to)
            .map(|v| {
                let t = v as f64 / cell;
                let k = t.floor();
                let f = t - k;
                ((k as usize).saturating_sub(first), f * f * (3.0 - 2.0 * f))
            })
            .collect::<Vec<_>>();
        (first, nodes)
    };
    let (gx0, cols) = axis(rect.x0, rect.x1);
    let (gy0, rows) = axis(rect.y0, rect.y1);
    let gw = cols.last().map_or(0, |c| c.0) + 2;
    let gh = rows.last().map_or(0, |c| c.0) + 2;
    let node = |tag: u64, gx: usize, gy: usize| {
        (2.0 * unit(seed, tag, (gx0 + gx) as u64, (gy0 + gy) as u64) - 1.0) * amp_px
    };
    let mut grid_x = Vec::with_capacity(gw * gh);
    let mut grid_y = Vec::with_capacity(gw * gh);
    for gy in 0..gh {
        for gx in 0..gw {
            grid_x.push(node(TAG_JITTER_X, gx, gy));
            grid_y.push(node(TAG_JITTER_Y, gx, gy));
        }
    }
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let (max_x, max_y) = ((img.width - 1) as f64, (img.height - 1) as f64);
    let amp2 = amp_px * amp_px;
    // The field interpolated to the current row at every grid column.
    let mut line_x = vec![0.0; gw];
    let mut line_y = vec![0.0; gw];
    let rw = rect.width();
    for ((y, &(ky, ty)), near_row) in (rect.y0..rect.y1).zip(&rows).zip(near.chunks_exact(rw)) {
        if !near_row.contains(&true) {
            continue;
        }
        for gx in 0..gw {
            let (a, b) = (ky * gw + gx, (ky + 1) * gw + gx);
            line_x[gx] = lerp(grid_x[a], grid_x[b], ty);
            line_y[gx] = lerp(grid_y[a], grid_y[b], ty);
        }
        let visit = (rect.x0..rect.x1).zip(&cols).zip(near_row);
        for ((x, &(kx, tx)), _) in visit.filter(|(_, near)| **near) {
            let mut dx = lerp(line_x[kx], line_x[kx + 1], tx);
            let mut dy = lerp(line_y[kx], line_y[kx + 1], tx);
            let len2 = dx * dx + dy * dy;
            if len2 > amp2 {
                let s = (amp2 / len2).sqrt();
                dx *= s;
                dy *= s;
            }
            let sx = (x as f64 + dx).round().clamp(0.0, max_x) as usize;
            let sy = (y as f64 + dy).round().clamp(0.0, max_y) as usize;
            labels[y * img.width + x] = src[sy * img.width + sx];
        }
    }
}

/// Per pixel of `rect` (row-major): whether a pixel of another label may lie within `r`
/// pixels (Chebyshev distance, a superset of the Euclidean disc). A label change between
/// two pixels shows up in a chain of 4-neighbour pairs between them, so the pairs that
/// differ (marked on their left / top pixel), dilated by `r` in x and then in y, cover it.
/// Pairs crossing the border of `rect` are not seen: callers grow `rect` beyond `r` around
/// every non-background pixel.
fn near_boundary(labels: &[u8], width: usize, rect: Rect, r: usize) -> Vec<bool> {
    let (rw, rh) = (rect.width(), rect.height());
    let row_of = |y: usize| &labels[(rect.y0 + y) * width + rect.x0..][..rw];
    // Horizontal: a change to the right or below, dilated by r along the row.
    let mut horiz = vec![false; rw * rh];
    let mut edge = vec![false; rw];
    for (y, out) in horiz.chunks_exact_mut(rw).enumerate() {
        let row = row_of(y);
        for x in 0..rw {
            let right = x + 1 < rw && row[x + 1] != row[x];
            let below = y + 1 < rh && row_of(y + 1)[x] != row[x];
            edge[x] = right || below;
        }
        let mut last: Option<usize> = None;
        for x in 0..rw {
            if edge[x] {
                last = Some(x);
            }
            out[x] = last.is_some_and(|l| x - l <= r);
        }
        let mut next: Option<usize> = None;
        for x in (0..rw).rev() {
            if edge[x] {
                next = Some(x);
            }
            out[x] |= next.is_some_and(|n| n - x <= r);
        }
    }
    // Vertical: dilate by r along the columns.
    let mut near = vec![false; rw * rh];
    let mut mark: Vec<Option<usize>> = vec![None; rw];
    for y in 0..rh {
        for x in 0..rw {
            let j = y * rw + x;
            if horiz[j] {
                mark[x] = Some(y);
            }
            near[j] = mark[x].is_some_and(|l| y - l <= r);
        }
    }
    mark.fill(None);
    for y in (0..rh).rev() {
        for x in 0..rw {
            let j = y * rw + x;
            if horiz[j] {
                mark[x] = Some(y);
            }
            near[j] |= mark[x].is_some_and(|n| n - y <= r);
        }
    }
    near
}

// ---------------------------------------------------------------------------------------
// Exact Euclidean distance transform with the nearest site's value.

/// Squared distance of a pixel with no site within the cap.
const FAR: u32 = u32::MAX;

/// A distance field over a rectangle of the image.
struct Field {
    rect: Rect,
    /// Squared distance to the nearest site, pixels², per pixel of `rect` (row-major).
    d2: Vec<u32>,
    /// The nearest site's value per pixel of `rect` (0 where `d2 == FAR`).
    site: Vec<u8>,
}

impl Field {
    /// Squared distance and nearest site value at image pixel `(x, y)`; `(FAR, 0)` outside
    /// the rectangle.
    fn at(&self, x: usize, y: usize) -> (u32, u8) {
        let r = self.rect;
        if !(r.x0..r.x1).contains(&x) || !(r.y0..r.y1).contains(&y) {
            return (FAR, 0);
        }
        let j = (y - r.y0) * r.width() + (x - r.x0);
        (self.d2[j], self.site[j])
    }
}

/// Exact squared Euclidean distance transform over `rect` (Felzenszwalb & Huttenlocher 2012:
/// a vertical pass, then the lower envelope of parabolas along each row), keeping the value
/// of the nearest site. `site(i)` is the value (non-zero) of image pixel `i` if it is a site,
/// else 0. Only sites inside `rect` count. Exact wherever the distance is at most `cap`
/// pixels; beyond that a pixel gets a distance greater than `cap` or `FAR`.
fn distance_field(rect: Rect, width: usize, cap: usize, site: impl Fn(usize) -> u8) -> Field {
    let (rw, rh) = (rect.width(), rect.height());
    let n = rw * rh;
    // Keeps g² and the row parabolas well inside u32 / f64 precision.
    let cap = u32::try_from(cap).unwrap_or(u32::MAX).min(1 << 15);
    // Vertical pass: distance to the nearest site in the same column (capped).
    let mut g = vec![FAR; n];
    let mut gs = vec![0u8; n];
    for y in 0..rh {
        let row = (rect.y0 + y) * width + rect.x0;
        for x in 0..rw {
            let j = y * rw + x;
            let s = site(row + x);
            if s != 0 {
                g[j] = 0;
                gs[j] = s;
            } else if y > 0 && g[j - rw] < cap {
                g[j] = g[j - rw] + 1;
                gs[j] = gs[j - rw];
            }
        }
    }
    for y in (0..rh.saturating_sub(1)).rev() {
        for x in 0..rw {
            let j = y * rw + x;
            let below = g[j + rw];
            if below < cap && below + 1 < g[j] {
                g[j] = below + 1;
                gs[j] = gs[j + rw];
            }
        }
    }
    // Horizontal pass: lower envelope of the parabolas (x - q)² + g(q)² of the columns
    // that have a site within the cap.
    let mut d2 = vec![FAR; n];
    let mut nearest = vec![0u8; n];
    let mut v: Vec<usize> = Vec::with_capacity(rw);
    let mut z: Vec<f64> = Vec::with_capacity(rw);
    let sq = |a: usize| (a as f64) * (a as f64);
    for y in 0..rh {
        let gr = &g[y * rw..(y + 1) * rw];
        v.clear();
        z.clear();
        for (q, &gq) in gr.iter().enumerate() {
            // Interior pixels of a run of sites are nearest only to themselves.
            let interior = gq == 0 && q > 0 && q + 1 < rw && gr[q - 1] == 0 && gr[q + 1] == 0;
            if gq == FAR || interior {
                continue;
            }
            let fq = sq(gq as usize) + sq(q);
            while let Some(&p) = v.last() {
                let fp = sq(gr[p] as usize) + sq(p);
                let s = (fq - fp) / (2.0 * (q - p) as f64);
                if z.last().is_some_and(|&zk| s <= zk) {
                    v.pop();
                    z.pop();
                } else {
                    v.push(q);
                    z.push(s);
                    break;
                }
            }
            if v.is_empty() {
                v.push(q);
                z.push(f64::NEG_INFINITY);
            }
        }
        if v.is_empty() {
            continue;
        }
        let mut k = 0;
        for x in 0..rw {
            while k + 1 < v.len() && z[k + 1] < x as f64 {
                k += 1;
            }
            let j = y * rw + x;
            if gr[x] == 0 {
                d2[j] = 0;
                nearest[j] = gs[j];
                continue;
            }
            let p = v[k];
            let dx = x.abs_diff(p) as u64;
            let gp = u64::from(gr[p]);
            d2[j] = u32::try_from(dx * dx + gp * gp)
                .unwrap_or(FAR - 1)
                .min(FAR - 1);
            nearest[j] = gs[y * rw + p];
        }
    }
    Field {
        rect,
        d2,
        site: nearest,
    }
}

#[cfg(test)]
mod tests;
