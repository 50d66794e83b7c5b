//! People close together (issue 6): hand-made clouds of labelled cylinder and sphere
//! surfaces (as `robot_arm.rs`), a floor and two people. Geometry mode: a short person's
//! head must stay a head when a taller neighbour's shoulder and arm are within
//! `head_separation_m` of it at head height. Labels mode: an arm whose hand touches
//! someone else's head stays in its owner's box.

mod common;

use bodyseg_core::{Class, PersonBox};
use bodyseg_people::{BoxMode, BoxesConfig, box_iou, find_boxes};
use common::Scene;

/// A person `height_m` tall standing at (`x`, `y`), facing +y (shoulders along x): the
/// 1.72 m body of `robot_arm.rs` scaled. Returns their true box (exact extent plus
/// bodyseg-synth's 5 cm margin, from the floor up).
fn person(out: &mut Scene, x: f32, y: f32, height_m: f32, arms: bool) -> PersonBox {
    leaning_person(out, x, y, height_m, arms, 0.0)
}

/// [`person`] with the head leaning `lean_y_m` along y (the returned box ignores it).
fn leaning_person(
    out: &mut Scene,
    x: f32,
    y: f32,
    height_m: f32,
    arms: bool,
    lean_y_m: f32,
) -> PersonBox {
    let s = height_m / 1.72;
    let at = |dx: f32, dy: f32, z: f32| [x + s * dx, y + s * dy, s * z];
    out.sphere(at(0.0, lean_y_m / s, 1.62), s * 0.1, Class::Head);
    let neck_top = at(0.0, 0.6 * lean_y_m / s, 1.54);
    out.cylinder(at(0.0, 0.0, 1.44), neck_top, s * 0.05, Class::Head);
    out.cylinder(
        at(0.0, 0.0, 0.88),
        at(0.0, 0.0, 1.44),
        s * 0.16,
        Class::Torso,
    );
    // Shoulders: joins the neck to the trunk and the arms (an open trunk's rim is
    // farther than `person_gap_m` from a scaled-up neck).
    out.cylinder(
        at(-0.22, 0.0, 1.42),
        at(0.22, 0.0, 1.42),
        s * 0.06,
        Class::Torso,
    );
    for side in [-1.0, 1.0] {
        let (hip, knee) = (at(side * 0.09, 0.0, 0.9), at(side * 0.09, 0.0, 0.45));
        out.cylinder(hip, knee, s * 0.07, Class::UpperLegs);
        out.cylinder(knee, at(side * 0.09, 0.0, 0.0), s * 0.07, Class::LowerLegs);
        if arms {
            let (shoulder, elbow) = (at(side * 0.22, 0.0, 1.42), at(side * 0.23, 0.0, 1.14));
            out.cylinder(shoulder, elbow, s * 0.045, Class::UpperArms);
            let hand = at(side * 0.24, 0.0, 0.86);
            out.cylinder(elbow, hand, s * 0.045, Class::LowerArms);
        }
    }
    // Extent: x ±0.285 (arms), y ±0.16 (torso), z 0–1.72, scaled; plus 0.05 on every
    // side and on top.
    PersonBox::axis_aligned(
        0,
        [x, y, (height_m + 0.05) / 2.0],
        [s * 0.285 + 0.05, s * 0.16 + 0.05, (height_m + 0.05) / 2.0],
    )
}

#[test]
fn a_short_person_beside_a_tall_one_keeps_their_head() {
    let mut scene = Scene::default();
    scene.floor();
    let short = person(&mut scene, 0.0, 0.0, 1.65, true);
    // 0.6 m away (beyond head_separation_m): the tall neighbour's shoulder and upper
    // arm, at 1.5–1.6 m, lie within 0.4 m of the short person's head and above their
    // chin, without touching their head.
    let tall = person(&mut scene, 0.6, 0.0, 1.9, true);
    let cfg = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    let found = find_boxes(&scene.cloud(false), &cfg).expect("boxes");
    // Counting every voxel within 0.4 m below the top, the neighbour's arm made the short
    // person's head "not compact" and they had no box.
    assert_eq!(found.boxes.len(), 2, "{found:?}");
    for truth in [&short, &tall] {
        let hits = found
            .boxes
            .iter()
            .filter(|b| box_iou(truth, b) >= 0.5)
            .count();
        assert_eq!(hits, 1, "{truth:?} vs {found:?}");
    }
}

#[test]
fn an_arm_touching_someone_else_s_head_stays_its_owner_s() {
    let mut scene = Scene::default();
    scene.floor();
    let left = person(&mut scene, 0.0, 0.0, 1.72, true);
    // The right person, 0.8 m away and without hanging arms, reaches out with their
    // left arm: the hand touches the left person's head from the side.
    person(&mut scene, 0.8, 0.0, 1.72, false);
    let (shoulder, elbow, hand) = ([0.58, 0.0, 1.42], [0.45, 0.0, 1.68], [0.15, 0.0, 1.68]);
    scene.cylinder(shoulder, elbow, 0.045, Class::UpperArms);
    scene.cylinder(elbow, hand, 0.04, Class::LowerArms);
    let found = find_boxes(&scene.cloud(true), &BoxesConfig::default()).expect("boxes");
    assert_eq!(found.boxes.len(), 2, "{found:?}");
    let (mine, theirs): (Vec<&PersonBox>, Vec<&PersonBox>) =
        found.boxes.iter().partition(|b| box_iou(&left, b) >= 0.5);
    assert_eq!((mine.len(), theirs.len()), (1, 1), "{found:?}");
    // Split at equal graph distance from the two heads, the forearm (nearer the left
    // head: it touches it) and the elbow went to the left person.
    assert!(!mine[0].contains(elbow), "{found:?}");
    assert!(theirs[0].contains(elbow), "{found:?}");
    assert!(theirs[0].contains([0.2, 0.0, 1.68]), "{found:?}");
}

#[test]
fn two_heads_leaning_together_are_two_people() {
    let mut scene = Scene::default();
    scene.floor();
    // Standing 0.6 m apart (facing each other along y), heads leaning 0.12 m towards
    // each other: tops 0.36 m apart, closer than head_separation_m, with a dip of more
    // than a head's height between them.
    leaning_person(&mut scene, 0.0, 0.0, 1.65, true, 0.12);
    leaning_person(&mut scene, 0.0, 0.6, 1.85, true, -0.12);
    // Their right forearms meet at chest height (a hand-over): one cluster.
    let (a, b) = ([0.22, 0.0, 1.1], [0.25, 0.6, 1.1]);
    scene.cylinder(a, b, 0.045, Class::LowerArms);
    let cfg = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    let found = find_boxes(&scene.cloud(false), &cfg).expect("boxes");
    // The higher top hid every lower one within head_separation_m: one person.
    assert_eq!(found.boxes.len(), 2, "{found:?}");
    let heads = [[0.0, 0.12, 1.55], [0.0, 0.48, 1.75]];
    for (k, head) in heads.iter().enumerate() {
        let holders: Vec<usize> = (0..2).filter(|&b| found.boxes[b].contains(*head)).collect();
        assert_eq!(holders.len(), 1, "head {k}: {found:?}");
    }
}

/// The true box (yaw 0) around the body-labelled points of `scene`: their extent along x
/// and y plus bodyseg-synth's 5 cm margin, from the floor up to the top plus the margin.
fn true_box_along_x(scene: &Scene) -> PersonBox {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (p, l) in scene.points.iter().zip(&scene.labels) {
        if l.class().is_some_and(|c| c.is_body()) {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
    }
    let top = hi[2] + 0.05;
    PersonBox {
        id: 0,
        center_m: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, top / 2.0],
        half_extents_m: [
            (hi[0] - lo[0]) / 2.0 + 0.05,
            (hi[1] - lo[1]) / 2.0 + 0.05,
            top / 2.0,
        ],
        yaw_rad: 0.0,
    }
}

#[test]
fn a_pointing_arm_does_not_turn_the_box() {
    let mut scene = Scene::default();
    scene.floor();
    // Facing +y, shoulders along x, the left arm hanging; the right arm points 45° to
    // the side and forward, slightly up (bodyseg-synth's "pointing").
    person(&mut scene, 0.0, 0.0, 1.72, false);
    let (shoulder, elbow, hand) = ([0.22, 0.0, 1.42], [0.45, 0.23, 1.46], [0.7, 0.48, 1.5]);
    scene.cylinder(shoulder, elbow, 0.045, Class::UpperArms);
    scene.cylinder(elbow, hand, 0.04, Class::LowerArms);
    scene.cylinder(
        [-0.22, 0.0, 1.42],
        [-0.24, 0.0, 0.86],
        0.045,
        Class::LowerArms,
    );
    let truth = true_box_along_x(&scene);
    let found = find_boxes(&scene.cloud(true), &BoxesConfig::default()).expect("boxes");
    assert_eq!(found.boxes.len(), 1, "{found:?}");
    let b = &found.boxes[0];
    // The box's sides follow the shoulders (yaw 0 modulo a quarter turn; tolerance:
    // a 3° error costs ≈ 3% of IoU here). Fitted on all voxels, the yaw turned 0.41 rad
    // towards the arm.
    let quarter = std::f32::consts::FRAC_PI_2;
    let off = b.yaw_rad.rem_euclid(quarter);
    assert!(off.min(quarter - off) < 0.05, "{b:?}");
    let iou = box_iou(&truth, b);
    assert!(iou > 0.85, "IoU {iou}: {b:?} vs {truth:?}");
}

/// A person at the origin facing +y whose right arm reaches forward with the elbow
/// hidden: the upper arm ends 0.3 m in front of the shoulder and the forearm starts
/// 0.25 m further on (no voxel in between, wider than `person_gap_m`). Returns the
/// hand's centre.
fn reaching_with_a_hidden_elbow(scene: &mut Scene) -> [f32; 3] {
    person(scene, 0.0, 0.0, 1.72, false);
    scene.cylinder(
        [0.22, 0.0, 1.42],
        [0.22, 0.3, 1.36],
        0.045,
        Class::UpperArms,
    );
    let hand = [0.22, 0.82, 1.26];
    scene.cylinder([0.22, 0.55, 1.31], hand, 0.04, Class::LowerArms);
    hand
}

#[test]
fn a_forearm_whose_elbow_is_hidden_stays_in_its_owner_s_box() {
    // Alone, the forearm was a cluster too small to be a person and was dropped.
    let mut scene = Scene::default();
    scene.floor();
    let hand = reaching_with_a_hidden_elbow(&mut scene);
    let found = find_boxes(&scene.cloud(true), &BoxesConfig::default()).expect("boxes");
    assert_eq!(found.boxes.len(), 1, "{found:?}");
    assert!(found.boxes[0].contains(hand), "{found:?}");

    // Its hand touching the chest of someone standing in front: the forearm joined their
    // cluster and went into their box.
    let mut scene = Scene::default();
    scene.floor();
    let hand = reaching_with_a_hidden_elbow(&mut scene);
    let other = person(&mut scene, 0.25, 1.05, 1.72, true);
    let found = find_boxes(&scene.cloud(true), &BoxesConfig::default()).expect("boxes");
    assert_eq!(found.boxes.len(), 2, "{found:?}");
    let (theirs, mine): (Vec<&PersonBox>, Vec<&PersonBox>) =
        found.boxes.iter().partition(|b| box_iou(&other, b) >= 0.5);
    assert_eq!((mine.len(), theirs.len()), (1, 1), "{found:?}");
    assert!(mine[0].contains(hand), "{found:?}");
    // The forearm's elbow end is not theirs.
    assert!(!theirs[0].contains([0.22, 0.6, 1.3]), "{found:?}");
}

#[test]
fn only_forearm_sized_lower_arm_pieces_are_fragments() {
    // Near a person with hanging arms: a streak labelled upper leg beside the chest (a
    // parser's mistake on flying pixels), and a 0.8 m bar labelled lower arm starting
    // beside the elbow (a robot link). Neither is a forearm: both stay out of the box.
    let mut scene = Scene::default();
    scene.floor();
    let truth = person(&mut scene, 0.0, 0.0, 1.72, true);
    let streak_end = [0.55, 0.0, 1.3];
    scene.cylinder([0.45, 0.0, 1.3], streak_end, 0.03, Class::UpperLegs);
    let bar_end = [0.0, -1.05, 1.1];
    scene.cylinder([0.25, -0.3, 1.1], bar_end, 0.04, Class::LowerArms);
    let found = find_boxes(&scene.cloud(true), &BoxesConfig::default()).expect("boxes");
    assert_eq!(found.boxes.len(), 1, "{found:?}");
    let b = &found.boxes[0];
    assert!(!b.contains(streak_end) && !b.contains(bar_end), "{b:?}");
    assert!(box_iou(&truth, b) > 0.8, "{b:?} vs {truth:?}");
}
