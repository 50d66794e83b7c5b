//! Placing people in the scene (obstacles, paths that keep apart over the sequence) and the
//! hand-over set-up and object.

use std::f32::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::clothes::{object_color, pick};
use super::draw::draw_person;
use super::math::{UP, gauss, sway, uni};
use super::motion::{Handover, Motion, Stadium, Walk};
use super::person::Person;
use super::pose::{BodyPose, FloorObstacle, HANDOVER_OBJECT_SIZE_M, PERSON_RADIUS_M};
use crate::config::PeopleConfig;
use crate::geometry::{Material, Owner, Primitive, Shape, add, dot, norm, rotate_z, scale, sub};

/// Candidate placements tried per person before the least bad one is taken.
pub(crate) const PLACEMENT_TRIES: usize = 1000;
/// Times (seconds) at which walking paths are checked against the constraints.
pub(crate) const CHECK_STEP_S: f64 = 0.25;
pub(crate) const CHECK_STEPS: usize = 240;

pub(crate) struct Constraints<'a> {
    pub(crate) area: f32,
    pub(crate) spacing: f32,
    pub(crate) obstacles: &'a [FloorObstacle],
    pub(crate) times: Vec<f64>,
}

impl Constraints<'_> {
    /// How far a pelvis position breaks the area and obstacle constraints, metres.
    pub(crate) fn site_violation(&self, xy: [f32; 2]) -> f32 {
        let mut v = (xy[0].abs() - self.area).max(0.0) + (xy[1].abs() - self.area).max(0.0);
        for o in self.obstacles {
            let dist = ((xy[0] - o.center_m[0]).powi(2) + (xy[1] - o.center_m[1]).powi(2)).sqrt();
            v += (o.radius_m + PERSON_RADIUS_M - dist).max(0.0);
        }
        v
    }

    /// How far a walking loop leaves the area or enters an obstacle (exact, over the whole
    /// loop), metres.
    pub(crate) fn path_violation(&self, path: &Stadium) -> f32 {
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
    pub(crate) fn violation(&self, motions: &[Motion], placed: &[Motion]) -> f32 {
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

pub(crate) fn facing_center(rng: &mut ChaCha8Rng, xy: [f32; 2]) -> f32 {
    if xy[0].hypot(xy[1]) < 0.1 {
        uni(rng, -PI, PI)
    } else {
        (-xy[1]).atan2(-xy[0]) + 0.45 * gauss(rng)
    }
}

pub(crate) fn candidate(
    rng: &mut ChaCha8Rng,
    person: &Person,
    area: f32,
    walk_speed: f32,
) -> Motion {
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
pub(crate) fn setup_handover(people: &mut [Person], rng: &mut ChaCha8Rng) {
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
