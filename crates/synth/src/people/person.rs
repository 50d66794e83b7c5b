//! A drawn person: forward and inverse kinematics of the skeleton at a time, and its
//! primitives (capsules, boxes) for the renderer.

use std::f32::consts::{PI, TAU};

use super::body::{
    Arm, Dims, ELBOW_MAX_RAD, ELBOW_MIN_RAD, Leg, STAND_LEG_FRACTION, Trunk, WALK_LEG_FRACTION,
};
use super::clothes::Clothes;
use super::math::{IDENTITY, M3, UP, mm, mv, rot_fsz, rot_x, rot_y, rot_z, two_bone};
use super::motion::{Handover, Motion};
use super::pose::BodyPose;
use crate::geometry::{
    Material, Owner, Primitive, Segment, Shape, V3, add, cross, dot, normalize, rotate_z, scale,
    sub,
};

/// One synthetic person for a whole sequence: shape, clothing and motion.
#[derive(Clone, Debug)]
pub struct Person {
    /// 1-based id (written in `depth_person` images).
    pub id: u8,
    pub(crate) pose: BodyPose,
    pub(crate) girth: f32,
    pub(crate) dims: Dims,
    pub(crate) clothes: Clothes,
    pub(crate) motion: Motion,
    pub(crate) trunk: Trunk,
    /// Left (index 0) and right arm.
    pub(crate) arms: [Arm; 2],
    /// Left (index 0) and right leg.
    pub(crate) legs: [Leg; 2],
    /// Pelvis height (hip joints) the pose aims for before the legs limit it, metres.
    pub(crate) hip_z_nominal: f32,
    pub(crate) handover: Option<Handover>,
}

/// Sides: +1 left, -1 right, in arm and leg index order.
pub(crate) const SIDES: [f32; 2] = [1.0, -1.0];

/// Joint positions and frames of one time step (world frame).
pub(crate) struct Skeleton {
    pub(crate) root: V3,
    pub(crate) pelvis: M3,
    pub(crate) lumbar: V3,
    pub(crate) abdomen: M3,
    pub(crate) thoracic: V3,
    pub(crate) chest: M3,
    pub(crate) neck_base: V3,
    pub(crate) neck_top: V3,
    pub(crate) head: M3,
    pub(crate) head_pos: V3,
    pub(crate) shoulder: [V3; 2],
    pub(crate) elbow: [V3; 2],
    pub(crate) wrist: [V3; 2],
    pub(crate) hand_center: [V3; 2],
    pub(crate) hand_axes: [M3; 2],
    pub(crate) hip: [V3; 2],
    pub(crate) knee: [V3; 2],
    pub(crate) ankle: [V3; 2],
    pub(crate) foot: [M3; 2],
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

    pub(crate) fn skeleton_at(&self, t: f64) -> Skeleton {
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

    pub(crate) fn emit(&self, sk: &Skeleton, out: &mut Vec<Primitive>) {
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

pub(crate) fn box_shape(center: V3, axes: M3, half: V3) -> Shape {
    Shape::Box { center, axes, half }
}

/// Ankle offset along the walking direction (body frame, metres) and lift above the
/// standing ankle height at gait phase `u` of this leg (0 = heel strike). The stance (60 %
/// of the cycle) moves the foot back at walking speed, the swing brings it forward.
pub(crate) fn gait_foot(u: f32, stride_m: f32, height_m: f32) -> (f32, f32) {
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
pub(crate) fn handover_arm(
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
