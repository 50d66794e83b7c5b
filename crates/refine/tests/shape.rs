//! The limb shape prior (`shape = "limbs"`) and the floor contact (`floor_contact_m`) on
//! hand-built bodies: each case is a label band the clustering steps leave wrong.

mod common;

use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label};
use bodyseg_refine::{RefineConfig, ShapeMode, refine_person};
use common::{Scene, ball, l};
use std::f32::consts::TAU;

fn cfg(shape: ShapeMode) -> RefineConfig {
    RefineConfig {
        eps_m: 0.03,
        min_points: 5,
        shape,
        ..Default::default()
    }
}

/// Surface points of a cylinder of `radius_m` from `a` to `b` (pitch `pitch_m` along and
/// around), labelled by `label(point, angle around the axis in radians, distance from a)`.
fn cylinder(
    a: Vec3,
    b: Vec3,
    radius_m: f32,
    pitch_m: f32,
    label: impl Fn(f32, f32) -> Label,
) -> (Vec<Vec3>, Vec<Label>) {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let dir = [d[0] / len, d[1] / len, d[2] / len];
    // A basis of the cross-section: e1 ⟂ dir, e2 = dir × e1.
    let helper = if dir[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let c = [
        dir[1] * helper[2] - dir[2] * helper[1],
        dir[2] * helper[0] - dir[0] * helper[2],
        dir[0] * helper[1] - dir[1] * helper[0],
    ];
    let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    let e1 = [c[0] / n, c[1] / n, c[2] / n];
    let e2 = [
        dir[1] * e1[2] - dir[2] * e1[1],
        dir[2] * e1[0] - dir[0] * e1[2],
        dir[0] * e1[1] - dir[1] * e1[0],
    ];
    let around = (TAU * radius_m / pitch_m).round() as i32;
    let steps = (len / pitch_m).round() as i32;
    let (mut pos, mut lab) = (Vec::new(), Vec::new());
    for i in 0..=steps {
        let t = i as f32 * pitch_m;
        for j in 0..around {
            let ang = j as f32 / around as f32 * TAU;
            let (s, co) = ang.sin_cos();
            pos.push(std::array::from_fn(|k| {
                a[k] + dir[k] * t + radius_m * (co * e1[k] + s * e2[k])
            }));
            lab.push(label(ang, t));
        }
    }
    (pos, lab)
}

/// Torso ball (r 0.15 m) with a head ball on it: the body tree's root and head.
fn trunk(s: &mut Scene) -> usize {
    let torso = s.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    s.add(ball([0.0, 0.0, 1.42], 0.08, 0.02, l(Class::Head)));
    torso
}

fn count(labels: &[Label], want: Class) -> usize {
    labels.iter().filter(|&&x| x == l(want)).count()
}

#[test]
fn a_strip_of_an_arm_labelled_torso_gets_the_arm_label_back() {
    let mut s = Scene::default();
    let torso = trunk(&mut s);
    // An upper arm hanging beside the torso (axis x = 0.22 m, radius 4.5 cm), whose front
    // strip (60° around +y, away from the torso at -x) the parser called torso, as where
    // the arm is seen in front of the torso.
    let arm = s.add(cylinder(
        [0.22, 0.0, 1.32],
        [0.22, 0.0, 1.0],
        0.045,
        0.01,
        |_, _| l(Class::UpperArms),
    ));
    // Relabel the strip by position: points of the arm on its +y side within ±30°.
    for i in s.parts[arm].clone() {
        let p = s.pos[i];
        let (dx, dy) = (p[0] - 0.22, p[1]);
        if dy > 0.0 && dx.abs() <= dy * (30f32.to_radians()).tan() {
            s.lab[i] = l(Class::Torso);
        }
    }
    let strip = s.labels_of(&s.lab, arm).len() - count(&s.labels_of(&s.lab, arm), Class::UpperArms);
    assert!(strip > 100, "the strip has {strip} points");

    // Without the prior the steps leave the strip torso: it is a cluster of its own.
    let r = refine_person(&s.pos, &s.lab, &cfg(ShapeMode::Off));
    assert_eq!(
        count(&s.labels_of(&r.point_labels, arm), Class::Torso),
        strip
    );

    let r = refine_person(&s.pos, &s.lab, &cfg(ShapeMode::Limbs));
    let arm_out = s.labels_of(&r.point_labels, arm);
    // The strip's points at the arm's very ends lie outside the fitted extent (its 2% and
    // 98% quantiles along the axis) and may stay torso: at least 90% come back.
    let left = count(&arm_out, Class::Torso);
    assert!(
        left * 10 <= strip,
        "{left} of {strip} strip points still torso"
    );
    assert_eq!(count(&arm_out, Class::UpperArms) + left, arm_out.len());
    // The torso keeps its own points.
    let torso_out = s.labels_of(&r.point_labels, torso);
    assert_eq!(count(&torso_out, Class::Torso), torso_out.len());
}

#[test]
fn a_boundary_shifted_past_a_bent_elbow_moves_back_to_the_joint() {
    let mut s = Scene::default();
    let torso = trunk(&mut s);
    // Upper arm hanging beside the torso down to the elbow at (0.22, 0, 1.0); the forearm
    // points forward (+y), bent 90°. The parser's boundary is 10 cm down the forearm: its
    // first 10 cm are labelled upper arm.
    let upper = s.add(cylinder(
        [0.22, 0.0, 1.32],
        [0.22, 0.0, 1.0],
        0.045,
        0.01,
        |_, _| l(Class::UpperArms),
    ));
    let lower = s.add(cylinder(
        [0.22, 0.0, 1.0],
        [0.22, 0.3, 1.0],
        0.035,
        0.01,
        |_, t| {
            if t < 0.095 {
                l(Class::UpperArms)
            } else {
                l(Class::LowerArms)
            }
        },
    ));
    let band: Vec<usize> = s.parts[lower]
        .clone()
        .filter(|&i| s.lab[i] == l(Class::UpperArms))
        .collect();
    // Forearm points past the upper arm's surface (y beyond its radius + 1 cm): the shape
    // says they are forearm.
    let clear: Vec<usize> = band
        .iter()
        .copied()
        .filter(|&i| s.pos[i][1] > 0.055)
        .collect();
    assert!(clear.len() > 20);

    let r = refine_person(&s.pos, &s.lab, &cfg(ShapeMode::Off));
    assert!(
        clear
            .iter()
            .all(|&i| r.point_labels[i] == l(Class::UpperArms))
    );

    let r = refine_person(&s.pos, &s.lab, &cfg(ShapeMode::Limbs));
    assert!(r.tree.slots[5].is_some() || r.tree.slots[6].is_some());
    let back = clear
        .iter()
        .filter(|&&i| r.point_labels[i] == l(Class::LowerArms))
        .count();
    assert_eq!(back, clear.len(), "forearm points past the elbow");
    // The upper arm above the elbow zone stays upper arm, the torso torso.
    for i in s.parts[upper].clone() {
        if s.pos[i][2] > 1.15 {
            assert_eq!(r.point_labels[i], l(Class::UpperArms), "{:?}", s.pos[i]);
        }
    }
    let torso_out = s.labels_of(&r.point_labels, torso);
    assert_eq!(count(&torso_out, Class::Torso), torso_out.len());
}

#[test]
fn floor_points_labelled_lower_leg_become_background() {
    let mut s = Scene::default();
    trunk(&mut s);
    // A lower leg standing on a floor at z = 0; a ring of floor around the foot is
    // labelled lower leg (the 2D label bleeding onto the floor).
    let leg = s.add(cylinder(
        [0.08, 0.0, 0.02],
        [0.08, 0.0, 0.45],
        0.05,
        0.01,
        |_, _| l(Class::LowerLegs),
    ));
    let mut floor = (Vec::new(), Vec::new());
    for i in -25..=25 {
        for j in -25..=25 {
            let p = [0.08 + i as f32 * 0.01, j as f32 * 0.01, 0.0];
            let r = ((p[0] - 0.08).powi(2) + p[1].powi(2)).sqrt();
            floor.0.push(p);
            floor.1.push(if r < 0.1 {
                l(Class::LowerLegs)
            } else {
                Label::BACKGROUND
            });
        }
    }
    let floor = s.add(floor);
    let bleed = count(&s.labels_of(&s.lab, floor), Class::LowerLegs);
    assert!(bleed > 50);

    // No R: this scene has no upper leg joining the lower leg to the torso.
    let off = RefineConfig {
        eps_m: 0.03,
        min_points: 5,
        steps: "M-N".parse().expect("valid steps"),
        ..Default::default()
    };
    let r = refine_person(&s.pos, &s.lab, &off);
    assert_eq!(
        count(&s.labels_of(&r.point_labels, floor), Class::LowerLegs),
        bleed
    );

    let on = RefineConfig {
        floor_contact_m: 0.006,
        ..off
    };
    let r = refine_person(&s.pos, &s.lab, &on);
    assert_eq!(
        count(&s.labels_of(&r.point_labels, floor), Class::LowerLegs),
        0
    );
    // The leg itself (2 cm and more above the floor) keeps its label.
    let leg_out = s.labels_of(&r.point_labels, leg);
    assert_eq!(count(&leg_out, Class::LowerLegs), leg_out.len());
}
