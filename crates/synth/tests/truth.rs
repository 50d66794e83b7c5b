//! The synthetic ground truth is exact: depth pixels lie on the surface they are
//! labelled with, true boxes hold their people, colour and depth views agree, the
//! prediction equals the truth without errors, and the same seed gives the same frame.

use bodyseg_calib::{Pose, RgbdCamera};
use bodyseg_core::Class;
use bodyseg_synth::parser_mistakes::mismatch_fraction;
use bodyseg_synth::render::surface_distance;
use bodyseg_synth::{NO_SURFACE, ParserMistakesConfig, SceneConfig, Synth, preset};

/// World point of depth pixel `i` of `camera` at depth `mm`, with the true rig.
fn world_point(camera: &RgbdCamera, i: usize, mm: u16) -> Option<[f32; 3]> {
    let w = camera.depth.width as usize;
    let (u, v) = ((i % w) as f64, (i / w) as f64);
    let ray = camera.depth.unproject(u, v)?;
    let z = f64::from(mm) / 1000.0;
    let p = transform(&camera.world_from_depth, [ray[0] * z, ray[1] * z, z]);
    Some([p[0] as f32, p[1] as f32, p[2] as f32])
}

fn transform(pose: &Pose, p: [f64; 3]) -> [f64; 3] {
    pose.transform_point(p)
}

/// σ of the depth noise at `z_m` for the default faults (1 mm at 1 m, ∝ z²).
fn sigma_m(z_m: f32) -> f32 {
    0.001 * z_m * z_m
}

fn synth(name: &str, seed: u64) -> Synth {
    Synth::new(preset(name).expect("preset"), seed).expect("synth")
}

#[test]
fn depth_pixels_lie_on_a_surface_of_their_labelled_class_and_person() {
    for (name, seed) in [("single", 3), ("handover", 1), ("robot_cell", 2)] {
        let synth = synth(name, seed);
        let index = 4;
        let frame = synth.frame(index);
        let t = synth.time_s(index);
        let people = synth.person_primitives_at(t);
        let mut checked = 0usize;
        let mut worst = 0.0f32;
        for (camera, images) in synth.true_rig().cameras.iter().zip(&frame.cameras) {
            for (i, &mm) in images.depth_mm.iter().enumerate() {
                let person = images.depth_person[i];
                if mm == 0 || person == 0 || images.flying[i] {
                    continue;
                }
                let label = images.depth_labels[i];
                let p = world_point(camera, i, mm).expect("ray");
                // Distance to the nearest primitive of that person with that class.
                let d = people[usize::from(person) - 1]
                    .iter()
                    .filter(|prim| prim.owner.class_id() == label)
                    .map(|prim| surface_distance(&prim.shape, p).abs())
                    .fold(f32::INFINITY, f32::min);
                // 5 σ of the noise (one miss in ~3 million) + 0.5 mm quantisation +
                // f32 rounding; at grazing angles the depth error maps to a surface
                // distance no larger than itself.
                let z = f32::from(mm) / 1000.0;
                let tolerance = 5.0 * sigma_m(z) + 0.0006;
                assert!(
                    d <= tolerance,
                    "{name}: camera {} pixel {i}: {d} m from the nearest {:?} of person {person} (tolerance {tolerance})",
                    camera.name,
                    Class::from_id(label)
                );
                worst = worst.max(d / tolerance);
                checked += 1;
            }
        }
        assert!(checked > 5_000, "{name}: only {checked} person pixels");
        eprintln!("{name}: {checked} person depth pixels, worst = {worst:.2} of tolerance");
    }
}

#[test]
fn true_boxes_hold_their_people() {
    for (name, seed) in [("single", 5), ("handover", 1), ("robot_cell", 2)] {
        let synth = synth(name, seed);
        for index in [0, 7] {
            let frame = synth.frame(index);
            assert_eq!(frame.boxes.boxes.len(), synth.people().len());
            for b in &frame.boxes.boxes {
                let test = b.test();
                let (mut inside, mut total, mut inside_all, mut total_all) = (0, 0, 0, 0);
                for (camera, images) in synth.true_rig().cameras.iter().zip(&frame.cameras) {
                    for (i, &mm) in images.depth_mm.iter().enumerate() {
                        if mm == 0 || u32::from(images.depth_person[i]) != b.id {
                            continue;
                        }
                        let p = world_point(camera, i, mm).expect("ray");
                        let hit = test.contains(p);
                        total_all += 1;
                        inside_all += usize::from(hit);
                        if !images.flying[i] {
                            total += 1;
                            inside += usize::from(hit);
                        }
                    }
                }
                assert!(
                    total > 500,
                    "{name} frame {index} box {}: {total} points",
                    b.id
                );
                let frac = inside as f64 / total as f64;
                let frac_all = inside_all as f64 / total_all as f64;
                eprintln!(
                    "{name} frame {index} box {}: {:.4} of {total} points inside ({:.4} with flying pixels)",
                    b.id, frac, frac_all
                );
                assert!(frac >= 0.99, "{name} frame {index} box {}: {frac}", b.id);
            }
        }
    }
}

/// The colour camera is rendered from its own pose (5 cm beside the depth sensor): away
/// from silhouettes, a depth point projected into the colour image with the true rig
/// finds the same class there.
#[test]
fn color_and_depth_truth_agree_through_the_true_rig() {
    let synth = synth("handover", 1);
    let frame = synth.frame(2);
    for (camera, images) in synth.true_rig().cameras.iter().zip(&frame.cameras) {
        let (mut same, mut total) = (0usize, 0usize);
        let w = camera.depth.width as usize;
        for (i, &mm) in images.depth_mm.iter().enumerate() {
            let label = images.depth_labels[i];
            if mm == 0 || images.depth_person[i] == 0 || images.flying[i] {
                continue;
            }
            // Skip pixels at a label or depth edge in the depth image.
            let (u, v) = (i % w, i / w);
            if u == 0 || v == 0 || u + 1 >= w || v + 1 >= camera.depth.height as usize {
                continue;
            }
            let edge = [i - 1, i + 1, i - w, i + w].iter().any(|&j| {
                images.depth_labels[j] != label
                    || (f32::from(images.depth_mm[j]) - f32::from(mm)).abs() > 30.0
            });
            if edge {
                continue;
            }
            let ray = camera.depth.unproject(u as f64, v as f64).expect("ray");
            let z = f64::from(mm) / 1000.0;
            let pc = camera
                .color_from_depth
                .transform_point([ray[0] * z, ray[1] * z, z]);
            let Some([uc, vc]) = camera.color.project(pc) else {
                continue;
            };
            let (uc, vc) = (uc.round(), vc.round());
            if uc < 0.0
                || vc < 0.0
                || uc >= f64::from(camera.color.width)
                || vc >= f64::from(camera.color.height)
            {
                continue;
            }
            let j = vc as usize * camera.color.width as usize + uc as usize;
            total += 1;
            same += usize::from(images.labels[j] == label);
        }
        let frac = same as f64 / total.max(1) as f64;
        eprintln!(
            "{}: {same}/{total} interior person points agree",
            camera.name
        );
        assert!(total > 1000, "{}: {total}", camera.name);
        // Occlusion between the two sensors and thin parts give a small residue.
        assert!(frac > 0.97, "{}: {frac}", camera.name);
    }
}

#[test]
fn no_errors_means_prediction_equals_truth_and_defaults_err_as_configured() {
    let mut config = preset("handover").expect("preset");
    config.parsing = ParserMistakesConfig::none();
    let exact = Synth::new(config, 1).expect("synth").frame(3);
    for c in &exact.cameras {
        assert_eq!(c.parsing, c.labels);
    }
    let noisy = synth("handover", 1).frame(3);
    for c in &noisy.cameras {
        let m = mismatch_fraction(&c.labels, &c.parsing);
        eprintln!(
            "default parsing errors: {:.3} of person pixels mislabelled",
            m
        );
        // ParserMistakesConfig's defaults aim at an SCHP-like 5-30% on people pixels.
        assert!((0.03..0.35).contains(&m), "{m}");
    }
}

#[test]
fn same_seed_same_frame_other_seed_other_people() {
    let a = synth("handover", 7).frame(5);
    let b = synth("handover", 7).frame(5);
    assert_eq!(a, b);
    let c = synth("handover", 8).frame(5);
    assert_ne!(a.boxes, c.boxes);
    assert_ne!(a.cameras[0].depth_mm, c.cameras[0].depth_mm);
}

#[test]
fn depth_has_kinect_like_faults_and_truth_marks_them() {
    let synth = synth("robot_cell", 2);
    let frame = synth.frame(1);
    let (mut flying, mut valid, mut missing_on_surface) = (0usize, 0usize, 0usize);
    for c in &frame.cameras {
        for i in 0..c.depth_mm.len() {
            if c.depth_mm[i] > 0 {
                valid += 1;
                assert!(c.depth_mm[i] >= 500 && c.depth_mm[i] <= 4500);
                assert_ne!(c.depth_labels[i], NO_SURFACE);
            } else if c.depth_labels[i] != NO_SURFACE {
                missing_on_surface += 1;
            }
            flying += usize::from(c.flying[i]);
        }
    }
    eprintln!("valid {valid}, flying {flying}, missing on a surface {missing_on_surface}");
    assert!(valid > 200_000, "{valid}");
    assert!(flying > 100, "{flying}");
    assert!(missing_on_surface > 1000, "{missing_on_surface}");
}

#[test]
fn color_exposure_offset_moves_people_in_color_only() {
    let base = preset("single").expect("preset");
    let mut late = base.clone();
    late.dsa.color_time_offset_s = 0.1;
    late.people.poses = vec!["walking".into()];
    let mut still = base;
    still.people.poses = vec!["walking".into()];
    let a = Synth::new(still, 4).expect("synth").frame(2);
    let b = Synth::new(late, 4).expect("synth").frame(2);
    assert_eq!(a.cameras[0].depth_mm, b.cameras[0].depth_mm);
    assert_ne!(a.cameras[0].labels, b.cameras[0].labels);
}

#[test]
fn bad_scene_configs_name_the_field() {
    for (text, field) in [
        ("[rig]\ncameras = 0", "rig.cameras"),
        (
            "[scene]\nboxes = 1\nroom_half_m = -2.0",
            "scene.room_half_m",
        ),
        ("[people]\ncount = 9", "people.count"),
        ("[people]\nunknown_key = 1", "unknown_key"),
    ] {
        let e = SceneConfig::from_toml(text).expect_err(text).to_string();
        assert!(e.contains(field), "{text}: {e}");
    }
}

#[test]
fn frames_do_not_depend_on_the_thread_count() {
    let synth = synth("robot_cell", 3);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| synth.frame(2));
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .expect("pool")
        .install(|| synth.frame(2));
    assert_eq!(one, three);
}
