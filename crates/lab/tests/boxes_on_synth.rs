//! Issue 6's floor on synthetic recordings: in ≥ 98% of frames every true person is
//! matched by exactly one box with 3D IoU ≥ 0.5 (exact oriented-box IoU) and there is no
//! extra box — per preset and per mode (labels with the simulated parser's predicted
//! labels, DSA projection; geometry, labels unused). The quick test scores 4 frames per
//! preset (all must be good); the `#[ignore]`d one the report's 50 (2 seeds × 25 frames,
//! 4 apart; `cargo test --release -p bodyseg-lab --test boxes_on_synth -- --ignored`).
//! Frames are spread by `BODYSEG_BOXES_SEED` (default 100) for the quick test.

use bodyseg_lab::{BoxStats, box_stats, match_boxes, study_frame};
use bodyseg_people::{BoxMode, BoxesConfig, find_boxes};
use bodyseg_project::FrameProjector;
use bodyseg_synth::{Synth, preset};

fn configs() -> [BoxesConfig; 2] {
    [
        BoxesConfig::default(),
        BoxesConfig {
            mode: BoxMode::Geometry,
            ..BoxesConfig::default()
        },
    ]
}

/// Scores `frames` of each seed, per preset and mode, and asserts ≥ 98% good frames.
fn check(seeds: &[u64], frames: &[usize]) {
    for name in ["single", "handover", "robot_cell"] {
        let mut totals = vec![BoxStats::default(); 2];
        for &seed in seeds {
            let synth = Synth::new(preset(name).expect("preset"), seed).expect("synth");
            let stats = box_stats(&synth, frames, &configs()).expect("boxes");
            for (t, s) in totals.iter_mut().zip(&stats) {
                t.absorb(s, seed as usize * 10_000);
            }
        }
        for (cfg, s) in configs().iter().zip(&totals) {
            eprintln!(
                "{name} {}: {}/{} good frames, mean IoU {:.3}, bad (seed*10000+frame) {:?}",
                cfg.mode.name(),
                s.good_frames,
                s.frames,
                s.mean_iou(),
                s.bad_frames
            );
            assert!(
                s.good_fraction() >= 0.98,
                "{name} {}: {}/{} good frames (bad: {:?}; seeds {seeds:?})",
                cfg.mode.name(),
                s.good_frames,
                s.frames,
                s.bad_frames
            );
        }
    }
}

#[test]
fn boxes_match_the_truth_on_a_few_frames_of_each_preset() {
    let seed = std::env::var("BODYSEG_BOXES_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    check(&[seed], &[0, 12, 24, 36]);
}

#[test]
#[ignore = "slow (300 frames rendered and projected): run in release"]
fn boxes_match_the_truth_on_50_frames_of_each_preset() {
    let frames: Vec<usize> = (0..25).map(|i| i * 4).collect();
    check(&[100, 101], &frames);
}

#[test]
fn labels_mode_finds_people_whose_legs_the_cameras_miss() {
    // robot_cell seed 1201: the lowest labelled voxel of a crouching person (frame 8) is
    // 0.46 m high, and of a standing one behind the robot's base (frame 44) 0.53 m, above
    // the 0.45 m a person's feet may be: both were dropped as floating. A labelled body
    // (a head on top, a torso) may miss its legs up to half its height.
    let synth = Synth::new(preset("robot_cell").expect("preset"), 1201).expect("synth");
    let stats = box_stats(&synth, &[8, 44], &[BoxesConfig::default()]).expect("boxes");
    assert_eq!(
        stats[0].good_frames, 2,
        "bad frames {:?}",
        stats[0].bad_frames
    );
}

#[test]
fn geometry_mode_keeps_an_arm_reaching_along_a_robot_link_by_its_color() {
    // robot_cell seed 1101, frames 12, 20 and 60: a person beside the robot reaches
    // towards it, the forearm along the robot's forearm link. On positions alone the
    // robot's part, spreading from its pedestal, takes the arm (box IoU 0.48 and 0.46 in
    // frames 12 and 20); with the points' colours it spreads slowly through the person's
    // sleeve and skin colours, which the orange robot does not wear, and pays to step into
    // them from its own. (Frame 60 was lost with colours but without that penalty, IoU
    // 0.41: the link touches the whole arm.)
    let synth = Synth::new(preset("robot_cell").expect("preset"), 1101).expect("synth");
    let projector = FrameProjector::new(synth.written_rig()).expect("projector");
    let cfg = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    for index in [12, 20, 60] {
        let (frame, mut cloud) = study_frame(&synth, &projector, index).expect("frame");
        assert!(cloud.colors.is_some(), "the study's clouds carry colours");
        let with = find_boxes(&cloud, &cfg).expect("boxes");
        let m = match_boxes(&frame.boxes.boxes, &with.boxes);
        assert!(m.is_good(), "frame {index} with colours: {m:?}");
        cloud.colors = None;
        let without = find_boxes(&cloud, &cfg).expect("boxes");
        let m = match_boxes(&frame.boxes.boxes, &without.boxes);
        assert!(
            !m.is_good(),
            "frame {index}: good without colours too, {m:?}"
        );
    }
}

#[test]
fn geometry_mode_keeps_an_arm_reaching_a_neighbour_by_its_sleeve_color() {
    // robot_cell seed 403 frame 28 and handover seed 300 frames 0 and 72: a person's arm
    // reaches a neighbour's chest or arm below the head. Along the voxel graph its far end
    // is nearer the neighbour's head than its owner's, and went to the neighbour (a box
    // IoU of 0.49-0.50 in each frame, under the 0.5 needed); its sleeve is a colour only
    // its owner's column wears, so
    // the neighbour now spreads into it at three times the cost.
    for (name, seed, indices) in [("robot_cell", 403, &[28][..]), ("handover", 300, &[0, 72])] {
        let synth = Synth::new(preset(name).expect("preset"), seed).expect("synth");
        let projector = FrameProjector::new(synth.written_rig()).expect("projector");
        let cfg = BoxesConfig {
            mode: BoxMode::Geometry,
            ..BoxesConfig::default()
        };
        for &index in indices {
            let (frame, cloud) = study_frame(&synth, &projector, index).expect("frame");
            let found = find_boxes(&cloud, &cfg).expect("boxes");
            let m = match_boxes(&frame.boxes.boxes, &found.boxes);
            assert!(m.is_good(), "{name} {seed} frame {index}: {m:?}");
        }
    }
}
