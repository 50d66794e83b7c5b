//! Drawing one person from its seed stream: body shape, clothes, a pose from the library and
//! joint perturbation.

use std::f32::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::body::{
    Arm, Dims, ELBOW_MAX_RAD, ELBOW_MIN_RAD, Leg, STAND_LEG_FRACTION, Trunk, WALK_LEG_FRACTION,
};
use super::clothes::make_clothes;
use super::math::{Chan, gauss, mm, mtv, mv, rot_x, rot_y, sway, sway_deg, sway_r, uni, uni_deg};
use super::motion::Motion;
use super::person::{Person, SIDES};
use super::pose::BodyPose;
use crate::config::PeopleConfig;
use crate::geometry::{V3, add, normalize, sub};

/// Which arms a one- or two-armed pose uses: (left, right).
pub(crate) fn arms_used(rng: &mut ChaCha8Rng, both_prob: f32) -> (bool, bool) {
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
pub(crate) fn arm_hanging(rng: &mut ChaCha8Rng, side: f32, girth: f32) -> Arm {
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
pub(crate) fn aim_forearm(d: &Dims, side: f32, flex: f32, abd: f32, target: V3) -> (f32, f32) {
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
pub(crate) fn arm_aimed(
    rng: &mut ChaCha8Rng,
    d: &Dims,
    side: f32,
    flex: f32,
    abd: f32,
    target: V3,
) -> Arm {
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
pub(crate) fn trunk_calm(rng: &mut ChaCha8Rng) -> Trunk {
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

pub(crate) fn legs_standing(rng: &mut ChaCha8Rng, h: f32) -> [Leg; 2] {
    let w = uni(rng, 0.05, 0.07) * h;
    let x = uni(rng, -0.01, 0.01) * h;
    SIDES.map(|s| Leg {
        ankle_xy: [x, s * w],
        toe_yaw: s * uni_deg(rng, 5.0, 15.0),
    })
}

/// Adds `sigma` (radians) Gaussian noise to the base of every joint-angle channel.
pub(crate) fn perturb(rng: &mut ChaCha8Rng, person: &mut Person, sigma: f32) {
    if sigma <= 0.0 {
        return;
    }
    let tr = &mut person.trunk;
    tr.pelvis_yaw.base += sigma * gauss(rng);
    // The spine (pelvis, lumbar, thoracic) and the neck-head chain are each one anatomical
    // joint split in parts: the noise is shared so that the chain bends by about `sigma`.
    let spine = sigma / 3f32.sqrt();
    shake(
        rng,
        spine,
        [
            &mut tr.pelvis_pitch,
            &mut tr.pelvis_roll,
            &mut tr.lumbar_flex,
            &mut tr.lumbar_lat,
            &mut tr.lumbar_twist,
            &mut tr.thor_flex,
            &mut tr.thor_lat,
            &mut tr.thor_twist,
        ],
    );
    let neck = sigma / 2f32.sqrt();
    shake(
        rng,
        neck,
        [
            &mut tr.neck_flex,
            &mut tr.neck_lat,
            &mut tr.neck_yaw,
            &mut tr.head_nod,
            &mut tr.head_yaw,
        ],
    );
    for arm in &mut person.arms {
        shake(
            rng,
            sigma,
            [
                &mut arm.flex,
                &mut arm.abd,
                &mut arm.twist,
                &mut arm.elbow,
                &mut arm.wrist,
            ],
        );
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

/// Adds `sigma` × a standard normal draw to the base of each channel, in order.
fn shake<'a>(rng: &mut ChaCha8Rng, sigma: f32, chans: impl IntoIterator<Item = &'a mut Chan>) {
    for c in chans {
        c.base += sigma * gauss(rng);
    }
}

/// Draws shape, clothing and pose of person `index` (motion is set at placement).
pub(crate) fn draw_person(
    config: &PeopleConfig,
    seed: u64,
    index: usize,
    pose: BodyPose,
) -> Person {
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
