//! The shapes a synthetic scene is made of, and ray intersection with them.
//!
//! Everything is in the world frame (metres, z up, floor at z = 0) and in `f32`: a scene is
//! at most ~10 m across, where `f32` resolves ~1 µm, far below the depth noise we add.

use bodyseg_core::Class;

/// A point or direction, metres.
pub type V3 = [f32; 3];

use bodyseg_core::math::frame_around_unit_axis;
pub use bodyseg_core::math::{add, cross, dot, lerp, norm, normalize, scale, sub};

/// The body segments of a synthetic person (at least the 15 the synth issue asks for),
/// each mapped to one of the 7 classes by [`Segment::class`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Segment {
    /// Head (skull and face).
    Head = 1,
    /// Hair on top and at the back of the head (class head).
    Hair,
    /// Neck (class head, as in Pascal-Person-Part).
    Neck,
    /// Chest.
    Chest,
    /// Abdomen.
    Abdomen,
    /// Pelvis / hips (class torso).
    Pelvis,
    /// Left upper arm.
    UpperArmLeft,
    /// Right upper arm.
    UpperArmRight,
    /// Left forearm.
    ForearmLeft,
    /// Right forearm.
    ForearmRight,
    /// Left hand (class lower arms).
    HandLeft,
    /// Right hand (class lower arms).
    HandRight,
    /// Left thigh.
    ThighLeft,
    /// Right thigh.
    ThighRight,
    /// Left shin.
    ShinLeft,
    /// Right shin.
    ShinRight,
    /// Left foot (class lower legs).
    FootLeft,
    /// Right foot (class lower legs).
    FootRight,
}

impl Segment {
    /// Every segment, in id order.
    pub const ALL: [Segment; 18] = [
        Segment::Head,
        Segment::Hair,
        Segment::Neck,
        Segment::Chest,
        Segment::Abdomen,
        Segment::Pelvis,
        Segment::UpperArmLeft,
        Segment::UpperArmRight,
        Segment::ForearmLeft,
        Segment::ForearmRight,
        Segment::HandLeft,
        Segment::HandRight,
        Segment::ThighLeft,
        Segment::ThighRight,
        Segment::ShinLeft,
        Segment::ShinRight,
        Segment::FootLeft,
        Segment::FootRight,
    ];

    /// The segment's id (1..=18; 0 means "no segment" in part images).
    pub fn id(self) -> u8 {
        self as u8
    }

    /// The segment with this id.
    pub fn from_id(id: u8) -> Option<Segment> {
        Segment::ALL.get(usize::from(id).wrapping_sub(1)).copied()
    }

    /// The body-part class of the segment (neck → head, hands → lower arms, feet → lower
    /// legs, pelvis → torso).
    pub fn class(self) -> Class {
        use Segment::*;
        match self {
            Head | Hair | Neck => Class::Head,
            Chest | Abdomen | Pelvis => Class::Torso,
            UpperArmLeft | UpperArmRight => Class::UpperArms,
            ForearmLeft | ForearmRight | HandLeft | HandRight => Class::LowerArms,
            ThighLeft | ThighRight => Class::UpperLegs,
            ShinLeft | ShinRight | FootLeft | FootRight => Class::LowerLegs,
        }
    }

    /// Which limb the segment belongs to (the unit an upper/lower swap or a missed part
    /// acts on), `None` for head and trunk.
    pub fn limb(self) -> Option<Limb> {
        use Segment::*;
        match self {
            UpperArmLeft | ForearmLeft | HandLeft => Some(Limb::ArmLeft),
            UpperArmRight | ForearmRight | HandRight => Some(Limb::ArmRight),
            ThighLeft | ShinLeft | FootLeft => Some(Limb::LegLeft),
            ThighRight | ShinRight | FootRight => Some(Limb::LegRight),
            _ => None,
        }
    }
}

/// One of the four limbs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Limb {
    /// Left arm (upper arm, forearm, hand).
    ArmLeft,
    /// Right arm.
    ArmRight,
    /// Left leg (thigh, shin, foot).
    LegLeft,
    /// Right leg.
    LegRight,
}

/// A surface pattern; colours are linear RGB in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Texture {
    /// One colour.
    Plain,
    /// Stripes of `period_m` along world z, alternating with `other`.
    Stripes {
        /// Stripe period, metres.
        period_m: f32,
        /// The second colour.
        other: [f32; 3],
    },
    /// A 3D checkerboard of `cell_m` cubes, alternating with `other`.
    Checker {
        /// Cell size, metres.
        cell_m: f32,
        /// The second colour.
        other: [f32; 3],
    },
    /// Smooth value noise of `cell_m` feature size and `amplitude` (fraction of the
    /// base colour), like fabric, wood or concrete.
    Noise {
        /// Feature size, metres.
        cell_m: f32,
        /// Relative amplitude in `[0, 1]`.
        amplitude: f32,
    },
}

/// How a surface looks in the colour image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base (albedo) colour, linear RGB in `[0, 1]`.
    pub albedo: [f32; 3],
    /// Pattern on top of the albedo.
    pub texture: Texture,
}

impl Material {
    /// A plain material.
    pub const fn plain(albedo: [f32; 3]) -> Self {
        Material {
            albedo,
            texture: Texture::Plain,
        }
    }
}

/// A solid the ray caster can hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// All points within `radius` of the segment `a`–`b` (a limb, a robot link).
    Capsule {
        /// One end of the axis, world.
        a: V3,
        /// The other end.
        b: V3,
        /// Radius, metres.
        radius: f32,
    },
    /// A flat-capped cylinder (robot links, table legs).
    Cylinder {
        /// Centre of one cap.
        a: V3,
        /// Centre of the other cap.
        b: V3,
        /// Radius, metres.
        radius: f32,
    },
    /// An ellipsoid: `center + axes[i] * radii[i]` are its semi-axes; `axes` orthonormal.
    Ellipsoid {
        /// Centre, world.
        center: V3,
        /// Unit semi-axis directions (orthonormal).
        axes: [V3; 3],
        /// Semi-axis lengths, metres.
        radii: V3,
    },
    /// An oriented box: `center ± axes[i] * half[i]`; `axes` orthonormal.
    Box {
        /// Centre, world.
        center: V3,
        /// Unit edge directions (orthonormal).
        axes: [V3; 3],
        /// Half edge lengths, metres.
        half: V3,
    },
}

/// What a surface is, for the ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    /// Part of the static scene or a held object: class background, person 0.
    Scene,
    /// Part of person `person` (1-based, as written in `depth_person`), segment `segment`.
    Person {
        /// Person id, 1-based.
        person: u8,
        /// The body segment.
        segment: Segment,
    },
}

impl Owner {
    /// The class id written in label images (0 for the scene).
    pub fn class_id(self) -> u8 {
        match self {
            Owner::Scene => Class::Background.id(),
            Owner::Person { segment, .. } => segment.class().id(),
        }
    }

    /// The person id written in `depth_person` (0 for the scene).
    pub fn person_id(self) -> u8 {
        match self {
            Owner::Scene => 0,
            Owner::Person { person, .. } => person,
        }
    }
}

/// A shape with its owner and material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    /// The solid.
    pub shape: Shape,
    /// Who it belongs to (ground truth).
    pub owner: Owner,
    /// How it looks.
    pub material: Material,
}

impl Shape {
    /// An axis-aligned bounding box `(min, max)` of the shape (exact: the extent along
    /// each world axis).
    pub fn aabb(&self) -> (V3, V3) {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for (i, u) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .enumerate()
        {
            (lo[i], hi[i]) = self.extent_along(u);
        }
        (lo, hi)
    }

    /// `(min, max)` of the shape's points projected on the unit direction `u` (exact).
    pub fn extent_along(&self, u: V3) -> (f32, f32) {
        match *self {
            Shape::Capsule { a, b, radius } => {
                let (pa, pb) = (dot(a, u), dot(b, u));
                (pa.min(pb) - radius, pa.max(pb) + radius)
            }
            Shape::Cylinder { a, b, radius } => {
                // A cap disc of normal n spans ±r·sqrt(1 − (n·u)²) along u.
                let n = normalize(sub(b, a));
                let e = radius * (1.0 - dot(n, u).powi(2)).max(0.0).sqrt();
                let (pa, pb) = (dot(a, u), dot(b, u));
                (pa.min(pb) - e, pa.max(pb) + e)
            }
            Shape::Ellipsoid {
                center,
                axes,
                radii,
            } => {
                let mut e2 = 0.0;
                for i in 0..3 {
                    let k = radii[i] * dot(axes[i], u);
                    e2 += k * k;
                }
                let c = dot(center, u);
                (c - e2.sqrt(), c + e2.sqrt())
            }
            Shape::Box { center, axes, half } => {
                let mut e = 0.0;
                for i in 0..3 {
                    e += half[i] * dot(axes[i], u).abs();
                }
                let c = dot(center, u);
                (c - e, c + e)
            }
        }
    }
}

/// Rotation about world z by `yaw_rad` applied to `v`.
#[inline]
pub fn rotate_z(v: V3, yaw_rad: f32) -> V3 {
    let (s, c) = yaw_rad.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}

/// An orthonormal frame whose third axis is `dir` (normalised), for shapes given by an axis.
pub fn frame_from_axis(dir: V3) -> [V3; 3] {
    frame_around_unit_axis(normalize(dir))
}
