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
