//! The public vocabulary of `people`: the pose library, floor obstacles and the sizes other
//! modules of the crate read.

use crate::geometry::V3;

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
