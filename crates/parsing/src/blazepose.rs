//! BlazePose landmarks + segmentation mask → the 7 classes (issue 29), pure functions.
//!
//! The rule of `docs/notes/2026-12-02-blazepose-rule.md`, ported from its reference,
//! `scripts/blazepose_prototype.py`: a square, rotated region of interest (ROI) per person
//! is cropped into the landmark model's 256×256 input ([`Roi`], [`crop`]); the model's
//! landmarks are refined on its heatmaps ([`refine_from_heatmap`]) and mapped back to the
//! image ([`decode`]); bones are built from them ([`bones`]: a torso quad and capsules
//! around the head, arms and legs); each pixel of the person's mask takes the class of the
//! nearest bone surface ([`label_person`]), with a probability = mask × a bone-margin
//! confidence; people are merged by the nearer bone ([`merge_people`]).
//!
//! This first phase has no ONNX session here: the `Segmenter` that runs the model on
//! person regions comes with the pipeline integration (second phase).
//!
//! # Conventions
//! - Image pixels (u, v) = (column, row), integer coordinates are pixel centres.
//! - Tensor coordinates of the 256×256 input are pixel edges (0..256): tensor pixel
//!   (i, j) has its centre at (i + 0.5, j + 0.5), as MediaPipe's landmark outputs.
//! - A ROI's `angle_rad` rotates its axes: right = (cos a, sin a), down = (−sin a, cos a)
//!   in image pixels; 0 = upright.

pub use crate::segmenter::PixelBox;
use bodyseg_core::{Label, LabelImage, RgbImage};

/// Side of the landmark model's square input, pixels.
pub const INPUT: usize = 256;
/// Side of the landmark heatmaps, cells (a cell is 4 input pixels).
pub const HEATMAP: usize = 64;
/// Landmarks the model outputs (33 body points + alignment points + auxiliaries).
pub const NUM_LANDMARKS: usize = 39;

/// Landmark indices (MediaPipe pose topology) used by the rule.
pub mod landmark {
    /// Nose.
    pub const NOSE: usize = 0;
    /// Left eye (centre).
    pub const LEFT_EYE: usize = 2;
    /// Right eye (centre).
    pub const RIGHT_EYE: usize = 5;
    /// Left ear.
    pub const LEFT_EAR: usize = 7;
    /// Right ear.
    pub const RIGHT_EAR: usize = 8;
    /// Mouth, left corner.
    pub const MOUTH_LEFT: usize = 9;
    /// Mouth, right corner.
    pub const MOUTH_RIGHT: usize = 10;
    /// Left shoulder.
    pub const LEFT_SHOULDER: usize = 11;
    /// Right shoulder.
    pub const RIGHT_SHOULDER: usize = 12;
    /// Left elbow.
    pub const LEFT_ELBOW: usize = 13;
    /// Right elbow.
    pub const RIGHT_ELBOW: usize = 14;
    /// Left wrist.
    pub const LEFT_WRIST: usize = 15;
    /// Right wrist.
    pub const RIGHT_WRIST: usize = 16;
    /// Left pinky, index, thumb.
    pub const LEFT_HAND: [usize; 3] = [17, 19, 21];
    /// Right pinky, index, thumb.
    pub const RIGHT_HAND: [usize; 3] = [18, 20, 22];
    /// Left hip.
    pub const LEFT_HIP: usize = 23;
    /// Right hip.
    pub const RIGHT_HIP: usize = 24;
    /// Left knee.
    pub const LEFT_KNEE: usize = 25;
    /// Right knee.
    pub const RIGHT_KNEE: usize = 26;
    /// Left ankle.
    pub const LEFT_ANKLE: usize = 27;
    /// Right ankle.
    pub const RIGHT_ANKLE: usize = 28;
    /// Left heel, foot index.
    pub const LEFT_FOOT: [usize; 2] = [29, 31];
    /// Right heel, foot index.
    pub const RIGHT_FOOT: [usize; 2] = [30, 32];
    /// Alignment point: body centre (mid-hip).
    pub const ALIGN_CENTRE: usize = 33;
    /// Alignment point: size and rotation.
    pub const ALIGN_SCALE: usize = 34;
    /// Face points: nose, eyes, ears, mouth (0..=10).
    pub const FACE: std::ops::RangeInclusive<usize> = 0..=10;
}

type P2 = [f64; 2];

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: P2, b: P2) -> P2 {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: P2, k: f64) -> P2 {
    [a[0] * k, a[1] * k]
}
fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn norm(a: P2) -> f64 {
    a[0].hypot(a[1])
}
fn mid(a: P2, b: P2) -> P2 {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

/// A square, rotated region of interest in the image (MediaPipe's `NormalizedRect` in
/// pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roi {
    /// Centre, image px (pixel centres at integers).
    pub centre_px: P2,
    /// Side, image px.
    pub side_px: f64,
    /// Rotation, radians; 0 = upright (see the module's conventions).
    pub angle_rad: f64,
}

impl Roi {
    /// The upright ROI around a box: its centre, side `scale` × the box's longer side.
    pub fn from_box(b: &PixelBox, scale: f64) -> Roi {
        let w = b.x1 - b.x0 + 1.0;
        let h = b.y1 - b.y0 + 1.0;
        Roi {
            centre_px: [(b.x0 + b.x1) / 2.0, (b.y0 + b.y1) / 2.0],
            side_px: w.max(h) * scale,
            angle_rad: 0.0,
        }
    }

    /// MediaPipe's ROI from alignment points (AlignmentPointsRects + RectTransformation
    /// with `square_long`): centre = `centre`, side = 2 |scale_pt − centre| × `scale`,
    /// rotated so that centre → scale_pt points up in the ROI.
    pub fn from_alignment(centre: P2, scale_pt: P2, scale: f64) -> Roi {
        let v = sub(scale_pt, centre);
        Roi {
            centre_px: centre,
            side_px: 2.0 * norm(v) * scale,
            angle_rad: v[0].atan2(-v[1]),
        }
    }

    /// (right, down) unit axes in image pixels.
    pub fn axes(&self) -> (P2, P2) {
        let (s, c) = self.angle_rad.sin_cos();
        ([c, s], [-s, c])
    }

    /// Tensor coordinates (0..256, pixel edges) → image px.
    pub fn tensor_to_image(&self, t: P2) -> P2 {
        let (right, down) = self.axes();
        let ox = (t[0] / INPUT as f64 - 0.5) * self.side_px;
        let oy = (t[1] / INPUT as f64 - 0.5) * self.side_px;
        add(self.centre_px, add(scale(right, ox), scale(down, oy)))
    }

    /// Image px → tensor coordinates (the inverse of [`Roi::tensor_to_image`]).
    pub fn image_to_tensor(&self, p: P2) -> P2 {
        let (right, down) = self.axes();
        let d = sub(p, self.centre_px);
        [
            (dot(d, right) / self.side_px + 0.5) * INPUT as f64,
            (dot(d, down) / self.side_px + 0.5) * INPUT as f64,
        ]
    }
}

/// The ROI cropped into a `size`×`size` RGB tensor, NHWC, values in [0, 1]: tensor pixel
/// (i, j) samples the image at the ROI point of tensor coordinates ((i + 0.5)·256/size,
/// (j + 0.5)·256/size), bilinear, coordinates clamped to the image (MediaPipe's
/// BORDER_REPLICATE). An empty image gives zeros.
pub fn crop(image: &RgbImage, roi: &Roi, size: usize) -> Vec<f32> {
    let mut out = Vec::new();
    crop_into(image, roi, size, &mut out);
    out
}

/// [`crop`] into `out` (its allocation reused).
pub fn crop_into(image: &RgbImage, roi: &Roi, size: usize, out: &mut Vec<f32>) {
    out.clear();
    out.resize(size * size * 3, 0.0);
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.rgb.len() < w * h * 3 {
        return;
    }
    let step = INPUT as f64 / size as f64;
    // tensor_to_image, with the axes computed once: p = origin + tx·ex + ty·ey.
    let (right, down) = roi.axes();
    let k = roi.side_px / INPUT as f64;
    let ex = scale(right, k);
    let ey = scale(down, k);
    let origin = sub(
        roi.centre_px,
        add(
            scale(right, roi.side_px / 2.0),
            scale(down, roi.side_px / 2.0),
        ),
    );
    let (wmax, hmax) = ((w - 1) as f64, (h - 1) as f64);
    for j in 0..size {
        let ty = (j as f64 + 0.5) * step;
        let row = add(origin, scale(ey, ty));
        for i in 0..size {
            let tx = (i as f64 + 0.5) * step;
            let p = add(row, scale(ex, tx));
            let x = p[0].clamp(0.0, wmax);
            let y = p[1].clamp(0.0, hmax);
            // clamped to [0, w-1]: the casts cannot leave the image
            let x0 = x.floor() as usize;
            let y0 = y.floor() as usize;
            let x1 = (x0 + 1).min(w - 1);
            let y1 = (y0 + 1).min(h - 1);
            let fx = x - x0 as f64;
            let fy = y - y0 as f64;
            let (a, b, c, d) = (
                (y0 * w + x0) * 3,
                (y0 * w + x1) * 3,
                (y1 * w + x0) * 3,
                (y1 * w + x1) * 3,
            );
            let o = (j * size + i) * 3;
            for ch in 0..3 {
                let at = |k: usize| f64::from(image.rgb[k + ch]);
                let top = at(a) * (1.0 - fx) + at(b) * fx;
                let bot = at(c) * (1.0 - fx) + at(d) * fx;
                out[o + ch] = ((top * (1.0 - fy) + bot * fy) / 255.0) as f32;
            }
        }
    }
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x.clamp(-60.0, 60.0)).exp())
}

/// MediaPipe's RefineLandmarksFromHeatmap: each landmark's (x, y) (tensor px) becomes the
/// sigmoid-weighted mean cell position in a `kernel`×`kernel` window of its heatmap around
/// it, when the window's largest weight is ≥ `min_confidence`. `landmarks` holds
/// (x, y, …) per landmark; `heatmap` is `[64][64][39]` logits (row, column, landmark).
pub fn refine_from_heatmap(
    landmarks: &mut [[f64; 5]],
    heatmap: &[f32],
    kernel: usize,
    min_confidence: f64,
) {
    if heatmap.len() < HEATMAP * HEATMAP * NUM_LANDMARKS {
        return;
    }
    let off = (kernel / 2) as i64;
    let cell = (INPUT / HEATMAP) as f64;
    for (k, lm) in landmarks.iter_mut().enumerate().take(NUM_LANDMARKS) {
        let col = (lm[0] / cell).floor();
        let row = (lm[1] / cell).floor();
        if !(0.0..HEATMAP as f64).contains(&col) || !(0.0..HEATMAP as f64).contains(&row) {
            continue;
        }
        let (col, row) = (col as i64, row as i64);
        let (mut sum, mut sc, mut sr, mut max) = (0.0, 0.0, 0.0, 0.0f64);
        for r in (row - off).max(0)..(row + off + 1).min(HEATMAP as i64) {
            for c in (col - off).max(0)..(col + off + 1).min(HEATMAP as i64) {
                let idx = (r as usize * HEATMAP + c as usize) * NUM_LANDMARKS + k;
                let wgt = sigmoid(f64::from(heatmap[idx]));
                sum += wgt;
                sc += c as f64 * wgt;
                sr += r as f64 * wgt;
                max = max.max(wgt);
            }
        }
        if max >= min_confidence && sum > 0.0 {
            lm[0] = (sc / sum + 0.5) * cell;
            lm[1] = (sr / sum + 0.5) * cell;
        }
    }
}

/// One person's decoded model output, in image coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedPose {
    /// The ROI the model saw.
    pub roi: Roi,
    /// Pose presence in [0, 1] (the model's `Identity_1`).
    pub flag: f64,
    /// Landmark positions, image px, [`NUM_LANDMARKS`] entries.
    pub xy: Vec<P2>,
    /// Visibility (sigmoid), per landmark.
    pub visibility: Vec<f64>,
    /// Presence (sigmoid), per landmark.
    pub presence: Vec<f64>,
    /// Person probability on the ROI's 256×256 grid, row-major (sigmoid of the mask logits).
    pub mask: Vec<f32>,
}

/// Decodes the landmark model's outputs for `roi`: `landmarks` = `Identity` (195 values:
/// x, y, z, visibility logit, presence logit per landmark, x and y in tensor px),
/// `flag` = `Identity_1`, `mask_logits` = `Identity_2` (256×256), `heatmap` = `Identity_3`
/// (refines x, y when given). `None` when a buffer is shorter than the model's.
pub fn decode(
    roi: &Roi,
    landmarks: &[f32],
    flag: f32,
    mask_logits: &[f32],
    heatmap: Option<&[f32]>,
) -> Option<DecodedPose> {
    if landmarks.len() < NUM_LANDMARKS * 5 || mask_logits.len() < INPUT * INPUT {
        return None;
    }
    let mut lm: Vec<[f64; 5]> = landmarks
        .chunks_exact(5)
        .take(NUM_LANDMARKS)
        .map(|c| {
            [
                f64::from(c[0]),
                f64::from(c[1]),
                f64::from(c[2]),
                f64::from(c[3]),
                f64::from(c[4]),
            ]
        })
        .collect();
    if let Some(h) = heatmap {
        refine_from_heatmap(&mut lm, h, 7, 0.5);
    }
    Some(DecodedPose {
        roi: *roi,
        flag: f64::from(flag),
        xy: lm
            .iter()
            .map(|l| roi.tensor_to_image([l[0], l[1]]))
            .collect(),
        visibility: lm.iter().map(|l| sigmoid(l[3])).collect(),
        presence: lm.iter().map(|l| sigmoid(l[4])).collect(),
        mask: mask_logits[..INPUT * INPUT]
            .iter()
            .map(|&v| sigmoid(f64::from(v)) as f32)
            .collect(),
    })
}

/// The thresholds and sizes of the rule (docs/notes/2026-12-02-blazepose-rule.md §5);
/// defaults are the values tuned on the benchmark's tune split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuleConfig {
    /// A pixel is the person's when its mask value is ≥ this.
    pub mask_threshold: f64,
    /// A landmark counts when its presence is ≥ this (out-of-frame points do not).
    pub min_presence: f64,
    /// A limb bone counts when both its ends are visible ≥ this.
    pub min_visibility: f64,
    /// Head capsule radius, × the head width.
    pub r_head: f64,
    /// Head width ≥ this × the eyes-to-mouth distance.
    pub face_to_width: f64,
    /// Head bone from the face centre down (toward the chin), × head width.
    pub head_down: f64,
    /// Head bone from the face centre up (toward the crown), × head width.
    pub head_up: f64,
    /// Torso quad's margin, × the body scale.
    pub r_torso: f64,
    /// Upper arm capsule radius, × the body scale.
    pub r_upper_arm: f64,
    /// Lower arm capsule radius, × the body scale.
    pub r_lower_arm: f64,
    /// Upper leg capsule radius, × the body scale.
    pub r_upper_leg: f64,
    /// Lower leg capsule radius, × the body scale.
    pub r_lower_leg: f64,
    /// The lower arm continues past the hand points by this × (hand − wrist).
    pub hand_extend: f64,
    /// Added to the torso's score, in body scales: a limb in front of the torso wins.
    pub torso_bias: f64,
    /// A mask pixel whose best score exceeds this is not the person's.
    pub max_score: f64,
    /// Bone-margin confidence: 1 − 0.5 exp(−(e2 − e1) / margin_scale).
    pub margin_scale: f64,
}

impl Default for RuleConfig {
    fn default() -> Self {
        RuleConfig {
            mask_threshold: 0.35,
            min_presence: 0.5,
            min_visibility: 0.2,
            r_head: 0.4,
            face_to_width: 2.0,
            head_down: 0.2,
            head_up: 0.3,
            r_torso: 0.25,
            r_upper_arm: 0.15,
            r_lower_arm: 0.14,
            r_upper_leg: 0.2,
            r_lower_leg: 0.22,
            hand_extend: 0.0,
            torso_bias: 0.2,
            max_score: 3.0,
            margin_scale: 0.5,
        }
    }
}

/// A bone's shape in image px.
#[derive(Clone, Debug, PartialEq)]
pub enum BoneShape {
    /// A capsule around a polyline (≥ 2 points).
    Polyline(Vec<P2>),
    /// The torso quad (distance 0 inside).
    Quad([P2; 4]),
}

/// One bone of a pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Bone {
    /// Class id (1..=6, ALGORITHM.md §0).
    pub class: u8,
    /// Its shape.
    pub shape: BoneShape,
    /// Capsule radius (margin of the quad), image px.
    pub radius_px: f64,
    /// The pose's body scale, image px (the unit of scores).
    pub scale_px: f64,
}

/// The bones a pose supports (§3 of the note).
pub fn bones(pose: &DecodedPose, cfg: &RuleConfig) -> Vec<Bone> {
    use landmark::*;
    let p = &pose.xy;
    if p.len() < NUM_LANDMARKS || pose.presence.len() < NUM_LANDMARKS {
        return Vec::new();
    }
    let ok = |i: usize| pose.presence[i] >= cfg.min_presence;
    let seen = |idx: &[usize]| {
        idx.iter()
            .all(|&i| ok(i) && pose.visibility[i] >= cfg.min_visibility)
    };
    let mean_of = |idx: &mut dyn Iterator<Item = usize>| -> Option<P2> {
        let (mut s, mut n) = ([0.0, 0.0], 0.0);
        for i in idx {
            s = add(s, p[i]);
            n += 1.0;
        }
        (n > 0.0).then(|| scale(s, 1.0 / n))
    };
    let sh_mid = mid(p[LEFT_SHOULDER], p[RIGHT_SHOULDER]);
    let hip_mid = mid(p[LEFT_HIP], p[RIGHT_HIP]);
    let body = norm(sub(sh_mid, hip_mid))
        .max(norm(sub(p[LEFT_SHOULDER], p[RIGHT_SHOULDER])))
        .max(norm(sub(p[LEFT_HIP], p[RIGHT_HIP])))
        .max(1.0);
    let (_, down) = pose.roi.axes();
    let mut out = Vec::new();
    let shoulders = ok(LEFT_SHOULDER) && ok(RIGHT_SHOULDER);
    if shoulders {
        let quad = if ok(LEFT_HIP) && ok(RIGHT_HIP) {
            [
                p[LEFT_SHOULDER],
                p[RIGHT_SHOULDER],
                p[RIGHT_HIP],
                p[LEFT_HIP],
            ]
        } else {
            let d = scale(down, body);
            [
                p[LEFT_SHOULDER],
                p[RIGHT_SHOULDER],
                add(p[RIGHT_SHOULDER], d),
                add(p[LEFT_SHOULDER], d),
            ]
        };
        out.push(Bone {
            class: 2,
            shape: BoneShape::Quad(quad),
            radius_px: cfg.r_torso * body,
            scale_px: body,
        });
    }
    if let Some(hc) = mean_of(&mut FACE.filter(|&i| ok(i))) {
        let to_head = sub(hc, sh_mid);
        let up = if shoulders && norm(to_head) > 1e-6 {
            scale(to_head, 1.0 / norm(to_head))
        } else {
            scale(down, -1.0)
        };
        let eyes = mid(p[LEFT_EYE], p[RIGHT_EYE]);
        let mouth = mid(p[MOUTH_LEFT], p[MOUTH_RIGHT]);
        let width = norm(sub(p[LEFT_EAR], p[RIGHT_EAR]))
            .max(cfg.face_to_width * norm(sub(eyes, mouth)))
            .max(1.0);
        out.push(Bone {
            class: 1,
            shape: BoneShape::Polyline(vec![
                sub(hc, scale(up, cfg.head_down * width)),
                add(hc, scale(up, cfg.head_up * width)),
            ]),
            radius_px: cfg.r_head * width,
            scale_px: body,
        });
    }
    let limbs = [
        (LEFT_SHOULDER, LEFT_ELBOW, LEFT_WRIST, &LEFT_HAND[..], 3u8),
        (
            RIGHT_SHOULDER,
            RIGHT_ELBOW,
            RIGHT_WRIST,
            &RIGHT_HAND[..],
            3u8,
        ),
        (LEFT_HIP, LEFT_KNEE, LEFT_ANKLE, &LEFT_FOOT[..], 5u8),
        (RIGHT_HIP, RIGHT_KNEE, RIGHT_ANKLE, &RIGHT_FOOT[..], 5u8),
    ];
    for (root, joint, end, tips, upper) in limbs {
        if !seen(&[root, joint]) {
            continue;
        }
        let (r_up, r_low) = if upper == 3 {
            (cfg.r_upper_arm, cfg.r_lower_arm)
        } else {
            (cfg.r_upper_leg, cfg.r_lower_leg)
        };
        out.push(Bone {
            class: upper,
            shape: BoneShape::Polyline(vec![p[root], p[joint]]),
            radius_px: r_up * body,
            scale_px: body,
        });
        if !seen(&[end]) {
            continue;
        }
        let mut pts = vec![p[joint], p[end]];
        if let Some(tip) = mean_of(&mut tips.iter().copied().filter(|&i| ok(i))) {
            pts.push(if upper == 3 {
                add(tip, scale(sub(tip, p[end]), cfg.hand_extend))
            } else {
                tip
            });
        }
        out.push(Bone {
            class: upper + 1,
            shape: BoneShape::Polyline(pts),
            radius_px: r_low * body,
            scale_px: body,
        });
    }
    out
}

/// Distance of `q` to the segment a–b.
pub fn segment_distance(q: P2, a: P2, b: P2) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    if l2 < 1e-18 {
        return norm(sub(q, a));
    }
    let t = (dot(sub(q, a), ab) / l2).clamp(0.0, 1.0);
    norm(sub(q, add(a, scale(ab, t))))
}

/// Distance of `q` to a polygon: 0 inside (even-odd rule), else to the nearest edge.
pub fn polygon_distance(q: P2, poly: &[P2]) -> f64 {
    let n = poly.len();
    let mut d = f64::INFINITY;
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        d = d.min(segment_distance(q, a, b));
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if q[0] < x {
                inside = !inside;
            }
        }
    }
    if inside { 0.0 } else { d }
}

impl Bone {
    /// The bone's score at `q`: (distance to its surface) / body scale + 1, plus
    /// `torso_bias` for the torso (§4 of the note).
    pub fn score(&self, q: P2, torso_bias: f64) -> f64 {
        let (d, bias) = match &self.shape {
            BoneShape::Polyline(pts) => (
                pts.windows(2)
                    .map(|w| segment_distance(q, w[0], w[1]))
                    .fold(f64::INFINITY, f64::min),
                0.0,
            ),
            BoneShape::Quad(quad) => (polygon_distance(q, quad), torso_bias),
        };
        (d - self.radius_px) / self.scale_px + 1.0 + bias
    }
}

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
fn mask_at(pose: &DecodedPose, axes: (P2, P2), q: P2) -> f64 {
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
    let ix = (tx.floor() as usize).min(INPUT - 2);
    let iy = (ty.floor() as usize).min(INPUT - 2);
    let (fx, fy) = (tx - ix as f64, ty - iy as f64);
    let m = |x: usize, y: usize| f64::from(pose.mask[y * INPUT + x]);
    (m(ix, iy) * (1.0 - fx) + m(ix + 1, iy) * fx) * (1.0 - fy)
        + (m(ix, iy + 1) * (1.0 - fx) + m(ix + 1, iy + 1) * fx) * fy
}

/// The window of the image a pose's ROI covers: its bounding box, clipped; `None` when it
/// misses the image.
fn roi_window(roi: &Roi, width: usize, height: usize) -> Option<(usize, usize, usize, usize)> {
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
const BLOCK: usize = 8;

/// The class of a pixel from its per-class scores: (class, e1, e2) with e1 ≤ e2 the two
/// smallest scores (e2 = e1 + 10 with one class).
fn best_two(per_class: &[f64; 7]) -> (usize, f64, f64) {
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
    let bl = bones(pose, cfg);
    if bl.is_empty() {
        return None;
    }
    let ww = u1 - u0;
    let n = ww * (v1 - v0);
    let mut class = vec![0u8; n];
    let mut prob = vec![1.0f32; n];
    let mut score = vec![f32::INFINITY; n];
    let axes = pose.roi.axes();
    let mut mask = vec![0.0f64; BLOCK * BLOCK];
    let mut keep: Vec<usize> = Vec::with_capacity(bl.len());
    for bv in (v0..v1).step_by(BLOCK) {
        let bv1 = (bv + BLOCK).min(v1);
        for bu in (u0..u1).step_by(BLOCK) {
            let bu1 = (bu + BLOCK).min(u1);
            // The mask first: most of a window is not the person's.
            let mut any = false;
            for v in bv..bv1 {
                for u in bu..bu1 {
                    let m = mask_at(pose, axes, [u as f64, v as f64]);
                    mask[(v - bv) * BLOCK + (u - bu)] = m;
                    prob[(v - v0) * ww + (u - u0)] = (1.0 - m).clamp(0.0, 1.0) as f32;
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
            let mut lower_of = Vec::with_capacity(bl.len());
            for b in &bl {
                let s = b.score(centre, cfg.torso_bias);
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
                        let s = b.score(q, cfg.torso_bias);
                        let c = usize::from(b.class);
                        per_class[c] = per_class[c].min(s);
                    }
                    let (c1, e1, e2) = best_two(&per_class);
                    if e1 > cfg.max_score {
                        continue;
                    }
                    let conf = 1.0 - 0.5 * (-(e2 - e1) / cfg.margin_scale).exp();
                    let k = (v - v0) * ww + (u - u0);
                    class[k] = c1 as u8;
                    prob[k] = (m * conf).clamp(0.0, 1.0) as f32;
                    score[k] = e1 as f32;
                }
            }
        }
    }
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
    let mut best = vec![f32::INFINITY; width * height];
    // Who won each pixel (index into `people`), for the depth test.
    let mut owner = vec![usize::MAX; width * height];
    // Front to back (unknown depths last), stable: ties keep the given order.
    let mut order: Vec<usize> = (0..people.len()).collect();
    order.sort_by(|&a, &b| {
        let key = |p: &PersonLabels| p.depth_m.unwrap_or(f64::INFINITY);
        key(&people[a]).total_cmp(&key(&people[b]))
    });
    for &index in &order {
        let p = &people[index];
        let pw = p.u1 - p.u0;
        for v in p.v0..p.v1.min(height) {
            for u in p.u0..p.u1.min(width) {
                let k = (v - p.v0) * pw + (u - p.u0);
                let i = v * width + u;
                if !p.score[k].is_finite() {
                    if owner[i] == usize::MAX {
                        probs[i] = probs[i].min(p.prob[k]);
                    }
                    continue;
                }
                let behind = owner[i] != usize::MAX
                    && match (people[owner[i]].depth_m, p.depth_m) {
                        (Some(front), Some(me)) => me - front > SIDE_BY_SIDE_M,
                        _ => false,
                    };
                if !behind && p.score[k] < best[i] {
                    best[i] = p.score[k];
                    labels[i] = Label::from_id_or_unknown(p.class[k]);
                    probs[i] = p.prob[k];
                    owner[i] = index;
                }
            }
        }
    }
    LabelImage {
        width: width as u32,
        height: height as u32,
        labels,
        probs: Some(probs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Tolerance for coordinate round trips: a few ulps of values ~ 1e2.
    const EPS: f64 = 1e-9;

    #[test]
    fn roi_round_trip_and_centre() {
        let roi = Roi {
            centre_px: [100.0, 50.0],
            side_px: 80.0,
            angle_rad: 0.7,
        };
        for t in [[0.0, 0.0], [128.0, 128.0], [200.5, 31.25]] {
            let back = roi.image_to_tensor(roi.tensor_to_image(t));
            assert!((back[0] - t[0]).abs() < EPS && (back[1] - t[1]).abs() < EPS);
        }
        let c = roi.tensor_to_image([128.0, 128.0]);
        assert!((c[0] - 100.0).abs() < EPS && (c[1] - 50.0).abs() < EPS);
    }

    #[test]
    fn alignment_roi_points_up() {
        let roi = Roi::from_alignment([50.0, 100.0], [50.0, 60.0], 1.5);
        assert!((roi.side_px - 120.0).abs() < EPS);
        assert!(roi.angle_rad.abs() < EPS);
        // head to the right: the ROI's up axis is +x
        let roi = Roi::from_alignment([50.0, 100.0], [90.0, 100.0], 1.0);
        let (_, down) = roi.axes();
        assert!((down[0] + 1.0).abs() < EPS && down[1].abs() < EPS);
    }

    #[test]
    fn distances() {
        assert!((segment_distance([5.0, 5.0], [0.0, 0.0], [10.0, 0.0]) - 5.0).abs() < EPS);
        assert!((segment_distance([12.0, 0.0], [0.0, 0.0], [10.0, 0.0]) - 2.0).abs() < EPS);
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        assert_eq!(polygon_distance([5.0, 5.0], &sq), 0.0);
        assert!((polygon_distance([12.0, 5.0], &sq) - 2.0).abs() < EPS);
    }

    #[test]
    fn crop_of_a_uniform_image_is_uniform_and_replicates_the_border() {
        let img = RgbImage::new(4, 3, [10u8, 20, 30].repeat(12)).expect("4x3x3 bytes");
        // a ROI mostly outside the image: the border pixels are replicated
        let roi = Roi {
            centre_px: [-50.0, -50.0],
            side_px: 40.0,
            angle_rad: 0.3,
        };
        let t = crop(&img, &roi, 8);
        for px in t.chunks_exact(3) {
            assert!((px[0] - 10.0 / 255.0).abs() < 1e-6 && (px[2] - 30.0 / 255.0).abs() < 1e-6);
        }
    }

    #[test]
    fn heatmap_moves_a_landmark_to_its_peak() {
        let mut heat = vec![-20.0f32; HEATMAP * HEATMAP * NUM_LANDMARKS];
        // landmark 11's peak at cell (row 10, col 12)
        heat[(10 * HEATMAP + 12) * NUM_LANDMARKS + 11] = 20.0;
        let mut lm = vec![[0.0; 5]; NUM_LANDMARKS];
        lm[11] = [45.0, 38.0, 0.0, 0.0, 0.0]; // cell (row 9, col 11): within the kernel
        lm[12] = [45.0, 38.0, 0.0, 0.0, 0.0]; // its heatmap is flat and low: unchanged
        refine_from_heatmap(&mut lm, &heat, 7, 0.5);
        assert!((lm[11][0] - 12.5 * 4.0).abs() < 1e-3 && (lm[11][1] - 10.5 * 4.0).abs() < 1e-3);
        assert_eq!(lm[12][0], 45.0);
    }

    /// An upright figure (image px), mask 1 everywhere.
    fn figure() -> DecodedPose {
        use landmark::*;
        let mut xy = vec![[50.0, 25.0]; NUM_LANDMARKS];
        xy[LEFT_EYE] = [53.0, 23.0];
        xy[RIGHT_EYE] = [47.0, 23.0];
        xy[MOUTH_LEFT] = [52.0, 28.0];
        xy[MOUTH_RIGHT] = [48.0, 28.0];
        xy[LEFT_EAR] = [56.0, 24.0];
        xy[RIGHT_EAR] = [44.0, 24.0];
        for (i, p) in [
            (LEFT_SHOULDER, [60.0, 40.0]),
            (RIGHT_SHOULDER, [40.0, 40.0]),
            (LEFT_HIP, [58.0, 80.0]),
            (RIGHT_HIP, [42.0, 80.0]),
            (LEFT_ELBOW, [70.0, 60.0]),
            (RIGHT_ELBOW, [30.0, 60.0]),
            (LEFT_WRIST, [72.0, 78.0]),
            (RIGHT_WRIST, [28.0, 78.0]),
            (LEFT_KNEE, [58.0, 110.0]),
            (RIGHT_KNEE, [42.0, 110.0]),
            (LEFT_ANKLE, [58.0, 140.0]),
            (RIGHT_ANKLE, [42.0, 140.0]),
        ] {
            xy[i] = p;
        }
        for i in LEFT_HAND {
            xy[i] = [72.0, 84.0];
        }
        for i in RIGHT_HAND {
            xy[i] = [28.0, 84.0];
        }
        for i in LEFT_FOOT {
            xy[i] = [58.0, 146.0];
        }
        for i in RIGHT_FOOT {
            xy[i] = [42.0, 146.0];
        }
        DecodedPose {
            roi: Roi {
                centre_px: [50.0, 80.0],
                side_px: 160.0,
                angle_rad: 0.0,
            },
            flag: 1.0,
            xy,
            visibility: vec![1.0; NUM_LANDMARKS],
            presence: vec![1.0; NUM_LANDMARKS],
            mask: vec![1.0; INPUT * INPUT],
        }
    }

    #[test]
    fn each_bone_labels_its_pixels() {
        let pose = figure();
        let p = label_person(&pose, &RuleConfig::default(), 100, 160).expect("in the image");
        let at = |u: usize, v: usize| p.class[(v - p.v0) * (p.u1 - p.u0) + (u - p.u0)];
        assert_eq!(at(50, 25), 1, "head");
        assert_eq!(at(50, 60), 2, "torso");
        assert_eq!(at(65, 50), 3, "upper arm");
        assert_eq!(at(71, 70), 4, "lower arm");
        assert_eq!(at(58, 95), 5, "upper leg");
        assert_eq!(at(42, 125), 6, "lower leg");
        assert!(p.prob.iter().all(|&x| (0.0..=1.0).contains(&x)));
        // the probability is lowest on a border between two parts
        let k_mid = (60 - p.v0) * (p.u1 - p.u0) + (50 - p.u0);
        let k_edge = (52 - p.v0) * (p.u1 - p.u0) + (64 - p.u0);
        assert!(p.prob[k_edge] < p.prob[k_mid]);
    }

    /// The Python reference (scripts/blazepose_prototype.py) on the same figure with a
    /// graded mask: tests/data/blazepose_rule_golden.json.
    #[test]
    fn matches_the_python_reference() {
        let golden: serde_json::Value =
            serde_json::from_str(include_str!("../tests/data/blazepose_rule_golden.json"))
                .expect("golden JSON parses");
        let mut pose = figure();
        for j in 0..INPUT {
            for i in 0..INPUT {
                let (tx, ty) = (i as f64 + 0.5, j as f64 + 0.5);
                let m = 1.2 - ((tx - 128.0) / 70.0).hypot((ty - 128.0) / 120.0);
                pose.mask[j * INPUT + i] = m.clamp(0.0, 1.0) as f32;
            }
        }
        let p = label_person(&pose, &RuleConfig::default(), 100, 160).expect("in the image");
        let field = |k: &str| golden[k].as_u64().expect("window bound") as usize;
        assert_eq!(
            (p.u0, p.u1, p.v0, p.v1),
            (field("u0"), field("u1"), field("v0"), field("v1"))
        );
        let want: Vec<u8> = golden["classes"]
            .as_str()
            .expect("classes string")
            .bytes()
            .map(|b| b - b'0')
            .collect();
        let probs: Vec<f64> = golden["probs"]
            .as_array()
            .expect("probs")
            .iter()
            .map(|v| v.as_f64().expect("number"))
            .collect();
        assert_eq!(want.len(), p.class.len());
        let same = want.iter().zip(&p.class).filter(|(a, b)| a == b).count();
        // Pixels exactly on a border between two bones may tie differently in f64 vs
        // numpy's summation order: allow 0.2 % of the window.
        assert!(
            same * 1000 >= want.len() * 998,
            "{same} of {} agree",
            want.len()
        );
        for k in 0..want.len() {
            // On the person's pixels; elsewhere the prototype writes 0 where this gives
            // the background's probability (1 − mask).
            if want[k] == p.class[k] && want[k] != 0 {
                // golden probabilities are rounded to 5 decimals
                assert!((probs[k] - f64::from(p.prob[k])).abs() < 1e-4, "pixel {k}");
            }
        }
    }

    #[test]
    fn legs_out_of_frame_are_not_invented() {
        use landmark::*;
        let mut pose = figure();
        for i in [LEFT_KNEE, RIGHT_KNEE, LEFT_ANKLE, RIGHT_ANKLE] {
            pose.presence[i] = 0.1;
        }
        let classes: Vec<u8> = bones(&pose, &RuleConfig::default())
            .iter()
            .map(|b| b.class)
            .collect();
        assert!(!classes.contains(&5) && !classes.contains(&6));
        assert!(classes.contains(&2) && classes.contains(&4));
    }

    #[test]
    fn no_mask_no_person_and_merge_takes_the_nearer_bone() {
        let mut pose = figure();
        pose.mask = vec![0.0; INPUT * INPUT];
        let empty = label_person(&pose, &RuleConfig::default(), 100, 160).expect("window");
        assert!(empty.class.iter().all(|&c| c == 0));

        let a = PersonLabels {
            u0: 0,
            u1: 2,
            v0: 0,
            v1: 1,
            class: vec![1, 2],
            prob: vec![0.9, 0.8],
            score: vec![0.5, 2.0],
            depth_m: None,
        };
        let b = PersonLabels {
            u0: 1,
            u1: 3,
            v0: 0,
            v1: 1,
            class: vec![3, 4],
            prob: vec![0.7, 0.6],
            score: vec![1.0, 1.0],
            depth_m: None,
        };
        let img = merge_people(4, 1, &[a.clone(), b.clone()]);
        let ids: Vec<u8> = img.labels.iter().map(|l| l.id()).collect();
        assert_eq!(ids, vec![1, 3, 4, 0]);
        // Outside every person: background, certain.
        assert_eq!(img.probs, Some(vec![0.9, 0.7, 0.6, 1.0]));

        // The person in front wins the overlap even with the farther bone...
        let front = PersonLabels {
            depth_m: Some(2.0),
            ..b.clone()
        };
        let behind = PersonLabels {
            depth_m: Some(3.0),
            ..a.clone()
        };
        let img = merge_people(4, 1, &[behind.clone(), front.clone()]);
        let ids: Vec<u8> = img.labels.iter().map(|l| l.id()).collect();
        assert_eq!(ids, vec![1, 3, 4, 0], "pixel 1: b is in front");
        // ...also with a smaller bone score behind it.
        let close_behind = PersonLabels {
            score: vec![0.1, 0.1],
            ..behind.clone()
        };
        let img = merge_people(4, 1, &[close_behind, front.clone()]);
        assert_eq!(img.labels[1].id(), 3);
        // Side by side (depths within SIDE_BY_SIDE_M): the nearer bone decides.
        let beside = PersonLabels {
            depth_m: Some(2.0 + SIDE_BY_SIDE_M / 2.0),
            score: vec![0.1, 0.1],
            ..a
        };
        let img = merge_people(4, 1, &[beside, front]);
        assert_eq!(img.labels[1].id(), 2);
    }

    /// [`label_person`]'s block culling gives what scoring every bone at every pixel
    /// gives (the reference below), on figures with graded masks and in several poses.
    #[test]
    fn block_culling_equals_scoring_every_bone() {
        let cfg = RuleConfig::default();
        for (angle, arm_dx) in [(0.0, 0.0), (0.3, 12.0), (-0.7, -20.0)] {
            let mut pose = figure();
            pose.roi.angle_rad = angle;
            pose.xy[landmark::LEFT_WRIST][0] += arm_dx;
            for j in 0..INPUT {
                for i in 0..INPUT {
                    let (tx, ty) = (i as f64 + 0.5, j as f64 + 0.5);
                    let m = 1.3 - ((tx - 128.0) / 60.0).hypot((ty - 128.0) / 110.0);
                    pose.mask[j * INPUT + i] = m.clamp(0.0, 1.0) as f32;
                }
            }
            let got = label_person(&pose, &cfg, 100, 160).expect("in the image");
            let bl = bones(&pose, &cfg);
            let axes = pose.roi.axes();
            let ww = got.u1 - got.u0;
            let mut labelled = 0;
            for v in got.v0..got.v1 {
                for u in got.u0..got.u1 {
                    let k = (v - got.v0) * ww + (u - got.u0);
                    let q = [u as f64, v as f64];
                    let m = mask_at(&pose, axes, q);
                    let mut per_class = [f64::INFINITY; 7];
                    for b in &bl {
                        let c = usize::from(b.class);
                        per_class[c] = per_class[c].min(b.score(q, cfg.torso_bias));
                    }
                    let (c1, e1, e2) = best_two(&per_class);
                    if m < cfg.mask_threshold || e1 > cfg.max_score {
                        assert_eq!(got.class[k], 0, "({u}, {v}) is not the person's");
                        assert!(got.score[k].is_infinite());
                        continue;
                    }
                    labelled += 1;
                    assert_eq!(usize::from(got.class[k]), c1, "({u}, {v})");
                    let conf = 1.0 - 0.5 * (-(e2 - e1) / cfg.margin_scale).exp();
                    // f32 storage of an f64 value
                    assert!((f64::from(got.prob[k]) - m * conf).abs() < 1e-6);
                }
            }
            assert!(labelled > 1000, "the figure is labelled: {labelled} px");
        }
    }
}
