//! Joint-angle sets (trunk, arms, legs) and a person's segment dimensions from body height.

use super::math::Chan;
use crate::geometry::V3;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Trunk {
    /// Pelvis offset in the body frame, metres.
    pub(crate) pelvis_x: Chan,
    pub(crate) pelvis_y: Chan,
    /// Pelvis lowering below the planted height, metres.
    pub(crate) pelvis_drop: Chan,
    pub(crate) pelvis_yaw: Chan,
    pub(crate) pelvis_pitch: Chan,
    pub(crate) pelvis_roll: Chan,
    pub(crate) lumbar_flex: Chan,
    pub(crate) lumbar_lat: Chan,
    pub(crate) lumbar_twist: Chan,
    pub(crate) thor_flex: Chan,
    pub(crate) thor_lat: Chan,
    pub(crate) thor_twist: Chan,
    pub(crate) neck_flex: Chan,
    pub(crate) neck_lat: Chan,
    pub(crate) neck_yaw: Chan,
    pub(crate) head_nod: Chan,
    pub(crate) head_yaw: Chan,
}

/// One arm's joint angles, radians: shoulder flexion (forward), abduction (outward), twist
/// about the upper arm (R_z angle in the arm frame), elbow flexion (>= 0), wrist flexion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Arm {
    pub(crate) flex: Chan,
    pub(crate) abd: Chan,
    pub(crate) twist: Chan,
    pub(crate) elbow: Chan,
    pub(crate) wrist: Chan,
    /// Shoulder flexion amplitude following the gait (walking), radians.
    pub(crate) gait_swing: f32,
}

/// Where a foot is planted: ankle x y in the body frame at rest, metres, and toe-out yaw.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Leg {
    pub(crate) ankle_xy: [f32; 2],
    pub(crate) toe_yaw: f32,
}

/// Elbow flexion limits, radians (no hyperextension).
pub(crate) const ELBOW_MIN_RAD: f32 = 0.03;
pub(crate) const ELBOW_MAX_RAD: f32 = 2.6;

// ---------------------------------------------------------------------------------------
// Body shape.

/// Lengths and radii of one body, metres (fractions of height from Drillis & Contini).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dims {
    pub(crate) height: f32,
    pub(crate) hip_half_w: f32,
    pub(crate) thigh: f32,
    pub(crate) shin: f32,
    pub(crate) ankle_h: f32,
    pub(crate) foot_center: V3,
    pub(crate) foot_half: V3,
    pub(crate) pelvis_center: V3,
    pub(crate) pelvis_radii: V3,
    pub(crate) lumbar_up: f32,
    pub(crate) abdomen_center: V3,
    pub(crate) abdomen_radii: V3,
    pub(crate) thoracic_up: f32,
    pub(crate) chest_center: V3,
    pub(crate) chest_radii: V3,
    pub(crate) shoulder: V3,
    pub(crate) shoulder_r: f32,
    pub(crate) neck_base: V3,
    pub(crate) neck_vec: V3,
    pub(crate) neck_r: f32,
    pub(crate) head_center: V3,
    pub(crate) head_radii: V3,
    pub(crate) hair_offset: V3,
    pub(crate) hair_radii: V3,
    pub(crate) upper_arm: f32,
    pub(crate) forearm: f32,
    pub(crate) hand_half: V3,
    pub(crate) upper_arm_r: f32,
    pub(crate) forearm_r: f32,
    pub(crate) thigh_r: f32,
    pub(crate) shin_r: f32,
}

impl Dims {
    pub(crate) fn new(h: f32, girth: f32, hair_volume: f32) -> Dims {
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

    pub(crate) fn leg(&self) -> f32 {
        self.thigh + self.shin
    }

    /// Shoulder joint in the chest frame (origin at the thoracic joint); `side` +1 left.
    pub(crate) fn shoulder_at(&self, side: f32) -> V3 {
        [self.shoulder[0], side * self.shoulder[1], self.shoulder[2]]
    }
}

/// Fraction of the leg length between hip and ankle when standing (knees nearly straight).
pub(crate) const STAND_LEG_FRACTION: f32 = 0.998;
/// Same while walking (knees a little bent through the stance).
pub(crate) const WALK_LEG_FRACTION: f32 = 0.975;

// ---------------------------------------------------------------------------------------
// Clothing.
