//! Unit tests of `people`.

use std::f32::consts::{PI, TAU};

use super::clothes::*;
use super::person::*;
use super::placement::*;
use super::pose::*;
use crate::config::POSE_NAMES;
use crate::config::PeopleConfig;
use crate::geometry::*;

fn config(poses: &[&str], count: u32) -> PeopleConfig {
    PeopleConfig {
        count,
        poses: poses.iter().map(|s| s.to_string()).collect(),
        area_half_m: 1.5,
        ..PeopleConfig::default()
    }
}

/// For each pose, the people [`make_people`] makes with `count` people of that pose and
/// seeds `0..seeds`, the config changed by `tweak` first: (pose name, seed, person).
fn people_of_each_pose(
    count: u32,
    seeds: u64,
    tweak: impl Fn(&mut PeopleConfig),
) -> Vec<(&'static str, u64, Person)> {
    let mut out = Vec::new();
    for name in POSE_NAMES {
        let mut c = config(&[name], count);
        tweak(&mut c);
        for seed in 0..seeds {
            out.extend(
                make_people(&c, seed, &[])
                    .into_iter()
                    .map(|p| (name, seed, p)),
            );
        }
    }
    out
}

fn prims(p: &Person, t: f64) -> Vec<Primitive> {
    let mut out = Vec::new();
    p.primitives_at(t, &mut out);
    out
}

fn of(prims: &[Primitive], seg: Segment) -> Vec<Primitive> {
    prims
        .iter()
        .filter(|q| matches!(q.owner, Owner::Person { segment, .. } if segment == seg))
        .copied()
        .collect()
}

fn min_z(prims: &[Primitive]) -> f32 {
    prims
        .iter()
        .map(|q| q.shape.aabb().0[2])
        .fold(f32::INFINITY, f32::min)
}

fn center(p: &Primitive) -> V3 {
    match p.shape {
        Shape::Ellipsoid { center, .. } | Shape::Box { center, .. } => center,
        Shape::Capsule { a, b, .. } | Shape::Cylinder { a, b, .. } => scale(add(a, b), 0.5),
    }
}

/// Points that move with a primitive: centre, or both axis ends.
fn key_points(p: &Primitive) -> [V3; 2] {
    match p.shape {
        Shape::Ellipsoid { center, .. } | Shape::Box { center, .. } => [center, center],
        Shape::Capsule { a, b, .. } | Shape::Cylinder { a, b, .. } => [a, b],
    }
}

fn dist(a: V3, b: V3) -> f32 {
    norm(sub(a, b))
}

const TIMES: [f64; 6] = [0.0, 0.37, 1.3, 2.9, 7.1, 33.3];

#[test]
fn pose_names_round_trip() {
    for (name, pose) in POSE_NAMES.iter().zip(BodyPose::ALL) {
        assert_eq!(BodyPose::from_name(name), Some(pose));
        assert_eq!(pose.name(), *name);
    }
    assert_eq!(BodyPose::from_name("dancing"), None);
}

#[test]
fn every_person_has_all_segments_with_its_id() {
    for seed in 0..5 {
        let people = make_people(&config(&POSE_NAMES, 3), seed, &[]);
        assert_eq!(people.len(), 3);
        for (i, p) in people.iter().enumerate() {
            assert_eq!(usize::from(p.id), i + 1);
            let out = prims(p, 1.0);
            let mut segs: Vec<Segment> = out
                .iter()
                .map(|q| match q.owner {
                    Owner::Person { person, segment } => {
                        assert_eq!(person, p.id);
                        segment
                    }
                    Owner::Scene => panic!("scene primitive in a person"),
                })
                .collect();
            segs.sort();
            segs.dedup();
            assert!(segs.len() >= 15, "{} segments", segs.len());
            assert_eq!(segs.len(), Segment::ALL.len());
        }
    }
}

#[test]
fn heights_within_config_range() {
    let mut c = config(&["standing"], 3);
    c.joint_noise_deg = 0.0;
    let mut heights = Vec::new();
    for seed in 0..20 {
        for p in make_people(&c, seed, &[]) {
            let h = p.height_m();
            assert!((1.5..=1.95).contains(&h), "height {h}");
            heights.push(h);
            for t in TIMES {
                let head = of(&prims(&p, t), Segment::Head);
                let top = head[0].shape.aabb().1[2];
                assert!(
                    top > h - 0.03 && top < h + 0.01,
                    "head top {top} for height {h}"
                );
            }
        }
    }
    let lo = heights.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = heights.iter().copied().fold(0.0, f32::max);
    assert!(lo < 1.6 && hi > 1.85, "heights not spread: {lo}..{hi}");
}

#[test]
fn feet_stand_on_the_floor_in_every_pose() {
    for (name, seed, p) in people_of_each_pose(2, 6, |_| {}) {
        for k in 0..40 {
            let t = f64::from(k) * 0.173;
            let out = prims(&p, t);
            assert!(min_z(&out) >= -0.01, "{name}: body below the floor");
            let feet: Vec<Primitive> = [Segment::FootLeft, Segment::FootRight]
                .into_iter()
                .flat_map(|s| of(&out, s))
                .collect();
            let lowest = min_z(&feet);
            assert!(
                (-0.01..=0.01).contains(&lowest),
                "{name} seed {seed} t {t}: lowest foot point {lowest}"
            );
            if name != "walking" {
                for f in &feet {
                    let z = f.shape.aabb().0[2];
                    assert!(z < 0.03, "{name}: a planted foot floats at {z}");
                }
            }
        }
    }
}

#[test]
fn same_seed_same_people_other_seed_other_people() {
    let c = config(&POSE_NAMES, 3);
    let a = make_people(&c, 7, &[]);
    let b = make_people(&c, 7, &[]);
    let other = make_people(&c, 8, &[]);
    for t in TIMES {
        for ((pa, pb), po) in a.iter().zip(&b).zip(&other) {
            assert_eq!(prims(pa, t), prims(pb, t));
            assert_eq!(pa.yaw_rad_at(t), pb.yaw_rad_at(t));
            assert_ne!(prims(pa, t), prims(po, t));
        }
    }
    // Poses vary with the seed.
    let mut seen: Vec<BodyPose> = (0..40)
        .flat_map(|s| make_people(&c, s, &[]))
        .map(|p| p.pose())
        .collect();
    seen.sort_by_key(|p| p.name());
    seen.dedup();
    assert!(seen.len() >= 6, "only {} poses drawn", seen.len());
}

#[test]
fn handover_hands_meet_between_close_people() {
    let mut c = config(&["standing"], 2);
    c.handover = true;
    c.area_half_m = 0.8;
    for count in [2, 3] {
        c.count = count;
        for seed in 0..12 {
            let people = make_people(&c, seed, &[]);
            let (p1, p2) = (&people[0], &people[1]);
            assert_eq!(p1.pose(), BodyPose::HandingOver);
            assert_eq!(p2.pose(), BodyPose::HandingOver);
            let yaw_gap = (p1.yaw_rad_at(0.0) - p2.yaw_rad_at(0.0)).rem_euclid(TAU);
            assert!((yaw_gap - PI).abs() < 0.1, "not facing: {yaw_gap}");
            for k in 0..30 {
                let t = f64::from(k) * 0.41;
                let a = p1.pelvis_xy_at(t);
                let b = p2.pelvis_xy_at(t);
                let gap = (a[0] - b[0]).hypot(a[1] - b[1]);
                assert!(gap < 0.8, "people {gap} m apart");
                let h1 = center(&of(&prims(p1, t), Segment::HandRight)[0]);
                let h2 = center(&of(&prims(p2, t), Segment::HandLeft)[0]);
                let d = dist(h1, h2);
                assert!(d < 0.1, "seed {seed} t {t}: hands {d} m apart");
                for h in [h1, h2] {
                    assert!((0.95..=1.25).contains(&h[2]), "hand at {h:?}");
                }
                let obj = handover_object(&people, &c, t).expect("hand-over object");
                assert_eq!(obj.owner, Owner::Scene);
                let oc = center(&obj);
                let mid = scale(add(h1, h2), 0.5);
                assert!((oc[0] - mid[0]).hypot(oc[1] - mid[1]) < 0.05);
                assert!(oc[2] > mid[2] && oc[2] < mid[2] + 0.15);
            }
        }
    }
    c.handover = false;
    let people = make_people(&c, 1, &[]);
    assert!(handover_object(&people, &c, 0.0).is_none());
}

#[test]
fn every_pose_gives_valid_finite_primitives() {
    for (name, _, p) in people_of_each_pose(3, 5, |c| c.joint_noise_deg = 15.0) {
        assert_eq!(p.pose().name(), name);
        for t in TIMES {
            let out = prims(&p, t);
            assert!(out.len() >= 18);
            for q in &out {
                let (lo, hi) = q.shape.aabb();
                assert!(lo.iter().chain(&hi).all(|x| x.is_finite()), "{name}");
                assert!(hi[2] < 2.2, "{name}: too tall");
                match q.shape {
                    Shape::Capsule { radius, .. } => assert!(radius > 0.0),
                    Shape::Ellipsoid { axes, radii, .. }
                    | Shape::Box {
                        axes, half: radii, ..
                    } => {
                        assert!(radii.iter().all(|r| *r > 0.0));
                        for i in 0..3 {
                            assert!((norm(axes[i]) - 1.0).abs() < 1e-3);
                            for j in 0..i {
                                assert!(dot(axes[i], axes[j]).abs() < 1e-3);
                            }
                        }
                    }
                    Shape::Cylinder { .. } => panic!("people have no cylinders"),
                }
            }
        }
    }
}

#[test]
fn people_stay_in_the_area_outside_obstacles_and_apart() {
    let obstacles = [
        FloorObstacle {
            center_m: [0.0, 0.0],
            radius_m: 0.3,
        },
        FloorObstacle {
            center_m: [1.0, -1.0],
            radius_m: 0.2,
        },
    ];
    for poses in [&["standing", "pointing"][..], &["walking", "standing"][..]] {
        let mut c = config(poses, 3);
        c.area_half_m = 1.5;
        c.min_spacing_m = 0.9;
        for seed in 0..10 {
            let people = make_people(&c, seed, &obstacles);
            for k in 0..120 {
                let t = f64::from(k) * 0.5;
                let xy: Vec<[f32; 2]> = people.iter().map(|p| p.pelvis_xy_at(t)).collect();
                for (i, a) in xy.iter().enumerate() {
                    assert!(a[0].abs() <= 1.5 && a[1].abs() <= 1.5, "outside: {a:?}");
                    for o in &obstacles {
                        let d = (a[0] - o.center_m[0]).hypot(a[1] - o.center_m[1]);
                        assert!(d >= o.radius_m + PERSON_RADIUS_M - 1e-3, "in obstacle");
                    }
                    for b in &xy[..i] {
                        let d = (a[0] - b[0]).hypot(a[1] - b[1]);
                        // Two loops and a standing person in a crowded area: the
                        // search may settle for a near miss (spacing is relaxed first).
                        let want = if poses[0] == "walking" {
                            0.85
                        } else {
                            0.9 - 1e-3
                        };
                        assert!(d >= want, "{poses:?} seed {seed}: {d} m apart");
                    }
                }
            }
        }
    }
}

#[test]
fn impossible_placement_is_relaxed_not_fatal() {
    let mut c = config(&POSE_NAMES, 3);
    c.area_half_m = 0.1;
    c.min_spacing_m = 5.0;
    let wall = [FloorObstacle {
        center_m: [0.0, 0.0],
        radius_m: 10.0,
    }];
    let people = make_people(&c, 3, &wall);
    assert_eq!(people.len(), 3);
    for p in &people {
        assert!(
            prims(p, 0.5)
                .iter()
                .all(|q| q.shape.aabb().0[0].is_finite())
        );
    }
    c.handover = true;
    c.handover_distance_m = 1.5;
    let people = make_people(&c, 3, &wall);
    assert!(handover_object(&people, &c, 1.0).is_some());
    c.count = 0;
    assert!(make_people(&c, 3, &[]).is_empty());
}

fn max_step(p: &Person, t: f64, dt: f64) -> f32 {
    let a = prims(p, t);
    let b = prims(p, t + dt);
    assert_eq!(a.len(), b.len());
    let mut worst = 0.0f32;
    for (qa, qb) in a.iter().zip(&b) {
        for (pa, pb) in key_points(qa).into_iter().zip(key_points(qb)) {
            worst = worst.max(dist(pa, pb));
        }
    }
    worst
}

#[test]
fn motion_is_continuous_between_frames() {
    for (name, _, p) in people_of_each_pose(2, 4, |c| c.walk_speed_m_s = 0.35) {
        for k in 0..200 {
            let t = f64::from(k) * 0.093;
            let step = max_step(&p, t, 1.0 / 30.0);
            assert!(step < 0.05, "{name} t {t}: moved {step} m in a frame");
        }
        // It does move.
        assert!(prims(&p, 0.0) != prims(&p, 2.0), "{name} frozen");
    }
    // At the default walking speed the swing foot is fast: 60 fps.
    let c = config(&["walking"], 1);
    for seed in 0..4 {
        for p in make_people(&c, seed, &[]) {
            for k in 0..300 {
                let t = f64::from(k) * 0.031;
                let step = max_step(&p, t, 1.0 / 60.0);
                assert!(step < 0.05, "walking t {t}: moved {step} m");
            }
        }
    }
}

#[test]
fn walkers_move_at_the_configured_speed() {
    let mut c = config(&["walking"], 1);
    c.area_half_m = 1.0;
    for seed in 0..6 {
        let p = &make_people(&c, seed, &[])[0];
        let mut path = 0.0;
        for k in 0..100 {
            let a = p.pelvis_xy_at(f64::from(k) * 0.05);
            let b = p.pelvis_xy_at(f64::from(k + 1) * 0.05);
            path += (a[0] - b[0]).hypot(a[1] - b[1]);
        }
        // 5 s at 0.6 m/s.
        assert!((path - 3.0).abs() < 0.1, "walked {path} m");
        // Facing the walking direction.
        let a = p.pelvis_xy_at(1.0);
        let b = p.pelvis_xy_at(1.01);
        let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
        let diff = (heading - p.yaw_rad_at(1.0) + PI).rem_euclid(TAU) - PI;
        assert!(diff.abs() < 0.2, "heading off by {diff}");
    }
}

#[test]
fn knees_bend_forward() {
    for (name, _, p) in people_of_each_pose(2, 5, |_| {}) {
        for t in TIMES {
            let out = prims(&p, t);
            for (thigh, shin, foot) in [
                (Segment::ThighLeft, Segment::ShinLeft, Segment::FootLeft),
                (Segment::ThighRight, Segment::ShinRight, Segment::FootRight),
            ] {
                let (
                    Shape::Capsule {
                        a: hip, b: knee, ..
                    },
                    Shape::Capsule { b: ankle, .. },
                    Shape::Box { axes, .. },
                ) = (
                    of(&out, thigh)[0].shape,
                    of(&out, shin)[0].shape,
                    of(&out, foot)[0].shape,
                )
                else {
                    panic!("unexpected leg shapes");
                };
                let line = normalize(sub(ankle, hip));
                let rel = sub(knee, hip);
                let off = sub(rel, scale(line, dot(rel, line)));
                assert!(dot(off, axes[0]) >= -1e-3, "{name}: knee bends backwards");
            }
        }
    }
    let c = config(&["crouching"], 1);
    let p = &make_people(&c, 0, &[])[0];
    let pelvis = of(&prims(p, 0.0), Segment::Pelvis);
    assert!(
        center(&pelvis[0])[2] < 0.45 * p.height_m(),
        "crouch not low"
    );
}

#[test]
fn clothes_are_distinct_and_sleeves_follow_the_config() {
    fn srgb(c: [f32; 3]) -> [f32; 3] {
        c.map(|x| {
            if x <= 0.0031308 {
                x * 12.92
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            }
        })
    }
    let mut c = config(&["standing"], 3);
    for (prob, short) in [(0.0, false), (1.0, true)] {
        c.short_sleeves = prob;
        for seed in 0..30 {
            for p in make_people(&c, seed, &[]) {
                let cl = &p.clothes;
                assert_eq!(p.short_sleeves(), short);
                let fore = of(&prims(&p, 0.0), Segment::ForearmLeft)[0].material;
                let want = if short { cl.skin } else { cl.shirt };
                assert_eq!(fore, want);
                let [shirt, trousers, skin] =
                    [cl.shirt, cl.trousers, cl.skin].map(|m| srgb(m.albedo));
                assert!(srgb_dist(shirt, trousers) >= MIN_CLOTHES_DIST - 1e-3);
                assert!(srgb_dist(shirt, skin) >= MIN_CLOTHES_DIST - 1e-3);
                assert!(srgb_dist(trousers, skin) >= MIN_CLOTHES_DIST - 1e-3);
                for m in [cl.shirt, cl.trousers, cl.skin, cl.hair, cl.shoes] {
                    assert!(m.albedo.iter().all(|x| (0.0..=1.0).contains(x)));
                }
            }
        }
    }
}

#[test]
fn arm_poses_put_hands_where_they_belong() {
    let mut c = config(&["reaching"], 1);
    c.joint_noise_deg = 0.0;
    for name in ["reaching", "arms_crossed", "hands_on_hips", "pointing"] {
        c.poses = vec![name.to_string()];
        for seed in 0..5 {
            let p = &make_people(&c, seed, &[])[0];
            let out = prims(p, 0.0);
            let h = p.height_m();
            let (root, yaw) = (p.pelvis_xy_at(0.0), p.yaw_rad_at(0.0));
            let local = |v: V3| rotate_z(sub(v, [root[0], root[1], 0.0]), -yaw);
            let hands =
                [Segment::HandLeft, Segment::HandRight].map(|s| local(center(&of(&out, s)[0])));
            let ok = match name {
                // Some hand forward at about chest height.
                "reaching" | "pointing" => hands
                    .iter()
                    .any(|v| v[0] > 0.25 * h && (0.6 * h..0.9 * h).contains(&v[2])),
                // Hands in front of the chest, each on the other side.
                "arms_crossed" => {
                    hands[0][1] < 0.02 * h
                        && hands[1][1] > -0.02 * h
                        && hands.iter().all(|v| v[0] > 0.02 * h && v[2] > 0.6 * h)
                }
                // Hands at the hips, at the sides.
                _ => hands
                    .iter()
                    .all(|v| (0.48 * h..0.66 * h).contains(&v[2]) && v[1].abs() > 0.07 * h),
            };
            assert!(ok, "{name} seed {seed}: hands at {hands:?} (height {h})");
        }
    }
}
