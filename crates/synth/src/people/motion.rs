//! How a person moves over a sequence: standing, walking a stadium-shaped path, or a
//! hand-over's shared meeting point.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use super::math::Chan;
use crate::geometry::{V3, add, rotate_z};

/// A closed walking loop: two straight legs joined by half circles (a stadium), walked
/// counter-clockwise at constant speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Stadium {
    pub(crate) center: [f32; 2],
    pub(crate) angle: f32,
    pub(crate) half_len: f32,
    pub(crate) radius: f32,
}

impl Stadium {
    pub(crate) fn perimeter(&self) -> f32 {
        4.0 * self.half_len + TAU * self.radius
    }

    /// Position (world x y) and heading at arc length `s` metres.
    pub(crate) fn at(&self, s: f64) -> ([f32; 2], f32) {
        let p = f64::from(self.perimeter());
        let s = if p > 0.0 { s.rem_euclid(p) as f32 } else { 0.0 };
        let (l, r) = (self.half_len, self.radius.max(1e-3));
        let (local, heading) = if s < 2.0 * l {
            ([-l + s, -r], 0.0)
        } else if s < 2.0 * l + PI * r {
            let a = -FRAC_PI_2 + (s - 2.0 * l) / r;
            ([l + r * a.cos(), r * a.sin()], a + FRAC_PI_2)
        } else if s < 4.0 * l + PI * r {
            let d = s - 2.0 * l - PI * r;
            ([l - d, r], PI)
        } else {
            let a = FRAC_PI_2 + (s - 4.0 * l - PI * r) / r;
            ([-l + r * a.cos(), r * a.sin()], a + FRAC_PI_2)
        };
        let w = rotate_z([local[0], local[1], 0.0], self.angle);
        (
            [self.center[0] + w[0], self.center[1] + w[1]],
            heading + self.angle,
        )
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Walk {
    pub(crate) path: Stadium,
    pub(crate) speed_m_s: f32,
    pub(crate) s0_m: f32,
    /// Gait cycle (stride) period, seconds, and stride length, metres.
    pub(crate) gait_period_s: f32,
    pub(crate) stride_m: f32,
    pub(crate) gait_phase0: f32,
}

impl Walk {
    pub(crate) fn at(&self, t_s: f64) -> ([f32; 2], f32) {
        self.path
            .at(f64::from(self.s0_m) + f64::from(self.speed_m_s) * t_s)
    }

    /// Gait phase in `[0, 1)`: 0 = left heel strike.
    pub(crate) fn phase(&self, t_s: f64) -> f32 {
        (t_s / f64::from(self.gait_period_s) + f64::from(self.gait_phase0)).rem_euclid(1.0) as f32
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Motion {
    /// Standing in place: pelvis rest position (world x y) and yaw; feet planted there.
    Still { xy: [f32; 2], yaw: f32 },
    /// Walking a loop.
    Walk(Walk),
}

impl Motion {
    pub(crate) fn at(&self, t_s: f64) -> ([f32; 2], f32) {
        match self {
            Motion::Still { xy, yaw } => (*xy, *yaw),
            Motion::Walk(w) => w.at(t_s),
        }
    }
}

/// The shared state of a hand-over, copied into both people.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Handover {
    /// Person 1 gives with the right hand; person 2 takes with the left.
    pub(crate) giver: bool,
    /// Meeting point of the hands at rest, world.
    pub(crate) meet: V3,
    /// Horizontal unit vector from giver to receiver.
    pub(crate) u: V3,
    /// Sway of the meeting point (world x y z, metres).
    pub(crate) sway: [Chan; 3],
    /// Distance between the two palm centres, metres.
    pub(crate) hand_sep: f32,
    /// Top of the hands above the meeting point, metres (where the object rests).
    pub(crate) hand_top: f32,
    pub(crate) object_color: [f32; 3],
}

impl Handover {
    pub(crate) fn meet_at(&self, t_s: f64) -> V3 {
        add(self.meet, self.sway.map(|c| c.at(t_s)))
    }

    /// Left of the giver (the hands meet on the giver's right side, at `-v`).
    pub(crate) fn v(&self) -> V3 {
        [-self.u[1], self.u[0], 0.0]
    }
}

// ---------------------------------------------------------------------------------------
// The person.
