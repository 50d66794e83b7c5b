//! Small rotation-matrix helpers, two-bone inverse kinematics and the seeded random draws
//! (uniform, Gaussian, slow sinusoidal sway) the body and pose modules use.

use std::f32::consts::TAU;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::geometry::{V3, add, dot, frame_from_axis, norm, normalize, scale, sub};

pub(crate) type M3 = [V3; 3];

pub(crate) const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
pub(crate) const UP: V3 = [0.0, 0.0, 1.0];

#[inline]
pub(crate) fn mv(m: &M3, v: V3) -> V3 {
    add(add(scale(m[0], v[0]), scale(m[1], v[1])), scale(m[2], v[2]))
}

#[inline]
pub(crate) fn mm(a: &M3, b: &M3) -> M3 {
    [mv(a, b[0]), mv(a, b[1]), mv(a, b[2])]
}

#[inline]
pub(crate) fn mtv(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

#[inline]
pub(crate) fn rot_x(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]]
}

#[inline]
pub(crate) fn rot_y(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]
}

#[inline]
pub(crate) fn rot_z(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Flexion (forward lean) about y, lateral bend about x, twist about z, applied in that
/// order from the parent.
#[inline]
pub(crate) fn rot_fsz(flex: f32, lat: f32, twist: f32) -> M3 {
    mm(&mm(&rot_y(flex), &rot_x(lat)), &rot_z(twist))
}

/// Two-bone inverse kinematics: the middle joint (knee, elbow) and the end point for a
/// chain of lengths `a`, `b` from `root` towards `target`, bending towards `pole`. The end
/// point is `target` when it is reachable, else the nearest reachable point on the line.
pub(crate) fn two_bone(root: V3, target: V3, a: f32, b: f32, pole: V3) -> (V3, V3) {
    let to = sub(target, root);
    let dist = norm(to);
    let n = if dist > 1e-6 {
        scale(to, 1.0 / dist)
    } else {
        [0.0, 0.0, -1.0]
    };
    let d = dist.clamp((a - b).abs() + 1e-4, a + b - 1e-4);
    let x = (a * a - b * b + d * d) / (2.0 * d);
    let h = (a * a - x * x).max(0.0).sqrt();
    let mut m = sub(pole, scale(n, dot(pole, n)));
    if norm(m) < 1e-6 {
        m = frame_from_axis(n)[0];
    }
    let m = normalize(m);
    let mid = add(add(root, scale(n, x)), scale(m, h));
    (mid, add(root, scale(n, d)))
}

pub(crate) fn uni(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.random::<f32>()
}

pub(crate) fn uni_deg(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    uni(rng, lo, hi).to_radians()
}

/// A standard normal deviate (Box–Muller).
pub(crate) fn gauss(rng: &mut ChaCha8Rng) -> f32 {
    let u1 = rng.random::<f32>().max(1e-7);
    let u2 = rng.random::<f32>();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

// ---------------------------------------------------------------------------------------
// Motion channels.

/// A scalar of the pose over time: a base value plus one slow sinusoid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Chan {
    pub(crate) base: f32,
    pub(crate) amp: f32,
    pub(crate) omega: f32,
    pub(crate) phase: f32,
}

impl Chan {
    pub(crate) fn at(&self, t_s: f64) -> f32 {
        if self.amp == 0.0 {
            return self.base;
        }
        let arg = f64::from(self.omega) * t_s + f64::from(self.phase);
        self.base + self.amp * (arg.sin() as f32)
    }
}

/// Slowest and fastest sway periods, seconds.
pub(crate) const SWAY_PERIOD_S: [f32; 2] = [2.0, 6.0];

/// A channel with base `base` and a sway of amplitude in `[lo, hi]` (same unit as `base`).
pub(crate) fn sway(rng: &mut ChaCha8Rng, base: f32, lo: f32, hi: f32) -> Chan {
    Chan {
        base,
        amp: uni(rng, lo, hi),
        omega: TAU / uni(rng, SWAY_PERIOD_S[0], SWAY_PERIOD_S[1]),
        phase: uni(rng, 0.0, TAU),
    }
}

/// Same with amplitudes in degrees and the base in radians.
pub(crate) fn sway_deg(rng: &mut ChaCha8Rng, base: f32, lo_deg: f32, hi_deg: f32) -> Chan {
    sway(rng, base, lo_deg.to_radians(), hi_deg.to_radians())
}

/// Same with the base drawn uniformly in `[base_lo_deg, base_hi_deg]`.
pub(crate) fn sway_r(
    rng: &mut ChaCha8Rng,
    base_lo_deg: f32,
    base_hi_deg: f32,
    lo_deg: f32,
    hi_deg: f32,
) -> Chan {
    let base = uni_deg(rng, base_lo_deg, base_hi_deg);
    sway_deg(rng, base, lo_deg, hi_deg)
}
