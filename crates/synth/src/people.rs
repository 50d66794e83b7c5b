//! Articulated synthetic people: body shape, clothing, a pose library, joint perturbation
//! and smooth motion over the frames of a sequence.
//!
//! # Conventions
//! - World frame: metres, z up, floor at z = 0. A person's body frame has x forward, y to
//!   the person's left, z up; its yaw is the angle of x about world z (0 = +x).
//! - The skeleton is a pelvis root (midpoint of the hip joints) with position and yaw, a
//!   spine of lumbar and thoracic joints, neck and head, shoulders, elbows and wrists, hips,
//!   knees and ankles. Trunk and arms use forward kinematics on joint angles (radians
//!   inside); legs are solved with two-bone inverse kinematics from planted feet, so feet
//!   stay on the floor and knees always bend forward. In a hand-over the handing arms are
//!   solved the same way towards a shared meeting point, so the hands stay together.
//! - Segment lengths follow Drillis & Contini's anthropometric ratios of body height
//!   (Winter, *Biomechanics and Motor Control of Human Movement*, fig. 4.1).
//! - Everything is drawn from `rand_chacha::ChaCha8Rng` streams of the sequence seed: person
//!   `i` uses stream `i + 1`, placement its own stream, so the same seed gives the same
//!   people and poses.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::config::PeopleConfig;
use crate::geometry::{
    Material, Owner, Primitive, Segment, Shape, Texture, V3, add, cross, dot, frame_from_axis,
    norm, normalize, rotate_z, scale, sub,
};

mod clothes;
mod draw;
mod placement;
#[cfg(test)]
mod tests;

use clothes::*;
use draw::*;
pub use placement::{handover_object, make_people};

/// Clearance kept between a person's pelvis centre and a [`FloorObstacle`]'s rim, metres
/// (about the half width of a body seen from above).
pub const PERSON_RADIUS_M: f32 = 0.3;

/// Size of the object passed in a hand-over, metres: across the arms, along the line
/// between the two people, and vertical.
pub const HANDOVER_OBJECT_SIZE_M: V3 = [0.25, 0.18, 0.12];

/// A circle on the floor people must keep out of (table, robot pedestal): centre (x, y)
/// and radius, metres, world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorObstacle {
    /// Centre, world x y, metres.
    pub center_m: [f32; 2],
    /// Radius, metres.
    pub radius_m: f32,
}

/// The poses of the library (`people.poses` in the scene configuration).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyPose {
    /// Upright, arms hanging, small sway.
    Standing,
    /// Walking a closed loop inside the area with a gait cycle of legs and arms.
    Walking,
    /// One or both arms stretched forward at chest height.
    Reaching,
    /// Handing an object over (with a partner in a hand-over, else offering forward).
    HandingOver,
    /// Forearms crossed in front of the chest.
    ArmsCrossed,
    /// Hands resting on the hips, elbows out.
    HandsOnHips,
    /// One arm pointing forward and to the side, head turned that way.
    Pointing,
    /// Knees bent, pelvis lowered, trunk leaning forward, feet on the floor.
    Crouching,
}

impl BodyPose {
    /// Every pose, in the order of `config::POSE_NAMES`.
    pub const ALL: [BodyPose; 8] = [
        BodyPose::Standing,
        BodyPose::Walking,
        BodyPose::Reaching,
        BodyPose::HandingOver,
        BodyPose::ArmsCrossed,
        BodyPose::HandsOnHips,
        BodyPose::Pointing,
        BodyPose::Crouching,
    ];

    /// The configuration name of the pose (`"arms_crossed"`).
    pub fn name(self) -> &'static str {
        match self {
            BodyPose::Standing => "standing",
            BodyPose::Walking => "walking",
            BodyPose::Reaching => "reaching",
            BodyPose::HandingOver => "handing_over",
            BodyPose::ArmsCrossed => "arms_crossed",
            BodyPose::HandsOnHips => "hands_on_hips",
            BodyPose::Pointing => "pointing",
            BodyPose::Crouching => "crouching",
        }
    }

    /// The pose of a configuration name, `None` for an unknown name.
    pub fn from_name(name: &str) -> Option<BodyPose> {
        BodyPose::ALL.into_iter().find(|p| p.name() == name)
    }
}

// ---------------------------------------------------------------------------------------
// Small maths: rotation matrices stored as columns (the rotated x, y, z axes).

type M3 = [V3; 3];

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const UP: V3 = [0.0, 0.0, 1.0];

#[inline]
fn mv(m: &M3, v: V3) -> V3 {
    add(add(scale(m[0], v[0]), scale(m[1], v[1])), scale(m[2], v[2]))
}

#[inline]
fn mm(a: &M3, b: &M3) -> M3 {
    [mv(a, b[0]), mv(a, b[1]), mv(a, b[2])]
}

#[inline]
fn mtv(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

#[inline]
fn rot_x(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]]
}

#[inline]
fn rot_y(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]
}

#[inline]
fn rot_z(a: f32) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Flexion (forward lean) about y, lateral bend about x, twist about z, applied in that
/// order from the parent.
#[inline]
fn rot_fsz(flex: f32, lat: f32, twist: f32) -> M3 {
    mm(&mm(&rot_y(flex), &rot_x(lat)), &rot_z(twist))
}

/// Two-bone inverse kinematics: the middle joint (knee, elbow) and the end point for a
/// chain of lengths `a`, `b` from `root` towards `target`, bending towards `pole`. The end
/// point is `target` when it is reachable, else the nearest reachable point on the line.
fn two_bone(root: V3, target: V3, a: f32, b: f32, pole: V3) -> (V3, V3) {
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

fn uni(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.random::<f32>()
}

fn uni_deg(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    uni(rng, lo, hi).to_radians()
}

/// A standard normal deviate (Box–Muller).
fn gauss(rng: &mut ChaCha8Rng) -> f32 {
    let u1 = rng.random::<f32>().max(1e-7);
    let u2 = rng.random::<f32>();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

// ---------------------------------------------------------------------------------------
// Motion channels.

/// A scalar of the pose over time: a base value plus one slow sinusoid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Chan {
    base: f32,
    amp: f32,
    omega: f32,
    phase: f32,
}

impl Chan {
    fn at(&self, t_s: f64) -> f32 {
        if self.amp == 0.0 {
            return self.base;
        }
        let arg = f64::from(self.omega) * t_s + f64::from(self.phase);
        self.base + self.amp * (arg.sin() as f32)
    }
}

/// Slowest and fastest sway periods, seconds.
const SWAY_PERIOD_S: [f32; 2] = [2.0, 6.0];

/// A channel with base `base` and a sway of amplitude in `[lo, hi]` (same unit as `base`).
fn sway(rng: &mut ChaCha8Rng, base: f32, lo: f32, hi: f32) -> Chan {
    Chan {
        base,
        amp: uni(rng, lo, hi),
        omega: TAU / uni(rng, SWAY_PERIOD_S[0], SWAY_PERIOD_S[1]),
        phase: uni(rng, 0.0, TAU),
    }
}

/// Same with amplitudes in degrees and the base in radians.
fn sway_deg(rng: &mut ChaCha8Rng, base: f32, lo_deg: f32, hi_deg: f32) -> Chan {
    sway(rng, base, lo_deg.to_radians(), hi_deg.to_radians())
}

/// Same with the base drawn uniformly in `[base_lo_deg, base_hi_deg]`.
fn sway_r(
    rng: &mut ChaCha8Rng,
    base_lo_deg: f32,
    base_hi_deg: f32,
    lo_deg: f32,
    hi_deg: f32,
) -> Chan {
    let base = uni_deg(rng, base_lo_deg, base_hi_deg);
    sway_deg(rng, base, lo_deg, hi_deg)
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Trunk {
    /// Pelvis offset in the body frame, metres.
    pelvis_x: Chan,
    pelvis_y: Chan,
    /// Pelvis lowering below the planted height, metres.
    pelvis_drop: Chan,
    pelvis_yaw: Chan,
    pelvis_pitch: Chan,
    pelvis_roll: Chan,
    lumbar_flex: Chan,
    lumbar_lat: Chan,
    lumbar_twist: Chan,
    thor_flex: Chan,
    thor_lat: Chan,
    thor_twist: Chan,
    neck_flex: Chan,
    neck_lat: Chan,
    neck_yaw: Chan,
    head_nod: Chan,
    head_yaw: Chan,
}

/// One arm's joint angles, radians: shoulder flexion (forward), abduction (outward), twist
/// about the upper arm (R_z angle in the arm frame), elbow flexion (>= 0), wrist flexion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Arm {
    flex: Chan,
    abd: Chan,
    twist: Chan,
    elbow: Chan,
    wrist: Chan,
    /// Shoulder flexion amplitude following the gait (walking), radians.
    gait_swing: f32,
}

/// Where a foot is planted: ankle x y in the body frame at rest, metres, and toe-out yaw.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Leg {
    ankle_xy: [f32; 2],
    toe_yaw: f32,
}

/// Elbow flexion limits, radians (no hyperextension).
const ELBOW_MIN_RAD: f32 = 0.03;
const ELBOW_MAX_RAD: f32 = 2.6;

// ---------------------------------------------------------------------------------------
// Body shape.

/// Lengths and radii of one body, metres (fractions of height from Drillis & Contini).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Dims {
    height: f32,
    hip_half_w: f32,
    thigh: f32,
    shin: f32,
    ankle_h: f32,
    foot_center: V3,
    foot_half: V3,
    pelvis_center: V3,
    pelvis_radii: V3,
    lumbar_up: f32,
    abdomen_center: V3,
    abdomen_radii: V3,
    thoracic_up: f32,
    chest_center: V3,
    chest_radii: V3,
    shoulder: V3,
    shoulder_r: f32,
    neck_base: V3,
    neck_vec: V3,
    neck_r: f32,
    head_center: V3,
    head_radii: V3,
    hair_offset: V3,
    hair_radii: V3,
    upper_arm: f32,
    forearm: f32,
    hand_half: V3,
    upper_arm_r: f32,
    forearm_r: f32,
    thigh_r: f32,
    shin_r: f32,
}

impl Dims {
    fn new(h: f32, girth: f32, hair_volume: f32) -> Dims {
        let g = girth;
        let gl = girth.powf(0.8);
        Dims {
            height: h,
            hip_half_w: 0.05 * h * (1.0 + 0.3 * (g - 1.0)),
            thigh: 0.245 * h,
            shin: 0.246 * h,
            ankle_h: 0.039 * h,
            foot_center: [0.051 * h, 0.0, -0.0195 * h],
            foot_half: [0.076 * h, 0.0275 * h * g.sqrt(), 0.0195 * h],
            pelvis_center: [-0.005 * h, 0.0, 0.02 * h],
            pelvis_radii: [0.055 * h * g, 0.095 * h * g, 0.06 * h],
            lumbar_up: 0.07 * h,
            abdomen_center: [0.0, 0.0, 0.035 * h],
            abdomen_radii: [0.05 * h * g, 0.08 * h * g, 0.055 * h],
            thoracic_up: 0.08 * h,
            chest_center: [0.0, 0.0, 0.065 * h],
            chest_radii: [0.058 * h * g, 0.088 * h * g, 0.085 * h],
            shoulder: [-0.01 * h, 0.104 * h * (1.0 + 0.4 * (g - 1.0)), 0.125 * h],
            shoulder_r: 0.032 * h * g,
            neck_base: [-0.005 * h, 0.0, 0.15 * h],
            neck_vec: [0.005 * h, 0.0, 0.045 * h],
            neck_r: 0.03 * h * g.sqrt(),
            head_center: [0.01 * h, 0.0, 0.06 * h],
            head_radii: [0.057 * h, 0.045 * h, 0.065 * h],
            hair_offset: [-0.016 * h, 0.0, 0.009 * h * hair_volume],
            hair_radii: [
                0.054 * h,
                0.046 * h * hair_volume.sqrt(),
                0.059 * h * hair_volume,
            ],
            upper_arm: 0.186 * h,
            forearm: 0.146 * h,
            hand_half: [0.024 * h * g.sqrt(), 0.012 * h * g.sqrt(), 0.054 * h],
            upper_arm_r: 0.026 * h * gl,
            forearm_r: 0.021 * h * gl,
            thigh_r: 0.042 * h * gl,
            shin_r: 0.029 * h * gl,
        }
    }

    fn leg(&self) -> f32 {
        self.thigh + self.shin
    }

    /// Shoulder joint in the chest frame (origin at the thoracic joint); `side` +1 left.
    fn shoulder_at(&self, side: f32) -> V3 {
        [self.shoulder[0], side * self.shoulder[1], self.shoulder[2]]
    }
}

/// Fraction of the leg length between hip and ankle when standing (knees nearly straight).
const STAND_LEG_FRACTION: f32 = 0.998;
/// Same while walking (knees a little bent through the stance).
const WALK_LEG_FRACTION: f32 = 0.975;

// ---------------------------------------------------------------------------------------
// Motion through the area.

/// A closed walking loop: two straight legs joined by half circles (a stadium), walked
/// counter-clockwise at constant speed.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stadium {
    center: [f32; 2],
    angle: f32,
    half_len: f32,
    radius: f32,
}

impl Stadium {
    fn perimeter(&self) -> f32 {
        4.0 * self.half_len + TAU * self.radius
    }

    /// Position (world x y) and heading at arc length `s` metres.
    fn at(&self, s: f64) -> ([f32; 2], f32) {
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
struct Walk {
    path: Stadium,
    speed_m_s: f32,
    s0_m: f32,
    /// Gait cycle (stride) period, seconds, and stride length, metres.
    gait_period_s: f32,
    stride_m: f32,
    gait_phase0: f32,
}

impl Walk {
    fn at(&self, t_s: f64) -> ([f32; 2], f32) {
        self.path
            .at(f64::from(self.s0_m) + f64::from(self.speed_m_s) * t_s)
    }

    /// Gait phase in `[0, 1)`: 0 = left heel strike.
    fn phase(&self, t_s: f64) -> f32 {
        (t_s / f64::from(self.gait_period_s) + f64::from(self.gait_phase0)).rem_euclid(1.0) as f32
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    /// Standing in place: pelvis rest position (world x y) and yaw; feet planted there.
    Still { xy: [f32; 2], yaw: f32 },
    /// Walking a loop.
    Walk(Walk),
}

impl Motion {
    fn at(&self, t_s: f64) -> ([f32; 2], f32) {
        match self {
            Motion::Still { xy, yaw } => (*xy, *yaw),
            Motion::Walk(w) => w.at(t_s),
        }
    }
}

/// The shared state of a hand-over, copied into both people.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Handover {
    /// Person 1 gives with the right hand; person 2 takes with the left.
    giver: bool,
    /// Meeting point of the hands at rest, world.
    meet: V3,
    /// Horizontal unit vector from giver to receiver.
    u: V3,
    /// Sway of the meeting point (world x y z, metres).
    sway: [Chan; 3],
    /// Distance between the two palm centres, metres.
    hand_sep: f32,
    /// Top of the hands above the meeting point, metres (where the object rests).
    hand_top: f32,
    object_color: [f32; 3],
}

impl Handover {
    fn meet_at(&self, t_s: f64) -> V3 {
        add(self.meet, self.sway.map(|c| c.at(t_s)))
    }

    /// Left of the giver (the hands meet on the giver's right side, at `-v`).
    fn v(&self) -> V3 {
        [-self.u[1], self.u[0], 0.0]
    }
}

// ---------------------------------------------------------------------------------------
// The person.

/// One synthetic person for a whole sequence: shape, clothing and motion.
#[derive(Clone, Debug)]
pub struct Person {
    /// 1-based id (written in `depth_person` images).
    pub id: u8,
    pose: BodyPose,
    girth: f32,
    dims: Dims,
    clothes: Clothes,
    motion: Motion,
    trunk: Trunk,
    /// Left (index 0) and right arm.
    arms: [Arm; 2],
    /// Left (index 0) and right leg.
    legs: [Leg; 2],
    /// Pelvis height (hip joints) the pose aims for before the legs limit it, metres.
    hip_z_nominal: f32,
    handover: Option<Handover>,
}

/// Sides: +1 left, -1 right, in arm and leg index order.
const SIDES: [f32; 2] = [1.0, -1.0];

/// Joint positions and frames of one time step (world frame).
struct Skeleton {
    root: V3,
    pelvis: M3,
    lumbar: V3,
    abdomen: M3,
    thoracic: V3,
    chest: M3,
    neck_base: V3,
    neck_top: V3,
    head: M3,
    head_pos: V3,
    shoulder: [V3; 2],
    elbow: [V3; 2],
    wrist: [V3; 2],
    hand_center: [V3; 2],
    hand_axes: [M3; 2],
    hip: [V3; 2],
    knee: [V3; 2],
    ankle: [V3; 2],
    foot: [M3; 2],
}

impl Person {
    /// The person's primitives at time `t_s` (seconds from the first frame), appended
    /// to `out`; every primitive has `Owner::Person { person: self.id, .. }`.
    pub fn primitives_at(&self, t_s: f64, out: &mut Vec<Primitive>) {
        let sk = self.skeleton_at(t_s);
        self.emit(&sk, out);
    }

    /// The direction the person faces at `t_s` (yaw about z, radians; 0 = +x).
    pub fn yaw_rad_at(&self, t_s: f64) -> f32 {
        let (_, yaw) = self.motion.at(t_s);
        let yaw = yaw + self.trunk.pelvis_yaw.at(t_s);
        (yaw + PI).rem_euclid(TAU) - PI
    }

    /// Body height (floor to the top of the head standing upright), metres.
    pub fn height_m(&self) -> f32 {
        self.dims.height
    }

    /// Build factor (1 = average; scales torso and limb radii).
    pub fn girth(&self) -> f32 {
        self.girth
    }

    /// The pose drawn for this person.
    pub fn pose(&self) -> BodyPose {
        self.pose
    }

    /// Whether the forearms are bare (short sleeves).
    pub fn short_sleeves(&self) -> bool {
        self.clothes.short_sleeves
    }

    /// Rest position of the pelvis at `t_s` (world x y, metres; without the small sway).
    pub fn pelvis_xy_at(&self, t_s: f64) -> [f32; 2] {
        self.motion.at(t_s).0
    }

    fn skeleton_at(&self, t: f64) -> Skeleton {
        let d = &self.dims;
        let tr = &self.trunk;
        let (base_xy, base_yaw) = self.motion.at(t);
        let walk = match self.motion {
            Motion::Walk(w) => Some((w, w.phase(t))),
            Motion::Still { .. } => None,
        };
        let gait_cos = walk.map_or(0.0, |(_, ph)| (TAU * ph).cos());

        // Pelvis orientation and horizontal position.
        let yaw = base_yaw + tr.pelvis_yaw.at(t) + 0.07 * gait_cos;
        let pelvis = mm(
            &rot_z(yaw),
            &mm(&rot_y(tr.pelvis_pitch.at(t)), &rot_x(tr.pelvis_roll.at(t))),
        );
        let off = rotate_z([tr.pelvis_x.at(t), tr.pelvis_y.at(t), 0.0], base_yaw);
        let root_xy = [base_xy[0] + off[0], base_xy[1] + off[1]];

        // Ankle targets: planted (still) or following the gait (walking).
        let mut ankle_target = [[0.0; 3]; 2];
        let mut toe_yaw = [0.0; 2];
        for i in 0..2 {
            let leg = &self.legs[i];
            let (rel, lift) = match walk {
                Some((w, ph)) => {
                    let u = if i == 0 {
                        ph
                    } else {
                        (ph + 0.5).rem_euclid(1.0)
                    };
                    gait_foot(u, w.stride_m, d.height)
                }
                None => (0.0, 0.0),
            };
            let local = [leg.ankle_xy[0] + rel, leg.ankle_xy[1], 0.0];
            let w = rotate_z(local, base_yaw);
            ankle_target[i] = [base_xy[0] + w[0], base_xy[1] + w[1], d.ankle_h + lift];
            toe_yaw[i] = base_yaw + leg.toe_yaw;
        }

        // Pelvis height: the pose's height, lowered where a leg could not reach its foot.
        let fraction = if walk.is_some() {
            WALK_LEG_FRACTION
        } else {
            STAND_LEG_FRACTION
        };
        let reach = fraction * d.leg();
        let hip_off = SIDES.map(|s| mv(&pelvis, [0.0, s * d.hip_half_w, 0.0]));
        let mut root_z = self.hip_z_nominal - tr.pelvis_drop.at(t).abs();
        for i in 0..2 {
            let hx = root_xy[0] + hip_off[i][0] - ankle_target[i][0];
            let hy = root_xy[1] + hip_off[i][1] - ankle_target[i][1];
            let horiz2 = hx * hx + hy * hy;
            let vert = (reach * reach - horiz2).max(0.0).sqrt();
            root_z = root_z.min(ankle_target[i][2] + vert - hip_off[i][2]);
        }
        let root = [root_xy[0], root_xy[1], root_z];

        // Legs.
        let mut hip = [[0.0; 3]; 2];
        let mut knee = [[0.0; 3]; 2];
        let mut ankle = [[0.0; 3]; 2];
        let mut foot = [IDENTITY; 2];
        for i in 0..2 {
            hip[i] = add(root, hip_off[i]);
            let fwd = [toe_yaw[i].cos(), toe_yaw[i].sin(), 0.0];
            let pole = add(fwd, [0.0, 0.0, 0.1]);
            let (k, a) = two_bone(hip[i], ankle_target[i], d.thigh, d.shin, pole);
            knee[i] = k;
            ankle[i] = a;
            foot[i] = rot_z(toe_yaw[i]);
        }

        // Spine, neck and head.
        let lumbar = add(root, mv(&pelvis, [0.0, 0.0, d.lumbar_up]));
        let abdomen = mm(
            &pelvis,
            &rot_fsz(
                tr.lumbar_flex.at(t),
                tr.lumbar_lat.at(t),
                tr.lumbar_twist.at(t) - 0.5 * 0.07 * gait_cos,
            ),
        );
        let thoracic = add(lumbar, mv(&abdomen, [0.0, 0.0, d.thoracic_up]));
        let chest = mm(
            &abdomen,
            &rot_fsz(
                tr.thor_flex.at(t),
                tr.thor_lat.at(t),
                tr.thor_twist.at(t) - 0.5 * 0.07 * gait_cos,
            ),
        );
        let neck_base = add(thoracic, mv(&chest, d.neck_base));
        let neck = mm(
            &chest,
            &rot_fsz(tr.neck_flex.at(t), tr.neck_lat.at(t), tr.neck_yaw.at(t)),
        );
        let neck_top = add(neck_base, mv(&neck, d.neck_vec));
        let head = mm(
            &neck,
            &mm(&rot_z(tr.head_yaw.at(t)), &rot_y(tr.head_nod.at(t))),
        );
        let head_pos = add(neck_top, mv(&head, d.head_center));

        // Arms.
        let mut shoulder = [[0.0; 3]; 2];
        let mut elbow = [[0.0; 3]; 2];
        let mut wrist = [[0.0; 3]; 2];
        let mut hand_center = [[0.0; 3]; 2];
        let mut hand_axes = [IDENTITY; 2];
        for i in 0..2 {
            let side = SIDES[i];
            shoulder[i] = add(thoracic, mv(&chest, d.shoulder_at(side)));
            let ik = self.handover.filter(|h| (i == 1) == h.giver);
            if let Some(h) = ik {
                let (e, w, c, axes) = handover_arm(d, h, t, shoulder[i], &chest, side);
                elbow[i] = e;
                wrist[i] = w;
                hand_center[i] = c;
                hand_axes[i] = axes;
                continue;
            }
            let arm = &self.arms[i];
            // Left arm swings forward with the right leg.
            let swing = -side * arm.gait_swing * gait_cos;
            let flex = arm.flex.at(t) + swing;
            let elbow_flex =
                (arm.elbow.at(t) + swing.max(0.0) * 0.5).clamp(ELBOW_MIN_RAD, ELBOW_MAX_RAD);
            let upper = mm(
                &chest,
                &mm(
                    &mm(&rot_y(-flex), &rot_x(side * arm.abd.at(t))),
                    &rot_z(arm.twist.at(t)),
                ),
            );
            elbow[i] = add(shoulder[i], mv(&upper, [0.0, 0.0, -d.upper_arm]));
            let fore = mm(&upper, &rot_y(-elbow_flex));
            wrist[i] = add(elbow[i], mv(&fore, [0.0, 0.0, -d.forearm]));
            let hand = mm(&fore, &rot_y(-arm.wrist.at(t)));
            hand_center[i] = add(wrist[i], mv(&hand, [0.0, 0.0, -d.hand_half[2]]));
            hand_axes[i] = hand;
        }

        Skeleton {
            root,
            pelvis,
            lumbar,
            abdomen,
            thoracic,
            chest,
            neck_base,
            neck_top,
            head,
            head_pos,
            shoulder,
            elbow,
            wrist,
            hand_center,
            hand_axes,
            hip,
            knee,
            ankle,
            foot,
        }
    }

    fn emit(&self, sk: &Skeleton, out: &mut Vec<Primitive>) {
        let d = &self.dims;
        let c = &self.clothes;
        // Feet never below the floor (they are planted at z = 0 unless a leg could not
        // reach; then the whole body is lifted).
        let mut lowest = f32::INFINITY;
        let mut feet = [[0.0; 3]; 2];
        for i in 0..2 {
            feet[i] = add(sk.ankle[i], mv(&sk.foot[i], d.foot_center));
            let (lo, _) = box_shape(feet[i], sk.foot[i], d.foot_half).aabb();
            lowest = lowest.min(lo[2]);
        }
        let lift = [0.0, 0.0, (-lowest).max(0.0)];
        let p = |v: V3| add(v, lift);
        let id = self.id;
        let mut push = |segment: Segment, shape: Shape, material: Material| {
            out.push(Primitive {
                shape,
                owner: Owner::Person {
                    person: id,
                    segment,
                },
                material,
            });
        };
        let ell = |center: V3, axes: M3, radii: V3| Shape::Ellipsoid {
            center: p(center),
            axes,
            radii,
        };
        let cap = |a: V3, b: V3, radius: f32| Shape::Capsule {
            a: p(a),
            b: p(b),
            radius,
        };

        push(
            Segment::Head,
            ell(sk.head_pos, sk.head, d.head_radii),
            c.skin,
        );
        push(
            Segment::Hair,
            ell(
                add(sk.head_pos, mv(&sk.head, d.hair_offset)),
                sk.head,
                d.hair_radii,
            ),
            c.hair,
        );
        push(
            Segment::Neck,
            cap(sk.neck_base, sk.neck_top, d.neck_r),
            c.skin,
        );
        push(
            Segment::Chest,
            ell(
                add(sk.thoracic, mv(&sk.chest, d.chest_center)),
                sk.chest,
                d.chest_radii,
            ),
            c.shirt,
        );
        push(
            Segment::Chest,
            cap(sk.shoulder[0], sk.shoulder[1], d.shoulder_r),
            c.shirt,
        );
        push(
            Segment::Abdomen,
            ell(
                add(sk.lumbar, mv(&sk.abdomen, d.abdomen_center)),
                sk.abdomen,
                d.abdomen_radii,
            ),
            c.shirt,
        );
        push(
            Segment::Pelvis,
            ell(
                add(sk.root, mv(&sk.pelvis, d.pelvis_center)),
                sk.pelvis,
                d.pelvis_radii,
            ),
            c.trousers,
        );
        const ARM_SEGMENTS: [[Segment; 3]; 2] = [
            [
                Segment::UpperArmLeft,
                Segment::ForearmLeft,
                Segment::HandLeft,
            ],
            [
                Segment::UpperArmRight,
                Segment::ForearmRight,
                Segment::HandRight,
            ],
        ];
        const LEG_SEGMENTS: [[Segment; 3]; 2] = [
            [Segment::ThighLeft, Segment::ShinLeft, Segment::FootLeft],
            [Segment::ThighRight, Segment::ShinRight, Segment::FootRight],
        ];
        for i in 0..2 {
            let [upper, fore, hand] = ARM_SEGMENTS[i];
            push(
                upper,
                cap(sk.shoulder[i], sk.elbow[i], d.upper_arm_r),
                c.shirt,
            );
            push(fore, cap(sk.elbow[i], sk.wrist[i], d.forearm_r), c.sleeve);
            push(
                hand,
                ell(sk.hand_center[i], sk.hand_axes[i], d.hand_half),
                c.skin,
            );
        }
        for i in 0..2 {
            let [thigh, shin, foot] = LEG_SEGMENTS[i];
            push(thigh, cap(sk.hip[i], sk.knee[i], d.thigh_r), c.trousers);
            push(shin, cap(sk.knee[i], sk.ankle[i], d.shin_r), c.trousers);
            push(
                foot,
                box_shape(p(feet[i]), sk.foot[i], d.foot_half),
                c.shoes,
            );
        }
    }
}

fn box_shape(center: V3, axes: M3, half: V3) -> Shape {
    Shape::Box { center, axes, half }
}

/// Ankle offset along the walking direction (body frame, metres) and lift above the
/// standing ankle height at gait phase `u` of this leg (0 = heel strike). The stance (60 %
/// of the cycle) moves the foot back at walking speed, the swing brings it forward.
fn gait_foot(u: f32, stride_m: f32, height_m: f32) -> (f32, f32) {
    const STANCE: f32 = 0.6;
    // The stance foot moves back by speed * stance time = STANCE * stride.
    let half = 0.5 * STANCE * stride_m;
    if u < STANCE {
        (half - 2.0 * half * u / STANCE, 0.0)
    } else {
        let s = (u - STANCE) / (1.0 - STANCE);
        let x = -half + half * (1.0 - (PI * s).cos());
        (x, 0.045 * height_m * (PI * s).sin())
    }
}

/// The handing arm of a hand-over: elbow, wrist, palm centre and hand axes reaching the
/// shared meeting point.
fn handover_arm(
    d: &Dims,
    h: Handover,
    t: f64,
    shoulder: V3,
    chest: &M3,
    side: f32,
) -> (V3, V3, V3, M3) {
    let m = h.meet_at(t);
    let v = h.v();
    let (toward, center) = if h.giver {
        (h.u, sub(m, scale(h.u, 0.5 * h.hand_sep)))
    } else {
        (scale(h.u, -1.0), add(m, scale(h.u, 0.5 * h.hand_sep)))
    };
    // Fingers point across the body (towards +v for both hands), a little towards the
    // partner; palms up under the object.
    let along = normalize(add(v, scale(toward, 0.3)));
    let thick = normalize(sub(UP, scale(along, dot(UP, along))));
    let width = cross(thick, along);
    let wrist_target = sub(center, scale(along, d.hand_half[2]));
    let pole = mv(chest, [-0.4, side * 0.7, -1.0]);
    let (elbow, wrist) = two_bone(shoulder, wrist_target, d.upper_arm, d.forearm, pole);
    let center = add(wrist, scale(along, d.hand_half[2]));
    (elbow, wrist, center, [width, thick, along])
}
