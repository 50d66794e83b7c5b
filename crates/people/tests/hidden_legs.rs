//! Labels mode with a person whose legs the cameras miss (issue 6): a hand-made labelled
//! upper body floating above the floor (the legs hidden behind a robot's base or cut off
//! by unlabelled points) is a person; a blob a parser labelled head and torso with the
//! head below its arms (a robot part, as the bundled model labels one) is not.

mod common;

use bodyseg_core::{Class, Label};
use bodyseg_people::{BoxesConfig, find_boxes};
use common::Scene;

/// Labels-mode boxes of `scene` on a floor.
fn boxes(mut scene: Scene) -> usize {
    scene.floor();
    find_boxes(&scene.cloud(true), &BoxesConfig::default())
        .expect("boxes")
        .boxes
        .len()
}

#[test]
fn an_upper_body_without_legs_is_a_person_with_its_head_on_top() {
    // A 1.52 m person seen from the hips up: trunk 0.55–1.25 m, head on top, arms
    // hanging. Its lowest labelled voxel (0.55 m) is above max_bottom_m (0.45 m).
    let mut person = Scene::default();
    person.cylinder([0.0, 0.0, 0.55], [0.0, 0.0, 1.25], 0.15, Class::Torso);
    person.sphere([0.0, 0.0, 1.4], 0.1, Class::Head);
    let upper_arm = ([0.0, 0.2, 1.25], [0.0, 0.22, 0.95], 0.05);
    person.both_sides(&[upper_arm], Class::UpperArms);
    assert_eq!(boxes(person), 1);
    // The same parts stacked as a robot link the parser misread: torso, then head, then
    // forearm and upper arm above it. Its head lies 0.4 m below its top.
    let mut robot = Scene::default();
    robot.cylinder([0.0, 0.0, 0.5], [0.0, 0.0, 0.75], 0.12, Class::Torso);
    robot.sphere([0.0, 0.0, 0.85], 0.1, Class::Head);
    robot.cylinder([0.0, 0.0, 0.95], [0.0, 0.0, 1.15], 0.06, Class::LowerArms);
    robot.cylinder([0.0, 0.0, 1.15], [0.0, 0.0, 1.25], 0.06, Class::UpperArms);
    assert_eq!(boxes(robot), 0);
    // A floating arm with a held object is still no person.
    let mut arm = Scene::default();
    arm.cylinder([0.0, 0.0, 0.8], [0.3, 0.0, 1.2], 0.05, Class::LowerArms);
    arm.sphere([0.0, 0.0, 0.75], 0.1, Label::BACKGROUND);
    assert_eq!(boxes(arm), 0);
}
