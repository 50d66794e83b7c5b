//! Box finding on synthetic frames: the depth images of the three presets back-projected
//! into the world frame with the exact per-depth-pixel labels, scored against the true
//! boxes with the exact oriented IoU. (The pipeline's `boxes_on_synth` test does the same
//! with the simulated parser's predicted labels, through the projection.)

use bodyseg_core::{LabeledCloud, PersonBox, PersonBoxes};
use bodyseg_people::{BoxMode, BoxesConfig, PeopleError, box_iou, find_boxes, match_boxes};
use bodyseg_synth::{Synth, SynthFrame, preset};

fn cloud(synth: &Synth, frame: &SynthFrame) -> LabeledCloud {
    synth.truth_cloud(frame).expect("truth cloud")
}

#[test]
fn every_person_gets_one_box_in_both_modes() {
    for name in ["single", "handover", "robot_cell"] {
        let synth = Synth::new(preset(name).expect("preset"), 21).expect("synth");
        for index in [0, 9] {
            let frame = synth.frame(index);
            let cloud = cloud(&synth, &frame);
            for mode in [BoxMode::Labels, BoxMode::Geometry] {
                let cfg = BoxesConfig {
                    mode,
                    ..BoxesConfig::default()
                };
                let found = find_boxes(&cloud, &cfg).expect("boxes");
                let m = match_boxes(&frame.boxes.boxes, &found.boxes);
                assert!(
                    m.is_good(),
                    "{name} frame {index} {}: {m:?}, {found:?}",
                    mode.name()
                );
                // Deterministic: the same cloud gives the same boxes.
                assert_eq!(find_boxes(&cloud, &cfg).expect("boxes"), found);
            }
        }
    }
}

#[test]
fn bad_config_and_file_mode_are_errors() {
    let cloud = LabeledCloud::default();
    let cfg = BoxesConfig {
        voxel_m: -1.0,
        ..BoxesConfig::default()
    };
    let e = find_boxes(&cloud, &cfg).expect_err("invalid");
    assert_eq!(
        e.to_string(),
        "boxes.voxel_m must be in [0.01, 0.5] metres, got -1"
    );
    let cfg = BoxesConfig {
        mode: BoxMode::File,
        ..BoxesConfig::default()
    };
    assert!(matches!(
        find_boxes(&cloud, &cfg),
        Err(PeopleError::FileMode)
    ));
    // An empty cloud has no people.
    assert!(
        find_boxes(&cloud, &BoxesConfig::default())
            .expect("empty")
            .boxes
            .is_empty()
    );
    let geometry = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    assert!(
        find_boxes(&cloud, &geometry)
            .expect("empty")
            .boxes
            .is_empty()
    );
}

/// Geometry mode (no labels) on frames `indices` of the synthetic recording `name`, `seed`:
/// per frame, its index, the true boxes and the found ones.
fn found_without_labels(
    name: &str,
    seed: u64,
    indices: &[usize],
) -> Vec<(usize, Vec<PersonBox>, PersonBoxes)> {
    let synth = Synth::new(preset(name).expect("preset"), seed).expect("synth");
    let cfg = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    indices
        .iter()
        .map(|&index| {
            let frame = synth.frame(index);
            let found = find_boxes(&cloud(&synth, &frame), &cfg).expect("boxes");
            (index, frame.boxes.boxes, found)
        })
        .collect()
}

/// Geometry mode on frames `indices` of a synthetic recording: every true person is
/// matched by exactly one found box with IoU ≥ 0.5, one to one, and there is no other box
/// (the box study's good frame, [`match_boxes`]).
fn every_person_matched_once_without_labels(name: &str, seed: u64, indices: &[usize]) {
    for (index, truth, found) in found_without_labels(name, seed, indices) {
        let m = match_boxes(&truth, &found.boxes);
        assert!(
            m.is_good(),
            "{name} {seed} frame {index}: {m:?}, {truth:?} vs {found:?}"
        );
    }
}

/// Frames of synthetic recordings where geometry mode once got a box wrong, each with what
/// went wrong and what changed: (preset, seed, frames).
const ONCE_WRONG: &[(&str, u64, &[usize])] = &[
    // A pointing arm past a shorter head stays its owner's.
    // robot_cell seed 603: a 1.8 m person points past the head of a 1.6 m neighbour, the
    // arm at the neighbour's head height touching the side of their head. Split at equal
    // graph distance from the heads, the arm went to the neighbour (their box IoU ≈ 0.46,
    // the pointer's ≈ 0.48); leaving a head sideways at its height now costs a contact.
    ("robot_cell", 603, &[0, 16]),
    // A robot forearm passing a person is not in their box.
    // robot_cell seed 701: the robot's forearm passes a short person's elbow at chest
    // height and ends beside them. Split at equal cost from the robot's pedestal and the
    // person's head, the part beyond the contact was theirs (their box IoU 0.41 and 0.50);
    // what is nobody's now spreads at half the cost.
    ("robot_cell", 701, &[20, 60]),
    // A pointing arm resting on a neighbour's neck stays its owner's.
    // robot_cell seed 403 frame 32: a pointing arm reaches a taller neighbour's neck, just
    // below their head. Only leaving a head sideways within 0.2 m of its top paid the
    // contact penalty; the arm went to the neighbour (its owner's box IoU 0.43).
    ("robot_cell", 403, &[32]),
    // A crouching person whose head a neighbour's arm touches is found.
    // robot_cell seed 302 frames 44 and 48: a 1.88 m person's arm reaches down onto the
    // head of a neighbour crouching at 1.37 m. With the arm, 10% of the head candidate's
    // blob lay 0.31 m from its top, more than a robot joint's, and the crouching person
    // got no box; the arm rises to its owner's shoulder, so it is now left out of the
    // head test (the crouching person's trunk fills the column below).
    ("robot_cell", 302, &[44, 48]),
    // A tall head with a neighbour's arm on it is found.
    // robot_cell seed 603 frame 8 and seed 500 frame 68: a neighbour's arm lies on the
    // head of a 1.6 m person; a quarter of the head's blob lay 0.21 and 0.24 m from its
    // top, beyond the 0.2 m tall tops were allowed (now 0.25 m), and the person got no box.
    ("robot_cell", 603, &[8]),
    ("robot_cell", 500, &[68]),
    // A robot joint a person's arm touches is not a head.
    // robot_cell seed 702 frame 32: a person's hand rests on the robot's elbow. Their arm
    // rises to their shoulder, as an arm reaching onto a crouching head does; left out of
    // the elbow's head test, it made the elbow a compact top over the pedestal, and the
    // robot a person. A robot's joint stands on thin links: the arm stays in the test.
    ("robot_cell", 702, &[32]),
    // A crouching person with a neighbour's hand lying on the head is found.
    // robot_cell seed 302 frames 36 and 56: a 1.88 m person's hand lies beside and a
    // little above the head of a neighbour crouching at 1.37 m, 0.2 m from its top. The
    // hand's top hid the head's (two heads' tops are 0.25 m apart), and the crouching
    // person got no box. A limb lying on the head no longer hides it.
    ("robot_cell", 302, &[36, 56]),
    // Tops under a limb that are not heads stay hidden.
    // A robot's base under its own upper arm (robot_cell seed 100 frame 12, 0.96 m high:
    // below the 1.0 m a crouching head reaches), and a person's shoulder under a
    // neighbour's hand 0.32 m from their own head (handover seed 800 frame 68): both
    // tops are hidden by a link rising from them, and each became an extra person when
    // any such top was unhidden.
    ("robot_cell", 100, &[12]),
    ("handover", 800, &[68]),
    // A person crouching at 1.1 m under a neighbour's limb is found.
    // robot_cell seed 902 frames 36-44 and seed 1100 frame 56: a person crouches at
    // 1.35 m beside a taller neighbour whose arm reaches over them, and the top that
    // is theirs (1.10 m) was below the 1.2 m under which a top hidden by a limb stayed
    // hidden: they got no box. Hands held before a chest, which that height kept out, are
    // now kept out by their size.
    ("robot_cell", 902, &[36, 40, 44]),
    ("robot_cell", 1100, &[56]),
    // A hand held out over its owner's body is not a head.
    // handover seed 1201 frames 52-60 and seed 503 frame 16: a hand held out before the
    // chest stands over its owner's body column, compact, as a head does, but its blob is
    // half a head's: 15-17 voxels (1201), 15 (503), against 38 and more for heads. The hand
    // was a person.
    ("handover", 1201, &[52, 56, 60]),
    ("handover", 503, &[16]),
    // What stands under 1 m is not a person.
    // robot_cell seed 1502 frame 12 and seed 1102 frame 28: a storage box and the robot's
    // shoulder on its pedestal passed every test of a person down to 0.9 m, as a crouching
    // adult (1.05 m and up) does, and got a box (0.95 and 0.96 m high, margin included).
    ("robot_cell", 1502, &[12]),
    ("robot_cell", 1102, &[28]),
    // Two people close face to face get boxes along the line between their heads.
    // handover seed 802: two people 0.54 m apart hand something over. The cameras see an
    // arc of the taller one's trunk, whose axis was 24° off (box IoU 0.49–0.50 in 13 of
    // 25 frames of the box study); the line between the heads gives the yaw.
    ("handover", 802, &[0, 12, 20]),
];

#[test]
fn every_person_is_matched_once_on_frames_once_wrong_without_labels() {
    for &(name, seed, indices) in ONCE_WRONG {
        every_person_matched_once_without_labels(name, seed, indices);
    }
}

#[test]
fn a_walking_person_s_box_follows_their_trunk_without_labels() {
    // single seed 800: a person walking. Their box's yaw follows the trunk (hips to
    // chest, beside the head's vertical), not all of them: the striding legs lie along
    // the facing direction, the shoulders across it. IoU 0.70, 0.75, 0.74 on all the
    // voxels, 0.77, 0.82, 0.78 on the trunk.
    for (index, truth, found) in found_without_labels("single", 800, &[0, 20, 40]) {
        let [truth] = truth.as_slice() else {
            panic!("one person in single");
        };
        let [b] = found.boxes.as_slice() else {
            panic!("frame {index}: one box, got {found:?}");
        };
        let iou = box_iou(truth, b);
        assert!(
            iou >= 0.76,
            "frame {index}: IoU {iou:.3}: {truth:?} vs {b:?}"
        );
    }
}
