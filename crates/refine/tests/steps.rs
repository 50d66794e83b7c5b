//! Each refinement step doing its job on small hand-built scenes (ALGORITHM.md §5).

mod common;

use bodyseg_core::{Class, Label, PersonBox};
use bodyseg_refine::{
    Clustering, PersonRefinement, RefineConfig, Steps, fuse, refine, refine_person,
};
use common::{Scene, ball, l, paper};

/// Torso ball (r 0.15 m) with a head ball touching it from above: a valid body tree.
fn body(scene: &mut Scene) -> (usize, usize) {
    let torso = scene.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    let head = scene.add(ball([0.0, 0.0, 1.42], 0.08, 0.02, l(Class::Head)));
    (torso, head)
}

#[test]
fn m_merges_a_small_lower_arm_cluster_inside_the_torso_sphere_into_torso() {
    let mut s = Scene::default();
    let (torso, _) = body(&mut s);
    // Offset from the torso's centre, well inside its bounding sphere.
    let arm = s.add(ball([0.05, 0.0, 1.18], 0.04, 0.02, l(Class::LowerArms)));
    let r = refine_person(&s.pos, &s.lab, &paper("M"));
    assert!(s.all_labelled(&r.point_labels, arm, l(Class::Torso)));
    assert!(s.all_labelled(&r.point_labels, torso, l(Class::Torso)));
    assert_eq!(r.merged(), 1);
    // Without M it stays a lower arm.
    let r = refine_person(&s.pos, &s.lab, &paper("N"));
    assert!(s.all_labelled(&r.point_labels, arm, l(Class::LowerArms)));
}

#[test]
fn r_turns_a_head_cluster_floating_1m_from_the_body_into_background() {
    let mut s = Scene::default();
    let (_, head) = body(&mut s);
    let ghost = s.add(ball([1.0, 0.0, 1.4], 0.05, 0.02, l(Class::Head)));
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    assert!(r.tree.is_valid());
    assert!(s.all_labelled(&r.point_labels, ghost, Label::BACKGROUND));
    assert!(s.all_labelled(&r.point_labels, head, l(Class::Head)));
    assert_eq!(r.removed(), 1);
    // M-N keeps it: only R removes.
    let r = refine_person(&s.pos, &s.lab, &paper("M-N"));
    assert!(s.all_labelled(&r.point_labels, ghost, l(Class::Head)));
}

#[test]
fn r_does_nothing_without_a_valid_tree() {
    let mut s = Scene::default();
    // No torso: no root, no valid tree.
    let head = s.add(ball([0.0, 0.0, 1.4], 0.06, 0.02, l(Class::Head)));
    let far = s.add(ball([1.0, 0.0, 1.4], 0.06, 0.02, l(Class::LowerArms)));
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    assert!(!r.tree.is_valid());
    assert!(s.all_labelled(&r.point_labels, head, l(Class::Head)));
    assert!(s.all_labelled(&r.point_labels, far, l(Class::LowerArms)));
}

#[test]
fn a_tree_node_never_changes_even_inside_another_cluster() {
    let mut s = Scene::default();
    let torso = s.add(ball([0.0, 0.0, 1.2], 0.25, 0.025, l(Class::Torso)));
    // Two head clusters inside the torso's sphere: the larger fills the head slot and is
    // kept; the smaller is not a tree node and M merges it.
    let head_big = s.add(ball([0.0, 0.0, 1.33], 0.07, 0.02, l(Class::Head)));
    let head_small = s.add(ball([0.0, 0.12, 1.15], 0.04, 0.02, l(Class::Head)));
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    let tree_head = r.tree.slots[0].expect("head slot filled");
    assert_eq!(r.features[tree_head as usize].label, l(Class::Head));
    assert_eq!(r.labels_after_merge[tree_head as usize], l(Class::Head));
    assert!(s.all_labelled(&r.point_labels, head_big, l(Class::Head)));
    assert!(s.all_labelled(&r.point_labels, head_small, l(Class::Torso)));
    assert!(s.all_labelled(&r.point_labels, torso, l(Class::Torso)));
}

#[test]
fn n_gives_noise_points_the_label_of_the_nearest_clustered_point() {
    let mut s = Scene::default();
    let (_, _head) = body(&mut s);
    // Isolated points (too sparse to be core) near the torso's side and above the head.
    let near_torso = s.point([0.19, 0.0, 1.2], l(Class::UpperLegs));
    let unknown_near_torso = s.point([-0.19, 0.0, 1.2], Label::UNKNOWN);
    let near_head = s.point([0.0, 0.0, 1.55], Label::UNKNOWN);
    let far_flying = s.point([0.0, 0.9, 1.9], l(Class::LowerLegs));
    let r = refine_person(&s.pos, &s.lab, &paper("N"));
    for i in [near_torso, unknown_near_torso, near_head, far_flying] {
        assert_eq!(
            r.clustering.cluster_of[i], None,
            "point {i} should be noise"
        );
    }
    assert_eq!(r.point_labels[near_torso], l(Class::Torso));
    assert_eq!(r.point_labels[unknown_near_torso], l(Class::Torso));
    assert_eq!(r.point_labels[near_head], l(Class::Head));
    assert_eq!(r.point_labels[far_flying], l(Class::Head));
    // And every noise point agrees with a brute-force nearest clustered point.
    for (i, c) in r.clustering.cluster_of.iter().enumerate() {
        if c.is_some() {
            continue;
        }
        let nearest = (0..s.pos.len())
            .filter(|&j| r.clustering.cluster_of[j].is_some())
            .min_by(|&a, &b| {
                let d = |j: usize| bodyseg_core::math::dist2(s.pos[i], s.pos[j]);
                d(a).total_cmp(&d(b)).then(a.cmp(&b))
            })
            .expect("clusters exist");
        assert_eq!(
            r.point_labels[i], r.point_labels[nearest],
            "noise point {i}"
        );
    }
    // Without N, noise keeps its label, and unknown becomes background.
    let r = refine_person(&s.pos, &s.lab, &paper("M"));
    assert_eq!(r.point_labels[near_torso], l(Class::UpperLegs));
    assert_eq!(r.point_labels[unknown_near_torso], Label::BACKGROUND);
}

#[test]
fn n_follows_the_labels_after_m_and_r() {
    let mut s = Scene::default();
    body(&mut s);
    let ghost = s.add(ball([1.0, 0.0, 1.4], 0.05, 0.02, l(Class::Head)));
    let near_ghost = s.point([1.08, 0.0, 1.4], Label::UNKNOWN);
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    assert!(s.all_labelled(&r.point_labels, ghost, Label::BACKGROUND));
    assert_eq!(r.point_labels[near_ghost], Label::BACKGROUND);
}

fn person(point_labels: Vec<Label>) -> PersonRefinement {
    PersonRefinement {
        clustering: Clustering::default(),
        features: Vec::new(),
        graph: Default::default(),
        tree: Default::default(),
        labels_after_merge: Vec::new(),
        labels_after_remove: Vec::new(),
        point_labels,
    }
}

fn unit_box(id: u32, x: f32) -> PersonBox {
    PersonBox::axis_aligned(id, [x, 0.0, 1.0], [0.5, 0.5, 1.0])
}

#[test]
fn fuse_keeps_the_original_label_where_overlapping_people_disagree() {
    let mut s = Scene::default();
    let a = s.point([-0.4, 0.0, 1.0], l(Class::Torso)); // box A only
    let both_disagree = s.point([0.0, 0.0, 1.0], l(Class::UpperArms)); // A and B
    let both_agree = s.point([0.05, 0.0, 1.0], l(Class::UpperArms)); // A and B
    let unknown_disagree = s.point([0.02, 0.0, 1.0], Label::UNKNOWN); // A and B, B nearer
    let outside = s.point([3.0, 0.0, 1.0], l(Class::Head)); // no box
    let cloud = s.cloud();
    let boxes = [unit_box(0, -0.45), unit_box(1, 0.45)];
    let people = vec![
        (
            vec![
                a as u32,
                both_disagree as u32,
                both_agree as u32,
                unknown_disagree as u32,
            ],
            person(vec![
                l(Class::Torso),
                l(Class::Torso),
                l(Class::LowerArms),
                l(Class::Torso),
            ]),
        ),
        (
            vec![
                both_disagree as u32,
                both_agree as u32,
                unknown_disagree as u32,
            ],
            person(vec![
                l(Class::LowerArms),
                l(Class::LowerArms),
                l(Class::Head),
            ]),
        ),
    ];
    let out = fuse(&cloud, &boxes, &people, false).cloud.labels;
    assert_eq!(out[a], l(Class::Torso));
    assert_eq!(
        out[both_disagree],
        l(Class::UpperArms),
        "disagreement keeps the original"
    );
    assert_eq!(
        out[both_agree],
        l(Class::LowerArms),
        "agreement takes the common label"
    );
    assert_eq!(
        out[unknown_disagree],
        l(Class::Head),
        "unknown takes the nearer box's label"
    );
    assert_eq!(
        out[outside],
        Label::BACKGROUND,
        "body point outside every box is an outlier"
    );
    let kept = fuse(&cloud, &boxes, &people, true).cloud.labels;
    assert_eq!(kept[outside], l(Class::Head));
}

#[test]
fn refine_keeps_the_inputs_points_in_the_inputs_order() {
    let p = bodyseg_testkit::human_cloud(20_000, 3);
    let out = refine(
        &p.cloud,
        std::slice::from_ref(&p.person_box),
        &RefineConfig::default(),
    )
    .expect("valid input");
    assert_eq!(out.cloud.positions_m, p.cloud.positions_m);
    assert_eq!(out.cloud.origins, p.cloud.origins);
    assert_eq!(out.cloud.len(), p.cloud.len());
    assert!(
        out.cloud.labels.iter().all(|l| !l.is_unknown()),
        "nothing leaves unknown"
    );
    assert_ne!(
        out.cloud.labels, p.cloud.labels,
        "refinement changed nothing"
    );
    // Reference is the input untouched.
    let cfg = RefineConfig {
        steps: Steps::Reference,
        ..Default::default()
    };
    let reference = refine(&p.cloud, &[], &cfg).expect("valid input");
    assert_eq!(reference.cloud, p.cloud);
}

/// Mean IoU over the body classes against the truth.
fn body_iou(pred: &[Label], truth: &[Label]) -> f64 {
    let mut sum = 0.0;
    for c in Class::BODY {
        let c = l(c);
        let tp = pred
            .iter()
            .zip(truth)
            .filter(|(p, t)| **p == c && **t == c)
            .count();
        let union = pred
            .iter()
            .zip(truth)
            .filter(|(p, t)| **p == c || **t == c)
            .count();
        sum += tp as f64 / union.max(1) as f64;
    }
    sum / 6.0
}

#[test]
fn m_r_n_improves_body_iou_on_a_synthetic_person() {
    let p = bodyseg_testkit::human_cloud(60_000, 9);
    let before = body_iou(&p.cloud.labels, &p.truth);
    let out = refine(
        &p.cloud,
        std::slice::from_ref(&p.person_box),
        &RefineConfig::default(),
    )
    .expect("valid input");
    let after = body_iou(&out.cloud.labels, &p.truth);
    assert!(after > before + 0.005, "BIoU {before:.4} -> {after:.4}");
}

#[test]
fn bad_config_and_bad_cloud_are_errors_naming_the_problem() {
    let p = bodyseg_testkit::human_cloud(2000, 1);
    let boxes = [p.person_box.clone()];
    let bad = RefineConfig {
        eps_m: 0.0,
        ..Default::default()
    };
    let e = refine(&p.cloud, &boxes, &bad)
        .expect_err("eps 0 is invalid")
        .to_string();
    assert!(e.contains("refine.eps_m"), "{e}");
    let mut nan = p.cloud.clone();
    nan.positions_m[17][2] = f32::NAN;
    let e = refine(&nan, &boxes, &RefineConfig::default())
        .expect_err("NaN is invalid")
        .to_string();
    assert!(e.contains("point 17"), "{e}");
    let flat = PersonBox {
        half_extents_m: [0.5, 0.0, 1.0],
        ..boxes[0].clone()
    };
    assert!(refine(&p.cloud, &[flat], &RefineConfig::default()).is_err());
}

#[test]
fn refine_variants_equal_one_refine_per_configuration() {
    let p = bodyseg_testkit::human_cloud(20_000, 5);
    // Two boxes (the person split in two halves) so the fuse sees several people.
    let mut left = p.person_box.clone();
    left.half_extents_m[0] *= 0.6;
    left.center_m[0] -= 0.4 * p.person_box.half_extents_m[0];
    let boxes = [p.person_box.clone(), left];
    // The paper's modes, and every mode beside them (issue 8).
    let modes = RefineConfig {
        graph: bodyseg_refine::GraphMode::Contact,
        tree: bodyseg_refine::TreeMode::Coverage,
        noise: bodyseg_refine::NoiseMode::Weighted,
        ..Default::default()
    };
    let mut mrn = Vec::new();
    for base in [RefineConfig::default(), modes] {
        let variants =
            bodyseg_refine::refine_variants(&p.cloud, &boxes, &base, &Steps::PAPER, true)
                .expect("valid");
        assert_eq!(variants.labels.len(), Steps::PAPER.len());
        let mut distinct = std::collections::HashSet::new();
        for (steps, got) in Steps::PAPER.iter().zip(&variants.labels) {
            let cfg = RefineConfig {
                steps: *steps,
                ..base.clone()
            };
            let want = refine(&p.cloud, &boxes, &cfg).expect("valid");
            assert_eq!(*got, want.cloud.labels, "{steps}");
            if *steps != Steps::Reference {
                assert_eq!(variants.clusters, want.clusters, "{steps}");
            }
            distinct.insert(got.clone());
        }
        assert!(distinct.len() >= 4, "the configurations differ");
        mrn.push(variants.labels[4].clone());
    }
    assert_ne!(mrn[0], mrn[1], "the modes change the M-R-N result");
}
