//! Floor contact (`floor_contact_m`) on a hand-built body: the leg label bled onto the floor
//! around a foot, which the clustering steps leave wrong.

mod common;

use bodyseg_core::Class;
use bodyseg_core::Label;
use bodyseg_refine::{RefineConfig, refine_person};
use common::{Scene, ball, l};
use std::f32::consts::TAU;

fn count(labels: &[Label], want: Class) -> usize {
    labels.iter().filter(|&&x| x == l(want)).count()
}

#[test]
fn floor_points_labelled_lower_leg_become_background() {
    let mut s = Scene::default();
    s.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    s.add(ball([0.0, 0.0, 1.42], 0.08, 0.02, l(Class::Head)));
    // A lower leg (a vertical cylinder, r 5 cm, from 2 cm to 45 cm) on a floor at z = 0; a
    // ring of floor around the foot is labelled lower leg (the 2D label bleeding onto it).
    let mut leg = (Vec::new(), Vec::new());
    for i in 0..=43 {
        for j in 0..31 {
            let (sin, cos) = (j as f32 / 31.0 * TAU).sin_cos();
            leg.0
                .push([0.08 + 0.05 * cos, 0.05 * sin, 0.02 + i as f32 * 0.01]);
            leg.1.push(l(Class::LowerLegs));
        }
    }
    let leg = s.add(leg);
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
