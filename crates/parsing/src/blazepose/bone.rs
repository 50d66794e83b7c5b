//! The rule's body parts: bone shapes between landmarks and their distance scores.

use super::decode::DecodedPose;
use super::landmark;
use super::model::NUM_LANDMARKS;
use super::roi::{P2, add, dot, mid, norm, scale, sub};

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
    /// The lower arm continues past the hand points by this × (hand − wrist). BlazePose's
    /// hand points are knuckles (pinky and index MCP, thumb IP), so the fingers reach about
    /// one more wrist-to-knuckle length beyond them when straight; 0.5 (the middle of the
    /// fingers; the capsule's radius covers more) replaced the prototype's 0 on 2026-12-04
    /// (tune split 0.463 → 0.465; 0.3 / 1.0: 0.464 / 0.466).
    pub hand_extend: f64,
    /// Added to the torso's score, in body scales: a limb in front of the torso wins.
    pub torso_bias: f64,
    /// An arm bone whose mean landmark depth lies more than this many body scales behind
    /// the torso's (the mean of the shoulders' and hips' depths) is behind the torso: it
    /// gets `torso_bias` too, so the precedence of a limb in front of the torso is not given
    /// to it and the nearer surface decides (the far arm of a person seen from the side, an
    /// arm behind the back). 0.2: about half a torso's depth front to back (chest depth ≈
    /// 0.2–0.25 m, shoulder to hip ≈ 0.5 m). +∞: off. Legs keep their precedence (tried:
    /// lower on the tune split).
    pub behind_torso_depth: f64,
    /// A mask pixel whose best score exceeds this is not the person's.
    pub max_score: f64,
    /// Bone-margin confidence: 1 − 0.5 exp(−(e2 − e1) / margin_scale).
    pub margin_scale: f64,
    /// Upper arms end flat on the medial side of the shoulder (the plane through the
    /// shoulder point across the upper arm, on the side of the other shoulder), round on its
    /// lateral side: the top of the shoulder and the chest beside the joint are the torso's,
    /// the deltoid outside it the arm's. A round end lets the upper arm take a disc around
    /// the shoulder point that Pascal-Person-Part labels torso
    /// (docs/notes/2026-12-03-blazepose.md, 2026-12-04). Legs keep round ends (tried flat:
    /// a seated person's thighs begin above the model's hip points).
    pub flat_shoulders: bool,
    /// A thigh whose knee lies outside the image gets its upper-leg bone from a counting hip
    /// to where the model puts the knee, whatever the knee's presence: presence is the
    /// model's "inside the frame" probability, so a knee below the image's edge has a low
    /// one although the thigh is in view (a seated person, a close-up; issue 29's "legs from
    /// the hips when the knees are missing"). The knee must still be visible ≥
    /// `min_visibility` as any limb joint (a knee behind a table below the frame is not),
    /// and the hip must lie inside the image by at least the thigh's radius, so that the
    /// thigh is in view and not only the round end of its capsule (a person cut at the
    /// hips). No lower leg: it would lie outside the frame.
    pub thighs_past_frame: bool,
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
            hand_extend: 0.5,
            torso_bias: 0.2,
            behind_torso_depth: 0.2,
            max_score: 3.0,
            margin_scale: 0.5,
            flat_shoulders: true,
            thighs_past_frame: true,
        }
    }
}

/// How a polyline bone ends at its first point (a limb's root).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoneStart {
    /// A round end (the capsule).
    Round,
    /// Flat on the medial side: `outward` is the unit vector pointing away from the body at
    /// the first point (from the other shoulder); a pixel both behind the plane through the
    /// first point, across the first segment, and medial of the first point is outside the
    /// bone by at least the smaller of those two distances; laterally the end stays round.
    FlatMedial {
        /// Unit vector, image px.
        outward: P2,
    },
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
    /// Added to the score, body scales: `torso_bias` for the torso and for an arm behind the
    /// torso, else 0.
    pub bias: f64,
    /// How a polyline bone ends at its first point.
    pub start: BoneStart,
}

/// The bones a pose supports (§3 of the note) in an image of `width`×`height` px.
pub fn bones(pose: &DecodedPose, cfg: &RuleConfig, width: usize, height: usize) -> Vec<Bone> {
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
    // Outside the image's pixel centres by more than half a pixel.
    // How far inside the image's pixel centres, px (negative outside).
    let inside_by = |q: P2| {
        (q[0] + 0.5)
            .min(width as f64 - 0.5 - q[0])
            .min(q[1] + 0.5)
            .min(height as f64 - 0.5 - q[1])
    };
    let outside = |q: P2| {
        !(-0.5..=width as f64 - 0.5).contains(&q[0])
            || !(-0.5..=height as f64 - 0.5).contains(&q[1])
    };
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
            bias: cfg.torso_bias,
            start: BoneStart::Round,
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
            bias: 0.0,
            start: BoneStart::Round,
        });
    }
    // Depth of the torso and the bias of a limb bone between landmarks `idx` (see
    // `behind_torso_depth`).
    let depth = &pose.depth_px;
    let mean_depth = |idx: &[usize]| idx.iter().map(|&i| depth[i]).sum::<f64>() / idx.len() as f64;
    let behind_bias = |idx: &[usize]| {
        if depth.len() < NUM_LANDMARKS {
            return 0.0;
        }
        let torso = mean_depth(&[LEFT_SHOULDER, RIGHT_SHOULDER, LEFT_HIP, RIGHT_HIP]);
        if mean_depth(idx) - torso > cfg.behind_torso_depth * body {
            cfg.torso_bias
        } else {
            0.0
        }
    };
    let limbs = [
        (
            LEFT_SHOULDER,
            RIGHT_SHOULDER,
            LEFT_ELBOW,
            LEFT_WRIST,
            &LEFT_HAND[..],
            3u8,
        ),
        (
            RIGHT_SHOULDER,
            LEFT_SHOULDER,
            RIGHT_ELBOW,
            RIGHT_WRIST,
            &RIGHT_HAND[..],
            3u8,
        ),
        (
            LEFT_HIP,
            RIGHT_HIP,
            LEFT_KNEE,
            LEFT_ANKLE,
            &LEFT_FOOT[..],
            5u8,
        ),
        (
            RIGHT_HIP,
            LEFT_HIP,
            RIGHT_KNEE,
            RIGHT_ANKLE,
            &RIGHT_FOOT[..],
            5u8,
        ),
    ];
    for (root, other, joint, end, tips, upper) in limbs {
        let (r_up, r_low) = if upper == 3 {
            (cfg.r_upper_arm, cfg.r_lower_arm)
        } else {
            (cfg.r_upper_leg, cfg.r_lower_leg)
        };
        let joint_past_frame = cfg.thighs_past_frame
            && upper == 5
            && outside(p[joint])
            && !ok(joint)
            && pose.visibility[joint] >= cfg.min_visibility
            && inside_by(p[root]) >= r_up * body;
        if !(seen(&[root, joint]) || seen(&[root]) && joint_past_frame) {
            continue;
        }
        out.push(Bone {
            class: upper,
            shape: BoneShape::Polyline(vec![p[root], p[joint]]),
            radius_px: r_up * body,
            scale_px: body,
            bias: if upper == 3 {
                behind_bias(&[root, joint])
            } else {
                0.0
            },
            start: match outward(p[root], p[other]) {
                Some(outward) if cfg.flat_shoulders && upper == 3 => {
                    BoneStart::FlatMedial { outward }
                }
                _ => BoneStart::Round,
            },
        });
        if joint_past_frame || !seen(&[end]) {
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
            bias: if upper == 3 {
                behind_bias(&[joint, end])
            } else {
                0.0
            },
            start: BoneStart::Round,
        });
    }
    out
}

/// The unit vector from `other` to `root` (outward from the body at a shoulder),
/// `None` when they coincide.
fn outward(root: P2, other: P2) -> Option<P2> {
    let v = sub(root, other);
    let n = norm(v);
    (n > 1e-6).then(|| scale(v, 1.0 / n))
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
    /// The bone's score at `q`: (distance to its surface) / body scale + 1 + its
    /// [`Bone::bias`] (`torso_bias` for the torso, §4 of the note). With [`BoneStart::FlatMedial`] the
    /// distance is max(distance − radius, min(distance behind the start plane, distance
    /// medial of the first point)): still 1-Lipschitz in `q`,
    /// so a score moves by at most (distance moved) / body scale, which the block culling
    /// of `label_person` relies on.
    pub fn score(&self, q: P2) -> f64 {
        let d = match &self.shape {
            BoneShape::Polyline(pts) => {
                let d = pts
                    .windows(2)
                    .map(|w| segment_distance(q, w[0], w[1]))
                    .fold(f64::INFINITY, f64::min)
                    - self.radius_px;
                let behind = match (pts.as_slice(), self.start) {
                    ([a, b, ..], BoneStart::FlatMedial { outward }) if norm(sub(*b, *a)) > 1e-9 => {
                        let axis = sub(*b, *a);
                        let behind = -dot(sub(q, *a), axis) / norm(axis);
                        behind.min(-dot(sub(q, *a), outward))
                    }
                    _ => f64::NEG_INFINITY,
                };
                d.max(behind)
            }
            BoneShape::Quad(quad) => polygon_distance(q, quad) - self.radius_px,
        };
        d / self.scale_px + 1.0 + self.bias
    }
}

/// A segment a–b of a bone with what [`segment_distance`] derives from its ends alone.
#[derive(Clone, Copy, Debug)]
struct Segment {
    a: P2,
    b: P2,
    /// b − a.
    ab: P2,
    /// |ab|², px².
    l2: f64,
}

impl Segment {
    fn new(a: P2, b: P2) -> Segment {
        let ab = sub(b, a);
        Segment {
            a,
            b,
            ab,
            l2: dot(ab, ab),
        }
    }

    /// `q` minus its nearest point on a–b: [`segment_distance`] is its length (the same
    /// operations on the same values).
    fn offset(&self, q: P2) -> P2 {
        if self.l2 < 1e-18 {
            return sub(q, self.a);
        }
        let t = (dot(sub(q, self.a), self.ab) / self.l2).clamp(0.0, 1.0);
        sub(q, add(self.a, scale(self.ab, t)))
    }
}

/// The most segments [`min_distance`] compares by their squares (the torso quad's four).
const MAX_SQUARED: usize = 4;
/// Two squared distances this far apart (relative) cannot swap order once `hypot` (within
/// an ulp of the true length) takes their roots.
const SQUARED_MARGIN: f64 = 1e-9;

/// The smallest of `q`'s distances to `segments` (`+∞` for none), as
/// `segments.map(segment_distance).fold(+∞, f64::min)` gives it, with `hypot` (a libm call,
/// most of a bone score's time) taken only of the segments whose squared distance is
/// within [`SQUARED_MARGIN`] of the smallest: the others' lengths are larger, so the
/// minimum is the same value. Anything unusual (a non-finite or tiny square, more segments
/// than [`MAX_SQUARED`]) takes every root.
fn min_distance(segments: &[Segment], q: P2) -> f64 {
    let all = || {
        segments
            .iter()
            .map(|s| norm(s.offset(q)))
            .fold(f64::INFINITY, f64::min)
    };
    if segments.len() < 2 || segments.len() > MAX_SQUARED {
        return all();
    }
    let mut offsets = [[0.0; 2]; MAX_SQUARED];
    let mut squares = [0.0; MAX_SQUARED];
    for (k, s) in segments.iter().enumerate() {
        offsets[k] = s.offset(q);
        squares[k] = dot(offsets[k], offsets[k]);
    }
    let squares = &squares[..segments.len()];
    let smallest = squares.iter().copied().fold(f64::INFINITY, f64::min);
    if !(smallest.is_finite() && smallest > 1e-200) || squares.iter().any(|s| s.is_nan()) {
        return all();
    }
    let limit = smallest * (1.0 + SQUARED_MARGIN);
    squares
        .iter()
        .zip(&offsets)
        .filter(|&(&s, _)| s <= limit)
        .map(|(_, &o)| norm(o))
        .fold(f64::INFINITY, f64::min)
}

/// A [`Bone`] with the parts of its score that do not depend on the pixel computed once
/// ([`label_person`](super::label_person) scores each bone at up to a few 10⁵ pixels):
/// [`PreparedBone::score`] equals [`Bone::score`] bit for bit.
#[derive(Clone, Debug)]
pub(crate) struct PreparedBone {
    pub(crate) class: u8,
    pub(crate) scale_px: f64,
    radius_px: f64,
    bias: f64,
    segments: Vec<Segment>,
    /// The torso quad's edges (even-odd test on them), else a polyline's segments.
    quad: bool,
    /// A flat medial start: the first point, the first segment's axis, its length and the
    /// outward unit vector.
    flat: Option<(P2, P2, f64, P2)>,
}

impl PreparedBone {
    pub(crate) fn new(bone: &Bone) -> PreparedBone {
        let (segments, quad, flat) = match &bone.shape {
            BoneShape::Polyline(pts) => {
                let flat = match (pts.as_slice(), bone.start) {
                    ([a, b, ..], BoneStart::FlatMedial { outward }) if norm(sub(*b, *a)) > 1e-9 => {
                        let axis = sub(*b, *a);
                        Some((*a, axis, norm(axis), outward))
                    }
                    _ => None,
                };
                let segments = pts.windows(2).map(|w| Segment::new(w[0], w[1])).collect();
                (segments, false, flat)
            }
            BoneShape::Quad(quad) => {
                let n = quad.len();
                let segments = (0..n)
                    .map(|i| Segment::new(quad[i], quad[(i + 1) % n]))
                    .collect();
                (segments, true, None)
            }
        };
        PreparedBone {
            class: bone.class,
            scale_px: bone.scale_px,
            radius_px: bone.radius_px,
            bias: bone.bias,
            segments,
            quad,
            flat,
        }
    }

    /// [`Bone::score`] at `q`.
    pub(crate) fn score(&self, q: P2) -> f64 {
        let d = if self.quad {
            // polygon_distance with the edges' differences taken once, and the distance
            // to the edges only outside (inside it is 0 whatever they are).
            let mut inside = false;
            for s in &self.segments {
                let (a, b) = (s.a, s.b);
                if (a[1] > q[1]) != (b[1] > q[1]) {
                    let x = a[0] + (q[1] - a[1]) * s.ab[0] / s.ab[1];
                    if q[0] < x {
                        inside = !inside;
                    }
                }
            }
            let d = if inside {
                0.0
            } else {
                min_distance(&self.segments, q)
            };
            d - self.radius_px
        } else {
            let d = min_distance(&self.segments, q) - self.radius_px;
            let behind = match self.flat {
                Some((a, axis, length, outward)) => {
                    let behind = -dot(sub(q, a), axis) / length;
                    behind.min(-dot(sub(q, a), outward))
                }
                None => f64::NEG_INFINITY,
            };
            d.max(behind)
        };
        d / self.scale_px + 1.0 + self.bias
    }
}
