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
// Clothing.

#[derive(Clone, Copy, Debug, PartialEq)]
struct Clothes {
    shirt: Material,
    /// The forearms: the shirt with long sleeves, skin with short ones.
    sleeve: Material,
    trousers: Material,
    skin: Material,
    hair: Material,
    shoes: Material,
    short_sleeves: bool,
}

fn srgb_to_linear(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear(srgb: [f32; 3]) -> [f32; 3] {
    srgb.map(srgb_to_linear)
}

fn hsv(h: f32, s: f32, v: f32) -> [f32; 3] {
    let h6 = h.rem_euclid(1.0) * 6.0;
    let c = v * s;
    let x = c * (1.0 - ((h6 % 2.0) - 1.0).abs());
    let (r, g, b) = match h6 as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// Distance of two sRGB colours (roughly perceptual).
fn srgb_dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    norm(sub(a, b))
}

fn jitter(rng: &mut ChaCha8Rng, c: [f32; 3], amount: f32) -> [f32; 3] {
    c.map(|x| (x + uni(rng, -amount, amount)).clamp(0.0, 1.0))
}

const SKIN_SRGB: [[f32; 3]; 7] = [
    [1.00, 0.88, 0.77],
    [0.95, 0.76, 0.65],
    [0.88, 0.67, 0.55],
    [0.78, 0.53, 0.40],
    [0.63, 0.40, 0.27],
    [0.47, 0.29, 0.20],
    [0.31, 0.20, 0.14],
];
const HAIR_SRGB: [[f32; 3]; 6] = [
    [0.08, 0.07, 0.06],
    [0.24, 0.16, 0.11],
    [0.42, 0.31, 0.22],
    [0.77, 0.63, 0.39],
    [0.59, 0.27, 0.16],
    [0.63, 0.63, 0.63],
];
const SHOES_SRGB: [[f32; 3]; 5] = [
    [0.10, 0.10, 0.10],
    [0.31, 0.20, 0.12],
    [0.86, 0.86, 0.84],
    [0.43, 0.43, 0.45],
    [0.12, 0.14, 0.27],
];
/// Minimum sRGB distance between shirt, trousers and skin colours, so a parser can tell
/// the torso, the legs and bare skin apart.
const MIN_CLOTHES_DIST: f32 = 0.3;

fn pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[T], fallback: T) -> T {
    if items.is_empty() {
        return fallback;
    }
    let i = ((rng.random::<f32>() * items.len() as f32) as usize).min(items.len() - 1);
    items.get(i).copied().unwrap_or(fallback)
}

fn skin_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    let t = uni(rng, 0.0, (SKIN_SRGB.len() - 1) as f32);
    let i = (t as usize).min(SKIN_SRGB.len() - 2);
    let f = t - i as f32;
    let a = SKIN_SRGB[i];
    let b = SKIN_SRGB[i + 1];
    jitter(rng, [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * f), 0.02)
}

fn shirt_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    if rng.random::<f32>() < 0.15 {
        let v = pick(rng, &[0.12, 0.45, 0.92], 0.45);
        return jitter(rng, [v, v, v], 0.04);
    }
    hsv(uni(rng, 0.0, 1.0), uni(rng, 0.3, 0.85), uni(rng, 0.3, 0.95))
}

fn trousers_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    match (rng.random::<f32>() * 5.0) as u32 {
        0 | 1 => hsv(
            uni(rng, 0.58, 0.64),
            uni(rng, 0.4, 0.75),
            uni(rng, 0.3, 0.65),
        ),
        2 => {
            let v = uni(rng, 0.08, 0.5);
            jitter(rng, [v, v, v], 0.02)
        }
        3 => hsv(
            uni(rng, 0.07, 0.14),
            uni(rng, 0.25, 0.5),
            uni(rng, 0.45, 0.8),
        ),
        _ => hsv(uni(rng, 0.0, 1.0), uni(rng, 0.3, 0.7), uni(rng, 0.2, 0.7)),
    }
}

fn make_clothes(rng: &mut ChaCha8Rng, short_sleeves_prob: f64) -> Clothes {
    let skin = skin_srgb(rng);
    let mut shirt = [0.15, 0.3, 0.75];
    for _ in 0..64 {
        let c = shirt_srgb(rng);
        if srgb_dist(c, skin) >= MIN_CLOTHES_DIST {
            shirt = c;
            break;
        }
    }
    let mut trousers = if srgb_dist(shirt, [0.2, 0.2, 0.22]) >= MIN_CLOTHES_DIST {
        [0.2, 0.2, 0.22]
    } else {
        [0.85, 0.8, 0.6]
    };
    for _ in 0..64 {
        let c = trousers_srgb(rng);
        if srgb_dist(c, skin) >= MIN_CLOTHES_DIST && srgb_dist(c, shirt) >= MIN_CLOTHES_DIST {
            trousers = c;
            break;
        }
    }
    let mut hair = pick(rng, &HAIR_SRGB, HAIR_SRGB[0]);
    hair = jitter(rng, hair, 0.03);
    if srgb_dist(hair, skin) < 0.15 {
        hair = HAIR_SRGB[1];
    }
    let shoes = pick(rng, &SHOES_SRGB, SHOES_SRGB[0]);
    let shoes = jitter(rng, shoes, 0.02);

    let shirt_texture = {
        let r = rng.random::<f32>();
        if r < 0.3 {
            let toward = if shirt.iter().sum::<f32>() > 1.5 {
                [0.0; 3]
            } else {
                [1.0; 3]
            };
            let f = uni(rng, 0.3, 0.5);
            let other = [0, 1, 2].map(|k| shirt[k] + (toward[k] - shirt[k]) * f);
            if srgb_dist(other, skin) >= 0.2 && srgb_dist(other, trousers) >= 0.2 {
                Texture::Stripes {
                    period_m: uni(rng, 0.03, 0.12),
                    other: linear(other),
                }
            } else {
                Texture::Plain
            }
        } else if r < 0.6 {
            Texture::Noise {
                cell_m: uni(rng, 0.02, 0.06),
                amplitude: uni(rng, 0.1, 0.25),
            }
        } else {
            Texture::Plain
        }
    };
    let shirt = Material {
        albedo: linear(shirt),
        texture: shirt_texture,
    };
    let skin = Material {
        albedo: linear(skin),
        texture: Texture::Noise {
            cell_m: 0.02,
            amplitude: 0.05,
        },
    };
    let short_sleeves = f64::from(rng.random::<f32>()) < short_sleeves_prob;
    Clothes {
        shirt,
        sleeve: if short_sleeves { skin } else { shirt },
        trousers: Material {
            albedo: linear(trousers),
            texture: Texture::Noise {
                cell_m: uni(rng, 0.01, 0.03),
                amplitude: uni(rng, 0.08, 0.2),
            },
        },
        skin,
        hair: Material {
            albedo: linear(hair),
            texture: Texture::Noise {
                cell_m: 0.006,
                amplitude: 0.2,
            },
        },
        shoes: Material::plain(linear(shoes)),
        short_sleeves,
    }
}

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

// ---------------------------------------------------------------------------------------
// Drawing people.

/// Which arms a one- or two-armed pose uses: (left, right).
fn arms_used(rng: &mut ChaCha8Rng, both_prob: f32) -> (bool, bool) {
    let r = rng.random::<f32>();
    if r < both_prob {
        (true, true)
    } else if r < both_prob + (1.0 - both_prob) * 0.65 {
        (false, true)
    } else {
        (true, false)
    }
}

/// Arm hanging at the side.
fn arm_hanging(rng: &mut ChaCha8Rng, side: f32, girth: f32) -> Arm {
    let inrot = uni_deg(rng, 5.0, 15.0);
    let abd = uni_deg(rng, 5.0, 10.0) + (girth - 1.0).max(0.0) * 0.5;
    Arm {
        flex: sway_r(rng, 0.0, 8.0, 2.0, 8.0),
        abd: sway_deg(rng, abd, 1.0, 3.0),
        twist: sway_deg(rng, -side * inrot, 2.0, 8.0),
        elbow: sway_r(rng, 8.0, 20.0, 3.0, 10.0),
        wrist: sway_r(rng, 0.0, 10.0, 2.0, 8.0),
        gait_swing: 0.0,
    }
}

/// The twist and elbow flexion that point the forearm of an upper arm at (`flex`, `abd`)
/// to `target` (chest frame, origin at the thoracic joint).
fn aim_forearm(d: &Dims, side: f32, flex: f32, abd: f32, target: V3) -> (f32, f32) {
    let upper = mm(&rot_y(-flex), &rot_x(side * abd));
    let elbow = add(d.shoulder_at(side), mv(&upper, [0.0, 0.0, -d.upper_arm]));
    let f = mtv(&upper, normalize(sub(target, elbow)));
    let e = (-f[2]).clamp(-1.0, 1.0).acos();
    let twist = if f[0].abs() + f[1].abs() > 1e-5 {
        f[1].atan2(f[0])
    } else {
        0.0
    };
    (twist, e.clamp(ELBOW_MIN_RAD, ELBOW_MAX_RAD))
}

/// An arm aimed at a target with small sway (crossed arms, hands on hips).
fn arm_aimed(rng: &mut ChaCha8Rng, d: &Dims, side: f32, flex: f32, abd: f32, target: V3) -> Arm {
    let (twist, elbow) = aim_forearm(d, side, flex, abd, target);
    Arm {
        flex: sway_deg(rng, flex, 1.0, 3.0),
        abd: sway_deg(rng, abd, 0.5, 2.0),
        twist: sway_deg(rng, twist, 0.5, 2.0),
        elbow: sway_deg(rng, elbow, 1.0, 3.0),
        wrist: sway_deg(rng, 0.0, 1.0, 3.0),
        gait_swing: 0.0,
    }
}

/// A calm trunk: every channel with a small sway around zero.
fn trunk_calm(rng: &mut ChaCha8Rng) -> Trunk {
    Trunk {
        pelvis_x: sway(rng, 0.0, 0.005, 0.02),
        pelvis_y: sway(rng, 0.0, 0.005, 0.02),
        pelvis_drop: sway(rng, 0.0, 0.0, 0.004),
        pelvis_yaw: sway_deg(rng, 0.0, 1.0, 3.0),
        pelvis_pitch: sway_deg(rng, 0.0, 0.5, 1.5),
        pelvis_roll: sway_deg(rng, 0.0, 0.5, 1.5),
        lumbar_flex: sway_deg(rng, 0.0, 1.0, 3.0),
        lumbar_lat: sway_deg(rng, 0.0, 0.5, 2.0),
        lumbar_twist: sway_deg(rng, 0.0, 1.0, 4.0),
        thor_flex: Chan {
            base: 0.0,
            amp: uni_deg(rng, 0.5, 1.5),
            omega: TAU / uni(rng, 3.0, 5.0),
            phase: uni(rng, 0.0, TAU),
        },
        thor_lat: sway_deg(rng, 0.0, 0.5, 1.5),
        thor_twist: sway_deg(rng, 0.0, 1.0, 3.0),
        neck_flex: sway_deg(rng, 0.0, 1.0, 4.0),
        neck_lat: sway_deg(rng, 0.0, 1.0, 3.0),
        neck_yaw: sway_deg(rng, 0.0, 2.0, 6.0),
        head_nod: sway_deg(rng, 0.0, 2.0, 5.0),
        head_yaw: sway_deg(rng, 0.0, 3.0, 15.0),
    }
}

fn legs_standing(rng: &mut ChaCha8Rng, h: f32) -> [Leg; 2] {
    let w = uni(rng, 0.05, 0.07) * h;
    let x = uni(rng, -0.01, 0.01) * h;
    SIDES.map(|s| Leg {
        ankle_xy: [x, s * w],
        toe_yaw: s * uni_deg(rng, 5.0, 15.0),
    })
}

/// Adds `sigma` (radians) Gaussian noise to the base of every joint-angle channel.
fn perturb(rng: &mut ChaCha8Rng, person: &mut Person, sigma: f32) {
    if sigma <= 0.0 {
        return;
    }
    let tr = &mut person.trunk;
    tr.pelvis_yaw.base += sigma * gauss(rng);
    // The spine (pelvis, lumbar, thoracic) and the neck-head chain are each one anatomical
    // joint split in parts: the noise is shared so that the chain bends by about `sigma`.
    let spine = sigma / 3f32.sqrt();
    for c in [
        &mut tr.pelvis_pitch,
        &mut tr.pelvis_roll,
        &mut tr.lumbar_flex,
        &mut tr.lumbar_lat,
        &mut tr.lumbar_twist,
        &mut tr.thor_flex,
        &mut tr.thor_lat,
        &mut tr.thor_twist,
    ] {
        c.base += spine * gauss(rng);
    }
    let neck = sigma / 2f32.sqrt();
    for c in [
        &mut tr.neck_flex,
        &mut tr.neck_lat,
        &mut tr.neck_yaw,
        &mut tr.head_nod,
        &mut tr.head_yaw,
    ] {
        c.base += neck * gauss(rng);
    }
    for arm in &mut person.arms {
        for c in [
            &mut arm.flex,
            &mut arm.abd,
            &mut arm.twist,
            &mut arm.elbow,
            &mut arm.wrist,
        ] {
            c.base += sigma * gauss(rng);
        }
        arm.elbow.base = arm.elbow.base.clamp(ELBOW_MIN_RAD, ELBOW_MAX_RAD);
    }
    // Hip flexion / abduction / rotation move the planted foot; the knee follows by IK.
    let leg_len = person.dims.leg();
    for (i, leg) in person.legs.iter_mut().enumerate() {
        leg.ankle_xy[0] += leg_len * (sigma * gauss(rng)).sin() * 0.5;
        leg.ankle_xy[1] += leg_len * (sigma * gauss(rng)).sin() * 0.5;
        leg.toe_yaw += sigma * gauss(rng);
        // Feet never cross the midline.
        let min_w = 0.025 * person.dims.height;
        leg.ankle_xy[1] = if i == 0 {
            leg.ankle_xy[1].max(min_w)
        } else {
            leg.ankle_xy[1].min(-min_w)
        };
    }
}

/// Draws shape, clothing and pose of person `index` (motion is set at placement).
fn draw_person(config: &PeopleConfig, seed: u64, index: usize, pose: BodyPose) -> Person {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index as u64 + 1);
    let [h_lo, h_hi] = config.height_m.map(|x| x as f32);
    let [g_lo, g_hi] = config.girth.map(|x| x as f32);
    let height = uni(&mut rng, h_lo.min(h_hi), h_hi.max(h_lo)).clamp(0.5, 2.5);
    let girth = uni(&mut rng, g_lo.min(g_hi), g_hi.max(g_lo)).clamp(0.3, 3.0);
    let dims = Dims::new(height, girth, uni(&mut rng, 0.95, 1.12));
    let clothes = make_clothes(&mut rng, config.short_sleeves);
    let d = &dims;
    let h = height;

    let mut trunk = trunk_calm(&mut rng);
    let mut arms = SIDES.map(|s| arm_hanging(&mut rng, s, girth));
    let mut legs = legs_standing(&mut rng, h);
    let mut hip_z_nominal = d.ankle_h + STAND_LEG_FRACTION * d.leg();

    match pose {
        BodyPose::Standing => {}
        BodyPose::Walking => {
            hip_z_nominal = d.ankle_h + WALK_LEG_FRACTION * d.leg();
            trunk.pelvis_x = Chan::default();
            trunk.pelvis_y = Chan::default();
            trunk.head_yaw.amp *= 0.5;
            for leg in &mut legs {
                leg.ankle_xy[0] = 0.0;
                leg.ankle_xy[1] = leg.ankle_xy[1].signum() * 0.055 * h;
                leg.toe_yaw *= 0.5;
            }
            for (i, arm) in arms.iter_mut().enumerate() {
                arm.flex = sway_r(&mut rng, 0.0, 5.0, 0.5, 2.0);
                arm.abd.base = uni_deg(&mut rng, 6.0, 10.0) + (girth - 1.0).max(0.0) * 0.5;
                arm.elbow = sway_r(&mut rng, 15.0, 30.0, 1.0, 4.0);
                // Arms swing more the faster the walk (about 15 degrees at 1 m/s).
                let speed = (config.walk_speed_m_s as f32).clamp(0.3, 1.2);
                arm.gait_swing = uni_deg(&mut rng, 10.0, 20.0) * speed;
                arm.twist.base = -SIDES[i] * uni_deg(&mut rng, 5.0, 15.0);
            }
        }
        BodyPose::Reaching => {
            let (left, right) = arms_used(&mut rng, 0.4);
            trunk.lumbar_flex.base = uni_deg(&mut rng, 0.0, 8.0);
            for (i, used) in [left, right].into_iter().enumerate() {
                if used {
                    arms[i] = Arm {
                        flex: sway_r(&mut rng, 70.0, 88.0, 4.0, 15.0),
                        abd: sway_r(&mut rng, 0.0, 15.0, 2.0, 6.0),
                        twist: sway_r(&mut rng, -SIDES[i] * 0.0, -SIDES[i] * 10.0, 2.0, 6.0),
                        elbow: sway_r(&mut rng, 3.0, 18.0, 3.0, 10.0),
                        wrist: sway_r(&mut rng, -10.0, 10.0, 2.0, 8.0),
                        gait_swing: 0.0,
                    };
                }
            }
            let fwd = uni(&mut rng, 0.03, 0.08) * h;
            let which = usize::from(rng.random::<bool>());
            legs[which].ankle_xy[0] += fwd;
            legs[1 - which].ankle_xy[0] -= 0.5 * fwd;
        }
        BodyPose::HandingOver => {
            // Without a partner: offering forward with the right hand, elbow bent.
            arms[1] = Arm {
                flex: sway_r(&mut rng, 45.0, 60.0, 3.0, 10.0),
                abd: sway_r(&mut rng, 5.0, 15.0, 1.0, 4.0),
                twist: sway_deg(&mut rng, 0.0, 2.0, 6.0),
                elbow: sway_r(&mut rng, 40.0, 60.0, 3.0, 10.0),
                wrist: sway_deg(&mut rng, 0.0, 2.0, 6.0),
                gait_swing: 0.0,
            };
            trunk.pelvis_x.amp *= 0.5;
            trunk.pelvis_y.amp *= 0.5;
            let fwd = uni(&mut rng, 0.02, 0.06) * h;
            legs[1].ankle_xy[0] += fwd;
            legs[0].ankle_xy[0] -= 0.5 * fwd;
        }
        BodyPose::ArmsCrossed => {
            for (i, side) in SIDES.into_iter().enumerate() {
                let flex = uni_deg(&mut rng, 20.0, 30.0) + (girth - 1.0).max(0.0) * 0.6;
                let abd = uni_deg(&mut rng, 10.0, 20.0);
                // Hand on the other upper arm; the left forearm a little higher and closer.
                let (dx, dz) = if i == 0 { (0.03, 0.07) } else { (0.055, 0.045) };
                let target = [d.chest_radii[0] + dx * h, -side * 0.11 * h, dz * h];
                arms[i] = arm_aimed(&mut rng, d, side, flex, abd, target);
            }
        }
        BodyPose::HandsOnHips => {
            for (i, side) in SIDES.into_iter().enumerate() {
                let flex = -uni_deg(&mut rng, 10.0, 20.0);
                let abd = uni_deg(&mut rng, 40.0, 55.0);
                // Hand at the side of the pelvis, in the chest frame of an upright trunk.
                let target = [
                    0.0,
                    side * (d.pelvis_radii[1] + 0.012 * h),
                    0.03 * h - d.lumbar_up - d.thoracic_up,
                ];
                arms[i] = arm_aimed(&mut rng, d, side, flex, abd, target);
            }
        }
        BodyPose::Pointing => {
            let i = if rng.random::<f32>() < 0.7 { 1 } else { 0 };
            let side = SIDES[i];
            let abd = uni_deg(&mut rng, 15.0, 50.0);
            arms[i] = Arm {
                flex: sway_r(&mut rng, 70.0, 95.0, 3.0, 12.0),
                abd: sway_deg(&mut rng, abd, 2.0, 8.0),
                twist: sway_deg(&mut rng, 0.0, 2.0, 5.0),
                elbow: sway_r(&mut rng, 2.0, 10.0, 1.0, 4.0),
                wrist: sway_deg(&mut rng, 0.0, 2.0, 5.0),
                gait_swing: 0.0,
            };
            trunk.head_yaw.base = side * 0.6 * abd;
            trunk.head_yaw.amp *= 0.4;
        }
        BodyPose::Crouching => {
            let w = uni(&mut rng, 0.07, 0.1) * h;
            let x = uni(&mut rng, 0.03, 0.06) * h;
            for (leg, side) in legs.iter_mut().zip(SIDES) {
                leg.ankle_xy = [x, side * w];
                leg.toe_yaw = side * uni_deg(&mut rng, 15.0, 25.0);
            }
            hip_z_nominal = uni(&mut rng, 0.28, 0.36) * h;
            trunk.pelvis_x = sway(&mut rng, 0.0, 0.003, 0.01);
            trunk.pelvis_y = sway(&mut rng, 0.0, 0.003, 0.01);
            trunk.pelvis_drop = sway(&mut rng, 0.0, 0.005, 0.02);
            let pitch = uni_deg(&mut rng, 10.0, 25.0);
            let lumbar = uni_deg(&mut rng, 10.0, 25.0);
            let thor = uni_deg(&mut rng, 5.0, 10.0);
            trunk.pelvis_pitch.base = pitch;
            trunk.lumbar_flex.base = lumbar;
            trunk.thor_flex.base = thor;
            trunk.neck_flex.base = -0.5 * (pitch + lumbar + thor);
            trunk.head_nod.base = -0.3 * (pitch + lumbar + thor);
            for (i, arm) in arms.iter_mut().enumerate() {
                *arm = Arm {
                    flex: sway_r(&mut rng, 30.0, 50.0, 3.0, 10.0),
                    abd: sway_r(&mut rng, 8.0, 15.0, 1.0, 4.0),
                    twist: sway_r(&mut rng, -SIDES[i] * 10.0, -SIDES[i] * 20.0, 2.0, 5.0),
                    elbow: sway_r(&mut rng, 40.0, 70.0, 3.0, 10.0),
                    wrist: sway_deg(&mut rng, 0.0, 2.0, 6.0),
                    gait_swing: 0.0,
                };
            }
        }
    }

    let mut person = Person {
        id: u8::try_from(index + 1).unwrap_or(u8::MAX),
        pose,
        girth,
        dims,
        clothes,
        motion: Motion::Still {
            xy: [0.0, 0.0],
            yaw: 0.0,
        },
        trunk,
        arms,
        legs,
        hip_z_nominal,
        handover: None,
    };
    let sigma = (config.joint_noise_deg as f32).max(0.0).to_radians();
    perturb(&mut rng, &mut person, sigma);
    person
}

// ---------------------------------------------------------------------------------------
// Placement.

/// Candidate placements tried per person before the least bad one is taken.
const PLACEMENT_TRIES: usize = 1000;
/// Times (seconds) at which walking paths are checked against the constraints.
const CHECK_STEP_S: f64 = 0.25;
const CHECK_STEPS: usize = 240;

struct Constraints<'a> {
    area: f32,
    spacing: f32,
    obstacles: &'a [FloorObstacle],
    times: Vec<f64>,
}

impl Constraints<'_> {
    /// How far a pelvis position breaks the area and obstacle constraints, metres.
    fn site_violation(&self, xy: [f32; 2]) -> f32 {
        let mut v = (xy[0].abs() - self.area).max(0.0) + (xy[1].abs() - self.area).max(0.0);
        for o in self.obstacles {
            let dist = ((xy[0] - o.center_m[0]).powi(2) + (xy[1] - o.center_m[1]).powi(2)).sqrt();
            v += (o.radius_m + PERSON_RADIUS_M - dist).max(0.0);
        }
        v
    }

    /// How far a walking loop leaves the area or enters an obstacle (exact, over the whole
    /// loop), metres.
    fn path_violation(&self, path: &Stadium) -> f32 {
        let e = rotate_z([path.half_len, 0.0, 0.0], path.angle);
        let ends = [
            [path.center[0] + e[0], path.center[1] + e[1]],
            [path.center[0] - e[0], path.center[1] - e[1]],
        ];
        let mut v = 0.0;
        for end in ends {
            for k in 0..2 {
                v += (end[k].abs() + path.radius - self.area).max(0.0);
            }
        }
        for o in self.obstacles {
            // Distance of the obstacle centre to the loop (the rim of the stadium).
            let ab = sub([ends[1][0], ends[1][1], 0.0], [ends[0][0], ends[0][1], 0.0]);
            let ap = [o.center_m[0] - ends[0][0], o.center_m[1] - ends[0][1], 0.0];
            let len2 = dot(ab, ab);
            let f = if len2 > 0.0 {
                (dot(ap, ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let to_axis = norm(sub(ap, scale(ab, f)));
            let dist = (to_axis - path.radius).abs();
            v += (o.radius_m + PERSON_RADIUS_M - dist).max(0.0);
        }
        v
    }

    /// Total violation of `motions` (moving together) against the placed ones.
    fn violation(&self, motions: &[Motion], placed: &[Motion]) -> f32 {
        let mut v = 0.0;
        for m in motions {
            if let Motion::Walk(w) = m {
                v += self.path_violation(&w.path) * self.times.len() as f32;
            }
        }
        for &t in &self.times {
            for m in motions {
                let (xy, _) = m.at(t);
                v += self.site_violation(xy);
                for q in placed {
                    let (qxy, _) = q.at(t);
                    let dist = ((xy[0] - qxy[0]).powi(2) + (xy[1] - qxy[1]).powi(2)).sqrt();
                    v += (self.spacing - dist).max(0.0);
                }
            }
        }
        v
    }
}

fn facing_center(rng: &mut ChaCha8Rng, xy: [f32; 2]) -> f32 {
    if xy[0].hypot(xy[1]) < 0.1 {
        uni(rng, -PI, PI)
    } else {
        (-xy[1]).atan2(-xy[0]) + 0.45 * gauss(rng)
    }
}

fn candidate(rng: &mut ChaCha8Rng, person: &Person, area: f32, walk_speed: f32) -> Motion {
    let xy = [uni(rng, -area, area), uni(rng, -area, area)];
    if person.pose != BodyPose::Walking {
        let yaw = facing_center(rng, xy);
        return Motion::Still { xy, yaw };
    }
    let h = person.dims.height;
    let radius = uni(rng, 0.3, 0.5).min(area.max(0.05));
    let half_len = uni(rng, 0.0, (area - radius).max(0.0));
    let path = Stadium {
        center: xy,
        angle: uni(rng, -PI, PI),
        half_len,
        radius,
    };
    let speed = walk_speed.max(0.0);
    // Slow walking: shorter strides; at (almost) zero speed the person steps in place.
    let stride = (h * (0.3 + 0.25 * speed)).min(speed * 1.6);
    let gait_period_s = if speed > 0.05 { stride / speed } else { 1.2 };
    Motion::Walk(Walk {
        path,
        speed_m_s: speed,
        s0_m: uni(rng, 0.0, path.perimeter()),
        gait_period_s: gait_period_s.clamp(0.6, 2.0),
        stride_m: if speed > 0.05 {
            speed * gait_period_s.clamp(0.6, 2.0)
        } else {
            0.0
        },
        gait_phase0: rng.random::<f32>(),
    })
}

/// The people of a sequence, drawn from `config` with `seed` (same seed, same people),
/// standing in the workspace around the world origin and outside `obstacles`.
///
/// Placement keeps pelvis centres inside `|x|, |y| <= area_half_m`, `min_spacing_m` apart
/// and [`PERSON_RADIUS_M`] outside every obstacle; when no tried placement meets all of
/// this, the one that breaks it least is used (the constraints are relaxed, never looped
/// on). With `config.handover` persons 1 and 2 face each other `handover_distance_m` apart.
pub fn make_people(config: &PeopleConfig, seed: u64, obstacles: &[FloorObstacle]) -> Vec<Person> {
    let count = config.count.min(u32::from(u8::MAX - 1)) as usize;
    let handover = config.handover && count >= 2;
    let poses: Vec<BodyPose> = config
        .poses
        .iter()
        .filter_map(|n| BodyPose::from_name(n))
        .collect();

    let mut pose_rng = ChaCha8Rng::seed_from_u64(seed);
    pose_rng.set_stream(0xA11_0C47);
    let mut people: Vec<Person> = (0..count)
        .map(|i| {
            let drawn = pick(&mut pose_rng, &poses, BodyPose::Standing);
            let pose = if handover && i < 2 {
                BodyPose::HandingOver
            } else {
                drawn
            };
            draw_person(config, seed, i, pose)
        })
        .collect();

    let area = (config.area_half_m as f32).max(0.0);
    let walk_speed = config.walk_speed_m_s as f32;
    let any_walker = people.iter().any(|p| p.pose == BodyPose::Walking);
    let constraints = Constraints {
        area,
        spacing: (config.min_spacing_m as f32).max(0.0),
        obstacles,
        times: if any_walker {
            (0..CHECK_STEPS).map(|k| k as f64 * CHECK_STEP_S).collect()
        } else {
            vec![0.0]
        },
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(0x9_1ACE);
    let mut placed: Vec<Motion> = Vec::with_capacity(count);

    let mut first = 0;
    if handover {
        let dist = (config.handover_distance_m as f32).max(0.1);
        let mut best: Option<(f32, [Motion; 2])> = None;
        for _ in 0..PLACEMENT_TRIES {
            let inner = (area - 0.5 * dist).max(0.0);
            let c = [uni(&mut rng, -inner, inner), uni(&mut rng, -inner, inner)];
            let a = uni(&mut rng, -PI, PI);
            let u = [a.cos(), a.sin()];
            let pair = [
                Motion::Still {
                    xy: [c[0] - 0.5 * dist * u[0], c[1] - 0.5 * dist * u[1]],
                    yaw: a,
                },
                Motion::Still {
                    xy: [c[0] + 0.5 * dist * u[0], c[1] + 0.5 * dist * u[1]],
                    yaw: a + PI,
                },
            ];
            let v = constraints.violation(&pair, &placed);
            if best.as_ref().is_none_or(|(bv, _)| v < *bv) {
                best = Some((v, pair));
            }
            if v <= 0.0 {
                break;
            }
        }
        if let Some((_, pair)) = best {
            for (p, m) in people.iter_mut().zip(pair) {
                p.motion = m;
            }
            placed.extend(pair);
        }
        setup_handover(&mut people, &mut rng);
        first = 2;
    }
    for p in people.iter_mut().skip(first) {
        let mut best: Option<(f32, Motion)> = None;
        for _ in 0..PLACEMENT_TRIES {
            let m = candidate(&mut rng, p, area, walk_speed);
            let v = constraints.violation(&[m], &placed);
            if best.as_ref().is_none_or(|(bv, _)| v < *bv) {
                best = Some((v, m));
            }
            if v <= 0.0 {
                break;
            }
        }
        if let Some((_, m)) = best {
            p.motion = m;
            placed.push(m);
        }
    }
    people
}

/// Meeting point, trunk lean and shared sway of the hand-over between persons 1 and 2
/// (already placed facing each other).
fn setup_handover(people: &mut [Person], rng: &mut ChaCha8Rng) {
    let [a, b, ..] = people else {
        return;
    };
    let (Motion::Still { xy: xa, yaw }, Motion::Still { xy: xb, .. }) = (a.motion, b.motion) else {
        return;
    };
    let u = [yaw.cos(), yaw.sin(), 0.0];
    let v = [-u[1], u[0], 0.0];
    let shoulder_z = |p: &Person| {
        let d = &p.dims;
        p.hip_z_nominal + d.lumbar_up + d.thoracic_up + d.shoulder[2]
    };
    let z = (0.5 * (shoulder_z(&*a) + shoulder_z(&*b)) - 0.3).clamp(1.0, 1.2);
    let mid = [0.5 * (xa[0] + xb[0]), 0.5 * (xa[1] + xb[1]), z];
    let meet = sub(mid, scale(v, 0.06));
    let hand_sep = 0.9 * (a.dims.hand_half[0] + b.dims.hand_half[0]);
    let hand_top = a.dims.hand_half[1].max(b.dims.hand_half[1]);
    let sway = [
        sway(rng, 0.0, 0.01, 0.025),
        sway(rng, 0.0, 0.01, 0.025),
        sway(rng, 0.0, 0.01, 0.02),
    ];
    let object_color = object_color(&[&a.clothes, &b.clothes]);
    let dist = ((xb[0] - xa[0]).powi(2) + (xb[1] - xa[1]).powi(2)).sqrt();
    for (p, giver) in [(a, true), (b, false)] {
        // Lean forward until the shoulder is well within reach of the hand.
        let d = p.dims;
        let arm = 0.92 * (d.upper_arm + d.forearm);
        let fwd = 0.5 * dist - 0.5 * hand_sep;
        let trunk_len = d.lumbar_up + d.thoracic_up + d.shoulder[2];
        let mut lean = 0.0f32;
        for step in 0..=45 {
            lean = (step as f32).to_radians();
            let sx = fwd - trunk_len * lean.sin();
            let sz = p.hip_z_nominal + trunk_len * lean.cos() - z;
            if sx.hypot(sz) <= arm {
                break;
            }
        }
        p.trunk.pelvis_pitch.base = 0.4 * lean + 0.03;
        p.trunk.lumbar_flex.base = 0.6 * lean + 0.03;
        // Facing the partner: no yaw offset, little yaw sway.
        p.trunk.pelvis_yaw.base = 0.0;
        p.trunk.pelvis_yaw.amp = p.trunk.pelvis_yaw.amp.min(0.03);
        p.trunk.pelvis_x.amp = p.trunk.pelvis_x.amp.min(0.008);
        p.trunk.pelvis_y.amp = p.trunk.pelvis_y.amp.min(0.008);
        p.handover = Some(Handover {
            giver,
            meet,
            u,
            sway,
            hand_sep,
            hand_top,
            object_color,
        });
    }
}

/// A plain colour for the hand-over object that differs most from both people's clothes
/// and skin (linear RGB).
fn object_color(clothes: &[&Clothes]) -> [f32; 3] {
    const CANDIDATES: [[f32; 3]; 5] = [
        [0.85, 0.35, 0.02],
        [0.02, 0.55, 0.65],
        [0.85, 0.75, 0.02],
        [0.65, 0.03, 0.5],
        [0.08, 0.55, 0.08],
    ];
    let mut best = CANDIDATES[0];
    let mut best_d = f32::NEG_INFINITY;
    for c in CANDIDATES {
        let mut dmin = f32::INFINITY;
        for cl in clothes {
            for m in [cl.shirt, cl.trousers, cl.skin, cl.sleeve] {
                dmin = dmin.min(norm(sub(c, m.albedo)));
            }
        }
        if dmin > best_d {
            best_d = dmin;
            best = c;
        }
    }
    best
}

/// The object passed between the first two people in a hand-over at `t_s` (class
/// background: `Owner::Scene`), `None` when the sequence has no hand-over.
///
/// A box of [`HANDOVER_OBJECT_SIZE_M`] resting on both palms at the meeting point, its long
/// side across the line between the two people.
pub fn handover_object(people: &[Person], config: &PeopleConfig, t_s: f64) -> Option<Primitive> {
    if !config.handover {
        return None;
    }
    let h = people.iter().find_map(|p| p.handover.filter(|h| h.giver))?;
    let m = h.meet_at(t_s);
    let [across, along, up] = HANDOVER_OBJECT_SIZE_M;
    let center = add(m, [0.0, 0.0, h.hand_top + 0.5 * up + 0.002]);
    Some(Primitive {
        shape: Shape::Box {
            center,
            axes: [h.u, h.v(), UP],
            half: [0.5 * along, 0.5 * across, 0.5 * up],
        },
        owner: Owner::Scene,
        material: Material::plain(h.object_color),
    })
}

#[cfg(test)]
mod tests;
