//! Unit tests of `blazepose`.

use super::bone::*;
use super::decode::*;
use super::figure::{sure_pose, upright_figure_xy};
use super::label::*;
use super::landmark;
use super::model::*;
use super::roi::*;
use crate::segmenter::PixelBox;
use bodyseg_core::RgbImage;

// Tolerance for coordinate round trips: a few ulps of values ~ 1e2.
const EPS: f64 = 1e-9;

#[test]
fn roi_round_trip_and_centre() {
    let roi = Roi {
        centre_px: [100.0, 50.0],
        side_px: 80.0,
        angle_rad: 0.7,
    };
    for t in [[0.0, 0.0], [128.0, 128.0], [200.5, 31.25]] {
        let back = roi.image_to_tensor(roi.tensor_to_image(t));
        assert!((back[0] - t[0]).abs() < EPS && (back[1] - t[1]).abs() < EPS);
    }
    let c = roi.tensor_to_image([128.0, 128.0]);
    assert!((c[0] - 100.0).abs() < EPS && (c[1] - 50.0).abs() < EPS);
}

#[test]
fn alignment_roi_points_up() {
    let roi = Roi::from_alignment([50.0, 100.0], [50.0, 60.0], 1.5);
    assert!((roi.side_px - 120.0).abs() < EPS);
    assert!(roi.angle_rad.abs() < EPS);
    // head to the right: the ROI's up axis is +x
    let roi = Roi::from_alignment([50.0, 100.0], [90.0, 100.0], 1.0);
    let (_, down) = roi.axes();
    assert!((down[0] + 1.0).abs() < EPS && down[1].abs() < EPS);
}

#[test]
fn distances() {
    assert!((segment_distance([5.0, 5.0], [0.0, 0.0], [10.0, 0.0]) - 5.0).abs() < EPS);
    assert!((segment_distance([12.0, 0.0], [0.0, 0.0], [10.0, 0.0]) - 2.0).abs() < EPS);
    let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
    assert_eq!(polygon_distance([5.0, 5.0], &sq), 0.0);
    assert!((polygon_distance([12.0, 5.0], &sq) - 2.0).abs() < EPS);
}

#[test]
fn crop_of_a_uniform_image_is_uniform_and_replicates_the_border() {
    let img = RgbImage::new(4, 3, [10u8, 20, 30].repeat(12)).expect("4x3x3 bytes");
    // a ROI mostly outside the image: the border pixels are replicated
    let roi = Roi {
        centre_px: [-50.0, -50.0],
        side_px: 40.0,
        angle_rad: 0.3,
    };
    let t = crop(&img, &roi, 8);
    for px in t.chunks_exact(3) {
        assert!((px[0] - 10.0 / 255.0).abs() < 1e-6 && (px[2] - 30.0 / 255.0).abs() < 1e-6);
    }
}

/// A crop blanked outside a box: the tensor pixels whose centres map outside it are the
/// value given, the others keep the image's colour.
#[test]
fn a_blanked_crop_sees_only_the_box() {
    let img = RgbImage::new(40, 40, [200u8, 100, 50].repeat(1600)).expect("40x40x3 bytes");
    // ROI = the image, 8×8 crop: tensor pixel i covers image columns 5i..5i+5
    let roi = Roi {
        centre_px: [19.5, 19.5],
        side_px: 40.0,
        angle_rad: 0.0,
    };
    let mut t = crop(&img, &roi, 8);
    let keep = PixelBox {
        x0: 10.0,
        y0: 0.0,
        x1: 39.0,
        y1: 19.0,
    };
    blank_outside(&mut t, &roi, 8, &keep, 0.0);
    for j in 0..8 {
        for i in 0..8 {
            // pixel centre in the image: 5i + 2, 5j + 2
            let (x, y) = (5 * i + 2, 5 * j + 2);
            let inside = (10..=39).contains(&x) && (0..=19).contains(&y);
            let r = t[(j * 8 + i) * 3];
            if inside {
                assert!((r - 200.0 / 255.0).abs() < 1e-6, "({i}, {j}) kept");
            } else {
                assert_eq!(r, 0.0, "({i}, {j}) blanked");
            }
        }
    }
}

#[test]
fn heatmap_moves_a_landmark_to_its_peak() {
    let mut heat = vec![-20.0f32; HEATMAP * HEATMAP * NUM_LANDMARKS];
    // landmark 11's peak at cell (row 10, col 12)
    heat[(10 * HEATMAP + 12) * NUM_LANDMARKS + 11] = 20.0;
    let mut lm = vec![[0.0; 5]; NUM_LANDMARKS];
    lm[11] = [45.0, 38.0, 0.0, 0.0, 0.0]; // cell (row 9, col 11): within the kernel
    lm[12] = [45.0, 38.0, 0.0, 0.0, 0.0]; // its heatmap is flat and low: unchanged
    refine_from_heatmap(&mut lm, &heat, 7, 0.5);
    assert!((lm[11][0] - 12.5 * 4.0).abs() < 1e-3 && (lm[11][1] - 10.5 * 4.0).abs() < 1e-3);
    assert_eq!(lm[12][0], 45.0);
}

#[test]
fn a_mirrored_run_comes_back_to_the_unmirrored_crop() {
    // Every pixel and channel distinct: mirroring twice is the identity, once moves
    // column i to column 255 − i.
    let mut crop: Vec<f32> = (0..INPUT * INPUT * 3).map(|k| k as f32).collect();
    let original = crop.clone();
    mirror_crop(&mut crop, INPUT);
    assert_eq!(crop[3 * (INPUT - 1) + 2], original[2]);
    mirror_crop(&mut crop, INPUT);
    assert_eq!(crop, original);
    // The mirror shows a person's left shoulder (11) where the right (12) was: a run on
    // the mirrored crop that puts landmark 12 at x = 100 means landmark 11 at 256 − 100.
    let mut landmarks = vec![0.0f32; NUM_LANDMARKS * 5];
    landmarks[12 * 5..12 * 5 + 5].copy_from_slice(&[100.0, 40.0, -3.0, 1.5, 2.5]);
    landmarks[0] = 128.5; // the nose stays the nose
    let mask: Vec<f32> = (0..INPUT * INPUT).map(|k| (k % INPUT) as f32).collect();
    let heat: Vec<f32> = (0..HEATMAP * HEATMAP * NUM_LANDMARKS)
        .map(|k| k as f32)
        .collect();
    let [l, m, h] = unmirror_outputs(&landmarks, &mask, &heat);
    assert_eq!(&l[11 * 5..11 * 5 + 5], &[156.0, 40.0, -3.0, 1.5, 2.5]);
    assert_eq!(l[12 * 5], 256.0); // landmark 11's x = 0 of the mirrored run
    assert_eq!(l[0], 127.5);
    assert_eq!(m[0], (INPUT - 1) as f32);
    // heatmap cell (row 0, col 0) of landmark 11 = the mirrored run's (0, 63) of 12
    assert_eq!(h[11], heat[(HEATMAP - 1) * NUM_LANDMARKS + 12]);
    for i in 0..NUM_LANDMARKS {
        assert_eq!(mirrored_landmark(mirrored_landmark(i)), i);
    }
    let [l2, m2, h2] = unmirror_outputs(&l, &m, &h);
    assert_eq!((l2, m2, h2), (landmarks, mask, heat));
    // Short buffers (a malformed model) come back as they are, without a panic.
    let [l3, m3, h3] = unmirror_outputs(&[1.0], &[2.0], &[]);
    assert_eq!((l3, m3, h3), (vec![1.0], vec![2.0], vec![]));
}

#[test]
fn a_pose_and_its_mirrored_run_average_their_masks_only() {
    let pose = figure();
    let mut mirrored = sure_pose(
        upright_figure_xy(),
        [50.0, 80.0],
        160.0,
        vec![0.5; INPUT * INPUT],
    );
    mirrored.xy[landmark::LEFT_ELBOW][0] += 10.0;
    let mean = average_masks(&pose, &mirrored);
    assert!(mean.mask.iter().all(|&m| m == 0.75));
    assert_eq!(mean.xy, pose.xy, "landmarks stay the first run's");
    // Another ROI: not the same crop, nothing to average.
    mirrored.roi.side_px += 1.0;
    assert_eq!(average_masks(&pose, &mirrored), pose);
}

/// An upright figure (image px), mask 1 everywhere.
fn figure() -> DecodedPose {
    sure_pose(
        upright_figure_xy(),
        [50.0, 80.0],
        160.0,
        vec![1.0; INPUT * INPUT],
    )
}

#[test]
fn each_bone_labels_its_pixels() {
    let pose = figure();
    let p = label_person(&pose, &RuleConfig::default(), 100, 160).expect("in the image");
    let at = |u: usize, v: usize| p.class[(v - p.v0) * (p.u1 - p.u0) + (u - p.u0)];
    assert_eq!(at(50, 25), 1, "head");
    assert_eq!(at(50, 60), 2, "torso");
    assert_eq!(at(65, 50), 3, "upper arm");
    assert_eq!(at(71, 70), 4, "lower arm");
    assert_eq!(at(58, 95), 5, "upper leg");
    assert_eq!(at(42, 125), 6, "lower leg");
    assert!(p.prob.iter().all(|&x| (0.0..=1.0).contains(&x)));
    // the probability is lowest on a border between two parts
    let k_mid = (60 - p.v0) * (p.u1 - p.u0) + (50 - p.u0);
    let k_edge = (52 - p.v0) * (p.u1 - p.u0) + (64 - p.u0);
    assert!(p.prob[k_edge] < p.prob[k_mid]);
}

/// The Python reference (scripts/blazepose_prototype.py) on the same figure with a
/// graded mask: tests/data/blazepose_rule_golden.json.
#[test]
fn matches_the_python_reference() {
    let golden: serde_json::Value =
        serde_json::from_str(include_str!("../../tests/data/blazepose_rule_golden.json"))
            .expect("golden JSON parses");
    let mut pose = figure();
    for j in 0..INPUT {
        for i in 0..INPUT {
            let (tx, ty) = (i as f64 + 0.5, j as f64 + 0.5);
            let m = 1.2 - ((tx - 128.0) / 70.0).hypot((ty - 128.0) / 120.0);
            pose.mask[j * INPUT + i] = m.clamp(0.0, 1.0) as f32;
        }
    }
    // The reference has round shoulders, no thighs past the frame and no depth order (all
    // added later).
    let cfg = RuleConfig {
        flat_shoulders: false,
        thighs_past_frame: false,
        behind_torso_depth: f64::INFINITY,
        hand_extend: 0.0,
        ..RuleConfig::default()
    };
    let p = label_person(&pose, &cfg, 100, 160).expect("in the image");
    let field = |k: &str| golden[k].as_u64().expect("window bound") as usize;
    assert_eq!(
        (p.u0, p.u1, p.v0, p.v1),
        (field("u0"), field("u1"), field("v0"), field("v1"))
    );
    let want: Vec<u8> = golden["classes"]
        .as_str()
        .expect("classes string")
        .bytes()
        .map(|b| b - b'0')
        .collect();
    let probs: Vec<f64> = golden["probs"]
        .as_array()
        .expect("probs")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect();
    assert_eq!(want.len(), p.class.len());
    let same = want.iter().zip(&p.class).filter(|(a, b)| a == b).count();
    // Pixels exactly on a border between two bones may tie differently in f64 vs
    // numpy's summation order: allow 0.2 % of the window.
    assert!(
        same * 1000 >= want.len() * 998,
        "{same} of {} agree",
        want.len()
    );
    for k in 0..want.len() {
        // On the person's pixels; elsewhere the prototype writes 0 where this gives
        // the background's probability (1 − mask).
        if want[k] == p.class[k] && want[k] != 0 {
            // golden probabilities are rounded to 5 decimals
            assert!((probs[k] - f64::from(p.prob[k])).abs() < 1e-4, "pixel {k}");
        }
    }
}

#[test]
fn legs_out_of_frame_are_not_invented() {
    use landmark::*;
    let mut pose = figure();
    for i in [LEFT_KNEE, RIGHT_KNEE, LEFT_ANKLE, RIGHT_ANKLE] {
        pose.presence[i] = 0.1;
    }
    let classes: Vec<u8> = bones(&pose, &RuleConfig::default(), 100, 160)
        .iter()
        .map(|b| b.class)
        .collect();
    assert!(!classes.contains(&5) && !classes.contains(&6));
    assert!(classes.contains(&2) && classes.contains(&4));
}

/// The class `label_person` gives pixel (u, v) of the upright figure (mask 1) in a
/// `width`×`height` image under `cfg`.
fn class_at(
    pose: &DecodedPose,
    cfg: &RuleConfig,
    (width, height): (usize, usize),
    u: usize,
    v: usize,
) -> u8 {
    let p = label_person(pose, cfg, width, height).expect("in the image");
    p.class[(v - p.v0) * (p.u1 - p.u0) + (u - p.u0)]
}

/// Just above the left shoulder (60, 40) and toward the neck the torso wins with flat
/// shoulders, the upper arm with round ones; beside the shoulder, outward, the arm keeps it.
#[test]
fn the_top_of_the_shoulder_is_torso_beside_it_arm() {
    let pose = figure();
    let flat = RuleConfig::default();
    let round = RuleConfig {
        flat_shoulders: false,
        ..flat
    };
    assert!(flat.flat_shoulders, "the default");
    assert_eq!(class_at(&pose, &round, (100, 160), 58, 37), 3);
    assert_eq!(class_at(&pose, &flat, (100, 160), 58, 37), 2);
    assert_eq!(class_at(&pose, &flat, (100, 160), 63, 38), 3);
    // the right shoulder (40, 40), mirrored
    assert_eq!(class_at(&pose, &flat, (100, 160), 42, 37), 2);
    assert_eq!(class_at(&pose, &flat, (100, 160), 37, 38), 3);
    // along the arm, below the shoulder, nothing changes
    assert_eq!(class_at(&pose, &flat, (100, 160), 65, 50), 3);
}

/// A seated person seen to the waist: the knees (y 110) lie below an image 100 px high,
/// with a low presence. The thighs are labelled from the hips (y 80) toward them, with no
/// lower legs; not when the hips are within a thigh radius of the edge (the person cut at
/// the hips), nor when the knees are inside the image (occluded, not out of frame), nor when
/// the knees' visibility is low (hidden).
#[test]
fn thighs_run_from_the_hips_to_knees_below_the_frame() {
    use landmark::*;
    let mut pose = figure();
    for i in [LEFT_KNEE, RIGHT_KNEE, LEFT_ANKLE, RIGHT_ANKLE] {
        pose.presence[i] = 0.1;
    }
    let cfg = RuleConfig::default();
    let classes = |cfg: &RuleConfig, height: usize| -> Vec<u8> {
        bones(&pose, cfg, 100, height)
            .iter()
            .map(|b| b.class)
            .collect()
    };
    let seated = classes(&cfg, 100);
    assert_eq!(seated.iter().filter(|&&c| c == 5).count(), 2, "{seated:?}");
    assert!(!seated.contains(&6));
    assert_eq!(class_at(&pose, &cfg, (100, 100), 58, 95), 5);
    let off = RuleConfig {
        thighs_past_frame: false,
        ..cfg
    };
    assert!(!classes(&off, 100).contains(&5));
    assert_ne!(class_at(&pose, &off, (100, 100), 58, 95), 5);
    // body scale 40 px, thigh radius 0.2 × 40 = 8 px: hips at y 80 are 4.5 px inside an
    // image 85 px high
    assert!(!classes(&cfg, 85).contains(&5), "cut at the hips");
    assert!(!classes(&cfg, 160).contains(&5), "knees in the frame");
    for i in [LEFT_KNEE, RIGHT_KNEE] {
        pose.visibility[i] = 0.1;
    }
    let hidden: Vec<u8> = bones(&pose, &cfg, 100, 100)
        .iter()
        .map(|b| b.class)
        .collect();
    assert!(!hidden.contains(&5), "knees hidden (below a table)");
}

/// The left forearm crosses the torso, elbow (70, 60) to wrist (52, 70): in front of the
/// torso (depth as the torso's) it is labelled over it; half a body scale (20 px) behind the
/// torso, the torso is; with `behind_torso_depth` off, the arm again.
#[test]
fn an_arm_behind_the_torso_gives_way_to_it() {
    use landmark::*;
    let mut pose = figure();
    pose.xy[LEFT_WRIST] = [52.0, 70.0];
    for &i in &LEFT_HAND {
        pose.xy[i] = [50.0, 71.0];
    }
    let cfg = RuleConfig::default();
    assert_eq!(class_at(&pose, &cfg, (100, 160), 55, 68), 4, "in front");
    for i in [LEFT_SHOULDER, LEFT_ELBOW, LEFT_WRIST] {
        pose.depth_px[i] = 20.0;
    }
    assert_eq!(class_at(&pose, &cfg, (100, 160), 55, 68), 2, "behind");
    let off = RuleConfig {
        behind_torso_depth: f64::INFINITY,
        ..cfg
    };
    assert_eq!(class_at(&pose, &off, (100, 160), 55, 68), 4, "off");
    // beside the torso, on the upper arm, the arm keeps its pixels
    assert_eq!(class_at(&pose, &cfg, (100, 160), 66, 50), 3);
}

/// The lower arm runs past the hand points (knuckles) by `hand_extend` × (hand − wrist):
/// left wrist (72, 78), hand points (72, 84), so the polyline ends at (72, 87) with 0.5.
#[test]
fn the_lower_arm_reaches_past_the_knuckles() {
    let pose = figure();
    let end_of_left_forearm = |cfg: &RuleConfig| {
        let bl = bones(&pose, cfg, 100, 160);
        let forearm = bl
            .iter()
            .find(|b| {
                b.class == 4
                    && matches!(&b.shape, BoneShape::Polyline(pts) if pts[0] == [70.0, 60.0])
            })
            .expect("the left forearm");
        match &forearm.shape {
            BoneShape::Polyline(pts) => *pts.last().expect("points"),
            BoneShape::Quad(_) => unreachable!("a forearm is a polyline"),
        }
    };
    let cfg = RuleConfig::default();
    assert_eq!(cfg.hand_extend, 0.5);
    let end = end_of_left_forearm(&cfg);
    assert!(
        (end[0] - 72.0).abs() < EPS && (end[1] - 87.0).abs() < EPS,
        "{end:?}"
    );
    let end = end_of_left_forearm(&RuleConfig {
        hand_extend: 0.0,
        ..cfg
    });
    assert!((end[1] - 84.0).abs() < EPS, "{end:?}");
}

/// A person of two pixels, columns `u0` and `u0 + 1` of row 0, depth unknown.
fn two_pixels(u0: usize, class: [u8; 2], prob: [f32; 2], score: [f32; 2]) -> PersonLabels {
    PersonLabels {
        u0,
        u1: u0 + 2,
        v0: 0,
        v1: 1,
        class: class.to_vec(),
        prob: prob.to_vec(),
        score: score.to_vec(),
        depth_m: None,
    }
}

#[test]
fn no_mask_no_person_and_merge_takes_the_nearer_bone() {
    let mut pose = figure();
    pose.mask = vec![0.0; INPUT * INPUT];
    let empty = label_person(&pose, &RuleConfig::default(), 100, 160).expect("window");
    assert!(empty.class.iter().all(|&c| c == 0));

    let a = two_pixels(0, [1, 2], [0.9, 0.8], [0.5, 2.0]);
    let b = two_pixels(1, [3, 4], [0.7, 0.6], [1.0, 1.0]);
    let img = merge_people(4, 1, &[a.clone(), b.clone()]);
    let ids: Vec<u8> = img.labels.iter().map(|l| l.id()).collect();
    assert_eq!(ids, vec![1, 3, 4, 0]);
    // Outside every person: background, certain.
    assert_eq!(img.probs, Some(vec![0.9, 0.7, 0.6, 1.0]));

    // The person in front wins the overlap even with the farther bone...
    let front = PersonLabels {
        depth_m: Some(2.0),
        ..b.clone()
    };
    let behind = PersonLabels {
        depth_m: Some(3.0),
        ..a.clone()
    };
    let img = merge_people(4, 1, &[behind.clone(), front.clone()]);
    let ids: Vec<u8> = img.labels.iter().map(|l| l.id()).collect();
    assert_eq!(ids, vec![1, 3, 4, 0], "pixel 1: b is in front");
    // ...also with a smaller bone score behind it.
    let close_behind = PersonLabels {
        score: vec![0.1, 0.1],
        ..behind.clone()
    };
    let img = merge_people(4, 1, &[close_behind, front.clone()]);
    assert_eq!(img.labels[1].id(), 3);
    // Side by side (depths within SIDE_BY_SIDE_M): the nearer bone decides.
    let beside = PersonLabels {
        depth_m: Some(2.0 + SIDE_BY_SIDE_M / 2.0),
        score: vec![0.1, 0.1],
        ..a
    };
    let img = merge_people(4, 1, &[beside, front]);
    assert_eq!(img.labels[1].id(), 2);
}

/// [`label_person`]'s block culling gives what scoring every bone at every pixel
/// gives (the reference below), on figures with graded masks and in several poses.
#[test]
fn block_culling_equals_scoring_every_bone() {
    let cfg = RuleConfig::default();
    for (angle, arm_dx) in [(0.0, 0.0), (0.3, 12.0), (-0.7, -20.0)] {
        let mut pose = figure();
        pose.roi.angle_rad = angle;
        pose.xy[landmark::LEFT_WRIST][0] += arm_dx;
        for j in 0..INPUT {
            for i in 0..INPUT {
                let (tx, ty) = (i as f64 + 0.5, j as f64 + 0.5);
                let m = 1.3 - ((tx - 128.0) / 60.0).hypot((ty - 128.0) / 110.0);
                pose.mask[j * INPUT + i] = m.clamp(0.0, 1.0) as f32;
            }
        }
        let got = label_person(&pose, &cfg, 100, 160).expect("in the image");
        let bl = bones(&pose, &cfg, 100, 160);
        let axes = pose.roi.axes();
        let ww = got.u1 - got.u0;
        let mut labelled = 0;
        for v in got.v0..got.v1 {
            for u in got.u0..got.u1 {
                let k = (v - got.v0) * ww + (u - got.u0);
                let q = [u as f64, v as f64];
                let m = mask_at(&pose, axes, q);
                let mut per_class = [f64::INFINITY; 7];
                for b in &bl {
                    let c = usize::from(b.class);
                    per_class[c] = per_class[c].min(b.score(q));
                }
                let (c1, e1, e2) = best_two(&per_class);
                if m < cfg.mask_threshold || e1 > cfg.max_score {
                    assert_eq!(got.class[k], 0, "({u}, {v}) is not the person's");
                    assert!(got.score[k].is_infinite());
                    continue;
                }
                labelled += 1;
                assert_eq!(usize::from(got.class[k]), c1, "({u}, {v})");
                let conf = 1.0 - 0.5 * (-(e2 - e1) / cfg.margin_scale).exp();
                // f32 storage of an f64 value
                assert!((f64::from(got.prob[k]) - m * conf).abs() < 1e-6);
            }
        }
        assert!(labelled > 1000, "the figure is labelled: {labelled} px");
    }
}

/// The bones with their pixel-independent parts computed once score every point exactly as
/// the bones do: the figure's bones (torso quad, round head, flat-shouldered upper arms,
/// three-point forearms), also rotated and with a degenerate (zero-length) limb, at points
/// inside, on and around them.
#[test]
fn prepared_bones_score_bit_for_bit_as_the_bones() {
    let cfg = RuleConfig::default();
    let mut poses = vec![figure()];
    let mut turned = figure();
    for p in &mut turned.xy {
        *p = [
            50.0 + 0.8 * (p[0] - 50.0) - 0.6 * (p[1] - 80.0),
            80.0 + 0.6 * (p[0] - 50.0) + 0.8 * (p[1] - 80.0),
        ];
    }
    poses.push(turned);
    let mut degenerate = figure();
    degenerate.xy[landmark::LEFT_ELBOW] = degenerate.xy[landmark::LEFT_SHOULDER];
    poses.push(degenerate);
    let mut checked = 0;
    for pose in &poses {
        let bl = bones(pose, &cfg, 100, 160);
        assert!(bl.len() >= 8, "the figure's bones: {}", bl.len());
        assert!(
            bl.iter()
                .any(|b| matches!(b.start, BoneStart::FlatMedial { .. }))
        );
        for b in &bl {
            let prepared = PreparedBone::new(b);
            // Quarter-pixel steps (not only pixel centres) over and beyond the image.
            for j in -40..=200 {
                for i in -40..=160 {
                    let q = [f64::from(i) * 0.75 - 0.125, f64::from(j) * 0.875 + 0.25];
                    assert_eq!(
                        prepared.score(q).to_bits(),
                        b.score(q).to_bits(),
                        "bone of class {} at {q:?}",
                        b.class
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 500_000);
}
