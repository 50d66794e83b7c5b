//! The refinement modes beside the paper's (issue 8): each on a hand-built scene that the
//! paper's mode gets wrong and the mode gets right (ALGORITHM.md §5.3, §5.6; the
//! multi-view vote's own case is in `bodyseg-project`'s tests, here its use by the steps).

mod common;

use bodyseg_core::{Class, Label, PersonBox};
use bodyseg_refine::{
    GraphMode, NoiseMode, PointEvidence, RefineConfig, RefineError, Steps, TreeMode, VoteMode,
    refine, refine_person, refine_variants, refine_variants_with,
};
use common::{Scene, ball, cuboid, l, paper};

fn contact(steps: &str) -> RefineConfig {
    RefineConfig {
        graph: GraphMode::Contact,
        contact_gap_m: 0.03,
        ..paper(steps)
    }
}

/// The evidence of a multi-view vote that gave `voted`.
fn vote_of(voted: Option<&[Label]>) -> PointEvidence<'_> {
    PointEvidence {
        voted,
        ..Default::default()
    }
}

fn all(s: &Scene, out: &[Label], part: usize, want: Class) -> bool {
    s.labels_of(out, part).iter().all(|&x| x == l(want))
}

/// A slab-shaped torso (0.3 × 0.2 × 0.6 m: its bounding sphere, r ≈ 0.35 m, reaches far
/// beyond its points) with a head on top.
fn slab_body(s: &mut Scene) -> usize {
    let torso = s.add(cuboid(
        [-0.15, -0.1, 0.9],
        [0.15, 0.1, 1.5],
        0.025,
        l(Class::Torso),
    ));
    s.add(ball([0.0, 0.0, 1.6], 0.08, 0.02, l(Class::Head)));
    torso
}

/// A forearm beside the slab body, seen by two cameras as lower arm (a 2 cm lattice) and
/// by a third as background (a missed part: the same cuboid sampled 1 cm off the others'
/// points): `(arm, missed)`, as [`Scene::add`] gives them.
fn forearm_one_camera_missed(s: &mut Scene) -> (usize, usize) {
    let arm = s.add(cuboid(
        [0.2, -0.04, 1.0],
        [0.24, 0.0, 1.3],
        0.02,
        l(Class::LowerArms),
    ));
    let missed = s.add(cuboid(
        [0.21, -0.03, 1.01],
        [0.23, -0.01, 1.31],
        0.02,
        Label::BACKGROUND,
    ));
    (arm, missed)
}

#[test]
fn contact_graph_lets_r_remove_a_blob_whose_sphere_but_not_its_points_touch_the_body() {
    let mut s = Scene::default();
    slab_body(&mut s);
    // A lower-arm blob beside the torso's shoulder, 8 cm from its nearest torso point:
    // its sphere intersects the torso's sphere (d 0.375 m <= 0.35 + 0.05) without lying
    // inside it. Something else's points (the neighbour's, the robot's) labelled arm.
    let blob = s.add(ball([0.28, 0.0, 1.45], 0.05, 0.02, l(Class::LowerArms)));
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    assert!(r.tree.is_valid());
    assert!(
        all(&s, &r.point_labels, blob, Class::LowerArms),
        "the spheres touch: the paper keeps the blob"
    );
    let r = refine_person(&s.pos, &s.lab, &contact("M-R-N"));
    assert!(r.tree.is_valid());
    assert!(
        all(&s, &r.point_labels, blob, Class::Background),
        "8 cm gap > contact_gap_m: R removes the blob"
    );
    // With a gap above the blob's, it touches again and stays.
    let wide = RefineConfig {
        contact_gap_m: 0.1,
        ..contact("M-R-N")
    };
    let r = refine_person(&s.pos, &s.lab, &wide);
    assert!(all(&s, &r.point_labels, blob, Class::LowerArms));
}

#[test]
fn contact_graph_keeps_m_from_merging_a_hand_held_in_front_of_the_torso() {
    let mut s = Scene::default();
    let torso = slab_body(&mut s);
    // A hand 8 cm in front of the torso: its sphere lies inside the torso's (d 0.22 + r
    // 0.04 <= 0.35), its points do not touch the torso's.
    let hand = s.add(ball([0.0, -0.22, 1.2], 0.04, 0.02, l(Class::LowerArms)));
    let r = refine_person(&s.pos, &s.lab, &paper("M"));
    assert!(
        all(&s, &r.point_labels, hand, Class::Torso),
        "the paper's M merges the hand into the torso"
    );
    let r = refine_person(&s.pos, &s.lab, &contact("M"));
    assert!(all(&s, &r.point_labels, hand, Class::LowerArms));
    assert!(all(&s, &r.point_labels, torso, Class::Torso));
    // A patch lying on the torso's front face is still merged.
    let mut s = Scene::default();
    slab_body(&mut s);
    let patch = s.add(cuboid(
        [-0.05, -0.1, 1.15],
        [0.05, -0.1, 1.25],
        0.01,
        l(Class::LowerArms),
    ));
    let r = refine_person(&s.pos, &s.lab, &contact("M"));
    assert!(all(&s, &r.point_labels, patch, Class::Torso));
}

#[test]
fn contact_graph_merges_one_cameras_other_label_for_a_surface_the_others_see() {
    let mut s = Scene::default();
    slab_body(&mut s);
    // A forearm seen by two cameras as lower arm (a 2 cm lattice) and by a third as
    // background (a missed part; the same cylinder sampled 1 cm off the others' points).
    // The two clusters have alike spheres, so the sphere test puts neither inside the
    // other; every background point lies within 1.8 cm of a lower-arm point.
    let (arm, missed) = forearm_one_camera_missed(&mut s);
    let r = refine_person(&s.pos, &s.lab, &paper("M"));
    assert!(all(&s, &r.point_labels, arm, Class::LowerArms));
    assert!(
        all(&s, &r.point_labels, missed, Class::Background),
        "spheres: the missed view's points stay background"
    );
    let r = refine_person(&s.pos, &s.lab, &contact("M"));
    assert!(all(&s, &r.point_labels, arm, Class::LowerArms));
    assert!(
        all(&s, &r.point_labels, missed, Class::LowerArms),
        "contact: immersed in the lower arm, merged into it"
    );
    // With a fraction above what is immersed (all of it is), nothing changes.
    let strict = RefineConfig {
        contact_inside_fraction: 1.0,
        contact_gap_m: 0.015,
        ..contact("M")
    };
    let r = refine_person(&s.pos, &s.lab, &strict);
    assert!(all(&s, &r.point_labels, missed, Class::Background));
}

/// A torso ball with both arms (upper arm, lower arm below it) against its sides, all
/// inside the torso's bounding sphere, and a mislabelled upper-arm patch on its front,
/// larger than either real upper arm. Returns (patch, [upper arms], [lower arms]).
fn torso_with_arms_and_patch(s: &mut Scene) -> (usize, [usize; 2], [usize; 2]) {
    s.add(ball([0.0, 0.0, 1.2], 0.3, 0.025, l(Class::Torso)));
    let patch = s.add(ball([0.0, 0.15, 1.2], 0.06, 0.02, l(Class::UpperArms)));
    let mut upper = [0; 2];
    let mut lower = [0; 2];
    for (k, x) in [0.2f32, -0.2].into_iter().enumerate() {
        upper[k] = s.add(ball([x, 0.0, 1.3], 0.05, 0.02, l(Class::UpperArms)));
        lower[k] = s.add(ball([x, 0.0, 1.19], 0.07, 0.02, l(Class::LowerArms)));
    }
    (patch, upper, lower)
}

#[test]
fn coverage_tree_keeps_both_real_arms_where_greedy_slot_filling_takes_a_patch() {
    let mut s = Scene::default();
    let (patch, upper, lower) = torso_with_arms_and_patch(&mut s);
    let size = |part: usize| s.parts[part].len();
    assert!(
        size(patch) > size(upper[0]),
        "the patch is the largest upper arm"
    );
    assert!(
        size(upper[0]) + size(lower[0]) > size(patch),
        "a real arm chain holds more points than the patch"
    );
    let r = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    assert!(
        all(&s, &r.point_labels, patch, Class::UpperArms),
        "greedy: the patch fills an upper-arm slot and is kept"
    );
    assert!(
        all(&s, &r.point_labels, upper[1], Class::Torso)
            && all(&s, &r.point_labels, lower[1], Class::Torso),
        "greedy: the second real arm is left out of the tree and M merges it into the torso"
    );
    let coverage = RefineConfig {
        tree: TreeMode::Coverage,
        ..paper("M-R-N")
    };
    let r = refine_person(&s.pos, &s.lab, &coverage);
    for k in 0..2 {
        assert!(
            all(&s, &r.point_labels, upper[k], Class::UpperArms),
            "arm {k}"
        );
        assert!(
            all(&s, &r.point_labels, lower[k], Class::LowerArms),
            "arm {k}"
        );
    }
    assert!(
        all(&s, &r.point_labels, patch, Class::Torso),
        "the patch is no tree node: M merges it"
    );
    let covered: usize = r.tree.nodes().map(|c| r.features[c as usize].size).sum();
    let greedy = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    let greedy_covered: usize = greedy
        .tree
        .nodes()
        .map(|c| greedy.features[c as usize].size)
        .sum();
    assert!(covered > greedy_covered, "{covered} <= {greedy_covered}");
}

#[test]
fn coverage_tree_equals_the_paper_tree_when_greedy_is_optimal() {
    // One candidate per slot: both searches find the same tree.
    let mut s = Scene::default();
    s.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    s.add(ball([0.0, 0.0, 1.42], 0.08, 0.02, l(Class::Head)));
    s.add(ball([0.17, 0.0, 1.25], 0.05, 0.02, l(Class::UpperArms)));
    s.add(ball([0.17, 0.0, 1.15], 0.06, 0.02, l(Class::LowerArms)));
    let a = refine_person(&s.pos, &s.lab, &paper("M-R-N"));
    let b = refine_person(
        &s.pos,
        &s.lab,
        &RefineConfig {
            tree: TreeMode::Coverage,
            ..paper("M-R-N")
        },
    );
    assert_eq!(a.tree.nodes().count(), 4);
    assert_eq!(a.tree, b.tree);
}

#[test]
fn weighted_noise_follows_the_surface_not_a_thin_strand_that_passes_nearer() {
    let mut s = Scene::default();
    // A head surface (the plane x = 0, 1 cm lattice) and a one-point-wide torso strand
    // (a line along x, 5 mm pitch) whose tip passes 8 mm from an unknown point lying 1 cm
    // off the head surface.
    let sheet = s.add(cuboid(
        [0.0, -0.1, -0.1],
        [0.0, 0.1, 0.1],
        0.01,
        l(Class::Head),
    ));
    let strand = s.add((
        (0..41)
            .map(|i| [0.018 + i as f32 * 0.005, 0.0, 0.0])
            .collect(),
        vec![l(Class::Torso); 41],
    ));
    let q = s.point([0.01, 0.0, 0.0], Label::UNKNOWN);
    let r = refine_person(&s.pos, &s.lab, &paper("N"));
    assert_eq!(r.clustering.cluster_of[q], None, "unknown is noise");
    assert!(all(&s, &r.point_labels, sheet, Class::Head));
    assert!(all(&s, &r.point_labels, strand, Class::Torso));
    assert_eq!(
        r.point_labels[q],
        l(Class::Torso),
        "1-NN follows the strand's tip"
    );
    let weighted = RefineConfig {
        noise: NoiseMode::Weighted,
        ..paper("N")
    };
    let r = refine_person(&s.pos, &s.lab, &weighted);
    assert_eq!(
        r.point_labels[q],
        l(Class::Head),
        "the vote follows the surface"
    );
    // One voter and no own vote is the paper's rule again.
    let one = RefineConfig {
        noise_k: 1,
        noise_self_weight: 0.0,
        ..weighted
    };
    let r = refine_person(&s.pos, &s.lab, &one);
    assert_eq!(r.point_labels[q], l(Class::Torso));
}

#[test]
fn weighted_noise_keeps_a_hand_too_sparse_to_cluster() {
    let mut s = Scene::default();
    // A torso and a lower arm sticking out of it sampled every 2 cm (far from the sensors):
    // too sparse for a core point (3 neighbours within eps, 5 needed), all noise.
    let torso = s.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    let arm: Vec<usize> = (0..11)
        .map(|i| s.point([0.165 + 0.02 * i as f32, 0.0, 1.2], l(Class::LowerArms)))
        .collect();
    let r = refine_person(&s.pos, &s.lab, &paper("N"));
    assert!(arm.iter().all(|&i| r.clustering.cluster_of[i].is_none()));
    assert!(all(&s, &r.point_labels, torso, Class::Torso));
    assert!(
        arm.iter().all(|&i| r.point_labels[i] == l(Class::Torso)),
        "1-NN gives the whole arm the torso's label"
    );
    let weighted = RefineConfig {
        noise: NoiseMode::Weighted,
        ..paper("N")
    };
    let r = refine_person(&s.pos, &s.lab, &weighted);
    // The arm's first point has a single torso voter within eps (weight ~0.6), less than its
    // own label's 1.0; the others have none and keep their label.
    assert!(
        arm.iter()
            .all(|&i| r.point_labels[i] == l(Class::LowerArms)),
        "{:?}",
        arm.iter().map(|&i| r.point_labels[i]).collect::<Vec<_>>()
    );
    let no_self = RefineConfig {
        noise_self_weight: 0.0,
        ..weighted.clone()
    };
    let r = refine_person(&s.pos, &s.lab, &no_self);
    assert!(arm.iter().all(|&i| r.point_labels[i] == l(Class::Torso)));
    // An unknown point out there still takes the nearest cluster's label.
    let mut s2 = Scene::default();
    s2.add(ball([0.0, 0.0, 1.2], 0.15, 0.02, l(Class::Torso)));
    let q = s2.point([0.4, 0.0, 1.2], Label::UNKNOWN);
    let r = refine_person(&s2.pos, &s2.lab, &weighted);
    assert_eq!(r.point_labels[q], l(Class::Torso));
}

#[test]
fn weighted_noise_with_one_voter_and_no_own_vote_equals_nearest() {
    let p = bodyseg_testkit::human_cloud(30_000, 4);
    let boxes = [p.person_box.clone()];
    let nearest = refine(&p.cloud, &boxes, &RefineConfig::default()).expect("valid");
    let one = RefineConfig {
        noise: NoiseMode::Weighted,
        noise_k: 1,
        noise_self_weight: 0.0,
        ..Default::default()
    };
    let weighted = refine(&p.cloud, &boxes, &one).expect("valid");
    assert_eq!(nearest.cloud.labels, weighted.cloud.labels);
}

#[test]
fn vote_mode_starts_the_steps_from_the_voted_labels_and_leaves_reference_alone() {
    let mut s = Scene::default();
    slab_body(&mut s);
    // A forearm that one camera's parser missed: its points (1 cm off the other views')
    // are background in the projection. The multi-view vote (two views against one) gave
    // them lower arm; here that vote is the `voted` list.
    let (arm, missed) = forearm_one_camera_missed(&mut s);
    let cloud = s.cloud();
    let mut voted = cloud.labels.clone();
    for i in s.parts[missed].clone() {
        voted[i] = l(Class::LowerArms);
    }
    let boxes = [PersonBox::axis_aligned(0, [0.0, 0.0, 1.0], [0.6, 0.6, 1.0])];
    let steps = [Steps::Reference, Steps::MRN];
    let off = paper("M-R-N");
    let on = RefineConfig {
        vote: VoteMode::MultiView,
        ..off.clone()
    };
    // The paper's M-R-N keeps the missed view's points background (spheres alike: neither
    // inside the other).
    let paper_out = refine_variants(&cloud, &boxes, &off, &steps, true).expect("valid");
    assert!(all(&s, &paper_out.labels[1], missed, Class::Background));
    let out = refine_variants_with(&cloud, vote_of(Some(&voted)), &boxes, &on, &steps, true)
        .expect("valid");
    // Reference is the projection, untouched by the vote; M-R-N starts from the vote.
    assert_eq!(out.labels[0], cloud.labels);
    assert!(all(&s, &out.labels[1], missed, Class::LowerArms));
    assert!(all(&s, &out.labels[1], arm, Class::LowerArms));
    // The vote off: `voted` is ignored.
    let ignored = refine_variants_with(&cloud, vote_of(Some(&voted)), &boxes, &off, &steps, true)
        .expect("valid");
    assert_eq!(ignored, paper_out);
    // The vote on without its labels, or with a list of another length: an error naming
    // the key, never a silent fallback to the projection.
    for v in [None, Some(&voted[1..])] {
        let e = refine_variants_with(&cloud, vote_of(v), &boxes, &on, &steps, true)
            .expect_err("no vote labels");
        assert!(matches!(e, RefineError::VoteLabels { .. }), "{e}");
        assert!(e.to_string().starts_with("refine.vote"), "{e}");
    }
    assert!(refine(&cloud, &boxes, &on).is_err());
}

#[test]
fn probability_noise_lets_an_unsure_label_yield_and_a_sure_one_hold() {
    // A torso voter 1.5 cm from a noise point the parser called head (eps 3 cm: the
    // voter weighs 1 / (1 + 0.25) = 0.8).
    let pos = vec![[0.0, 0.0, 1.0], [0.015, 0.0, 1.0]];
    let labels = vec![l(Class::Head), l(Class::Torso)];
    let is_noise = [true, false];
    let run = |probs: Option<&[f32]>| {
        let vote = bodyseg_refine::Vote {
            k: 16,
            radius_m: 0.03,
            self_weight: 1.0,
        };
        bodyseg_refine::reassign_noise_weighted(&pos, &labels, &is_noise, None, probs, vote)[0]
    };
    assert_eq!(run(None), l(Class::Head), "own label 1.0 against 0.8");
    assert_eq!(run(Some(&[1.0, 1.0])), l(Class::Head), "sure: holds");
    assert_eq!(
        run(Some(&[0.5, 1.0])),
        l(Class::Torso),
        "unsure: 0.5 yields"
    );
    assert_eq!(
        run(Some(&[f32::NAN, 1.0])),
        l(Class::Head),
        "NaN counts as sure"
    );
}

/// A forearm (2 cm lattice) beside the slab body whose middle band (two layers) the parser
/// called upper arm with probability `band_prob`, and a real upper arm on the body's other
/// side (probability 0.9, as every other point): `(forearm, band, probabilities)`.
fn forearm_with_unsure_band(s: &mut Scene, band_prob: f32) -> (usize, usize, Vec<f32>) {
    s.add(cuboid(
        [-0.24, -0.04, 1.2],
        [-0.2, 0.0, 1.4],
        0.02,
        l(Class::UpperArms),
    ));
    // The forearm, bottom to top: lower arm, the band, lower arm.
    let [below, band, _] = [
        (1.0, 1.12, Class::LowerArms),
        (1.14, 1.16, Class::UpperArms),
        (1.18, 1.3, Class::LowerArms),
    ]
    .map(|(z0, z1, class)| s.add(cuboid([0.2, -0.04, z0], [0.24, 0.0, z1], 0.02, l(class))));
    let mut probs = vec![0.9; s.pos.len()];
    for i in s.parts[band].clone() {
        probs[i] = band_prob;
    }
    (below, band, probs)
}

#[test]
fn probability_noise_relabels_a_band_the_parser_was_unsure_of() {
    let mut s = Scene::default();
    slab_body(&mut s);
    let (below, band, unsure) = forearm_with_unsure_band(&mut s, 0.4);
    let cloud = s.cloud();
    let boxes = [PersonBox::axis_aligned(0, [0.0, 0.0, 1.0], [0.6, 0.6, 1.0])];
    let steps = [Steps::Run {
        merge: false,
        remove: false,
        noise: true,
    }];
    let weighted = RefineConfig {
        noise: NoiseMode::Weighted,
        ..paper("N")
    };
    let probability = RefineConfig {
        noise: NoiseMode::Probability,
        noise_doubt_ratio: 0.7,
        ..weighted.clone()
    };
    fn with(probs: &[f32]) -> PointEvidence<'_> {
        PointEvidence {
            label_probs: Some(probs),
            ..Default::default()
        }
    }
    // Weighted noise: the band is a cluster of its own (18 points), so N leaves it.
    let out = refine_variants_with(&cloud, with(&unsure), &boxes, &weighted, &steps, false)
        .expect("valid");
    assert!(all(&s, &out.labels[0], band, Class::UpperArms));
    // Probability: 0.4 is below 0.7 × the upper arms' median (0.9), so the band is noise,
    // and its forearm neighbours
    // outvote its own label (weight 0.4).
    let out = refine_variants_with(&cloud, with(&unsure), &boxes, &probability, &steps, false)
        .expect("valid");
    assert!(all(&s, &out.labels[0], band, Class::LowerArms));
    assert!(all(&s, &out.labels[0], below, Class::LowerArms));
    // A band the parser was sure of stays what it said.
    let mut s2 = Scene::default();
    slab_body(&mut s2);
    let (_, band2, sure) = forearm_with_unsure_band(&mut s2, 0.95);
    let out = refine_variants_with(
        &s2.cloud(),
        with(&sure),
        &boxes,
        &probability,
        &steps,
        false,
    )
    .expect("valid");
    assert!(all(&s2, &out.labels[0], band2, Class::UpperArms));
    // Without N the unsure points keep their own label (never left unknown).
    let m_only = RefineConfig {
        steps: "M".parse().expect("valid"),
        ..probability.clone()
    };
    let out = refine_variants_with(
        &cloud,
        with(&unsure),
        &boxes,
        &m_only,
        &[m_only.steps],
        false,
    )
    .expect("valid");
    assert!(all(&s, &out.labels[0], band, Class::UpperArms));
    // One probability per point, or an error.
    let e = refine_variants_with(
        &cloud,
        with(&unsure[1..]),
        &boxes,
        &probability,
        &steps,
        false,
    )
    .expect_err("short list");
    assert!(matches!(e, RefineError::LabelProbs { .. }), "{e}");
}

#[test]
fn doubt_is_measured_against_each_labels_own_median() {
    let (a, b) = (l(Class::Torso), l(Class::LowerArms));
    // The torso: mostly sure, one point unsure. The forearm: a part the parser is never
    // sure of (median 0.4), one point much less sure than the rest.
    let labels = [a, a, a, a, b, b, b, b, Label::UNKNOWN, a];
    let probs = [0.9, 0.95, 0.9, 0.3, 0.4, 0.4, 0.35, 0.2, 0.1, f32::NAN];
    let out = bodyseg_refine::doubtful_as_unknown(&labels, &probs, 0.7);
    let u = Label::UNKNOWN;
    // Thresholds: torso 0.7 × 0.9 = 0.63, forearm 0.7 × 0.4 = 0.28 (one absolute threshold
    // of 0.6 would have made the whole forearm doubtful).
    assert_eq!(out, [a, a, a, u, b, b, b, u, u, a]);
    // Ratio 0: nothing is doubtful.
    assert_eq!(
        bodyseg_refine::doubtful_as_unknown(&labels, &probs, 0.0),
        labels
    );
}

/// The labels `cfg` (its `steps`) gives the scene's points with the parser's probabilities
/// `probs`, in one person box (`center`, `half_extents`).
fn refine_with_probs(
    cloud: &bodyseg_core::LabeledCloud,
    probs: &[f32],
    (center, half_extents): ([f32; 3], [f32; 3]),
    cfg: &RefineConfig,
) -> Vec<Label> {
    let boxes = [PersonBox::axis_aligned(0, center, half_extents)];
    let evidence = PointEvidence {
        label_probs: Some(probs),
        ..Default::default()
    };
    refine_variants_with(cloud, evidence, &boxes, cfg, &[cfg.steps], false)
        .expect("valid")
        .labels
        .swap_remove(0)
}

/// A forearm far from the slab body (lower arm, 2 cm lattice) crossed by a one-layer
/// sliver the parser called torso and was sure of (0.9), with a layer on each side of it
/// that it also called torso but doubted (0.3): `(sliver, doubted layers, probabilities)`.
fn forearm_with_a_torso_sliver(s: &mut Scene) -> (usize, [usize; 2], Vec<f32>) {
    let layer = |s: &mut Scene, z0: f32, z1: f32, class: Class| {
        s.add(cuboid([0.4, -0.04, z0], [0.6, 0.0, z1], 0.02, l(class)))
    };
    layer(s, 1.0, 1.12, Class::LowerArms);
    let below = layer(s, 1.14, 1.14, Class::Torso);
    let sliver = layer(s, 1.16, 1.16, Class::Torso);
    let above = layer(s, 1.18, 1.18, Class::Torso);
    layer(s, 1.2, 1.3, Class::LowerArms);
    let mut probs = vec![0.9; s.pos.len()];
    for part in [below, above] {
        for i in s.parts[part].clone() {
            probs[i] = 0.3;
        }
    }
    (sliver, [below, above], probs)
}

#[test]
fn doubted_labels_are_voted_by_the_sure_points_across_the_limb() {
    let mut s = Scene::default();
    slab_body(&mut s);
    let (sliver, doubted, probs) = forearm_with_a_torso_sliver(&mut s);
    let cloud = s.cloud();
    let narrow = RefineConfig {
        noise: NoiseMode::Probability,
        noise_doubt_ratio: 0.85,
        ..paper("N")
    };
    let wide = RefineConfig {
        noise_doubt_radius_m: 0.15,
        noise_doubt_k: 256,
        ..narrow.clone()
    };
    let run = |cfg: &RefineConfig| {
        refine_with_probs(&cloud, &probs, ([0.1, 0.0, 1.0], [0.7, 0.6, 1.0]), cfg)
    };
    // The narrow vote: the nearest sure points are as many sliver (torso) as forearm points,
    // and the doubted layers' own label breaks the tie.
    let out = run(&narrow);
    for part in doubted {
        assert!(all(&s, &out, part, Class::Torso), "narrow vote");
    }
    // The wide vote: a few hundred sure points around them, most of them forearm.
    let out = run(&wide);
    for part in doubted {
        assert!(all(&s, &out, part, Class::LowerArms), "wide vote");
    }
    // Only the doubted points: the sure sliver is a cluster N does not touch.
    assert!(all(&s, &out, sliver, Class::Torso));
    // Without probabilities nothing is doubted, and the radius changes nothing.
    let weighted = |cfg: &RefineConfig| RefineConfig {
        noise: NoiseMode::Weighted,
        ..cfg.clone()
    };
    assert_eq!(run(&weighted(&wide)), run(&weighted(&narrow)));
    // Bad values name their key.
    for (cfg, key) in [
        (
            RefineConfig {
                noise_doubt_radius_m: -0.1,
                ..wide.clone()
            },
            "noise_doubt_radius_m",
        ),
        (
            RefineConfig {
                noise_doubt_k: 0,
                ..wide.clone()
            },
            "noise_doubt_k",
        ),
    ] {
        let e = cfg.validate().expect_err("invalid");
        assert!(e.to_string().contains(key), "{e}");
    }
}

/// Adds cuboid parts `(lo, hi, class)` on a 2 cm lattice to the scene; their part indices.
fn parts<const N: usize>(s: &mut Scene, table: [([f32; 3], [f32; 3], Class); N]) -> [usize; N] {
    table.map(|(lo, hi, class)| s.add(cuboid(lo, hi, 0.02, l(class))))
}

#[test]
fn r_through_noise_keeps_a_forearm_joined_by_a_doubted_elbow_and_removes_a_loose_object() {
    let mut s = Scene::default();
    slab_body(&mut s);
    // An upper arm against the body's side, a forearm held out from its lower end joined
    // only by an elbow band the parser doubted (3 layers: an 8 cm gap between the two arm
    // clusters, more than twice the contact gap), and a piece labelled forearm 0.3 m from
    // everything (an object).
    let [_, elbow, forearm, object] = parts(
        &mut s,
        [
            ([0.17, -0.04, 1.2], [0.21, 0.0, 1.48], Class::UpperArms),
            ([0.23, -0.04, 1.2], [0.27, 0.0, 1.24], Class::UpperArms),
            ([0.29, -0.04, 1.2], [0.5, 0.0, 1.24], Class::LowerArms),
            ([0.5, -0.04, 0.8], [0.54, 0.0, 0.9], Class::LowerArms),
        ],
    );
    let mut probs = vec![0.9; s.pos.len()];
    for i in s.parts[elbow].clone() {
        probs[i] = 0.2;
    }
    let cloud = s.cloud();
    let paper_r = RefineConfig {
        noise: NoiseMode::Probability,
        noise_doubt_ratio: 0.85,
        ..contact("R")
    };
    let bridged = RefineConfig {
        remove_through_noise: true,
        ..paper_r.clone()
    };
    let run = |cfg: &RefineConfig| {
        refine_with_probs(&cloud, &probs, ([0.2, 0.0, 1.0], [0.6, 0.6, 1.0]), cfg)
    };
    let out = run(&paper_r);
    assert!(
        all(&s, &out, forearm, Class::Background),
        "cut off at the elbow"
    );
    assert!(all(&s, &out, object, Class::Background));
    let out = run(&bridged);
    assert!(
        all(&s, &out, forearm, Class::LowerArms),
        "joined through the elbow"
    );
    assert!(
        all(&s, &out, object, Class::Background),
        "nothing joins the object"
    );
}

#[test]
fn merge_into_background_takes_a_patch_on_a_wall_but_never_a_foot_on_the_floor() {
    let mut s = Scene::default();
    slab_body(&mut s);
    // A floor under the body with a foot standing on it (lower leg points in the floor's
    // layer), and a wall behind it with a patch the parser called forearm in it.
    let [_, foot, _, patch] = parts(
        &mut s,
        [
            ([-0.5, -0.5, 0.0], [0.5, 0.5, 0.04], Class::Background),
            ([0.2, 0.21, 0.01], [0.3, 0.27, 0.03], Class::LowerLegs),
            ([-0.5, 0.6, 0.2], [0.5, 0.64, 1.4], Class::Background),
            ([0.0, 0.61, 0.6], [0.1, 0.63, 0.7], Class::LowerArms),
        ],
    );
    let cloud = s.cloud();
    let boxes = [PersonBox::axis_aligned(0, [0.0, 0.1, 1.0], [0.6, 0.6, 1.0])];
    let m = contact("M");
    let into_background = RefineConfig {
        merge_into_background: true,
        ..m.clone()
    };
    let run = |cfg: &RefineConfig| refine(&cloud, &boxes, cfg).expect("valid").cloud.labels;
    // Off (the paper): both keep their labels.
    let out = run(&m);
    assert!(all(&s, &out, patch, Class::LowerArms));
    assert!(all(&s, &out, foot, Class::LowerLegs));
    // On: the patch goes to the wall, the foot stays a foot.
    let out = run(&into_background);
    assert!(all(&s, &out, patch, Class::Background), "patch on the wall");
    assert!(all(&s, &out, foot, Class::LowerLegs), "foot on the floor");
}

#[test]
fn foreign_colors_take_an_object_labelled_forearm_off_the_arm_and_leave_the_arm() {
    let mut s = Scene::default();
    let torso = slab_body(&mut s);
    // An arm held out from the body's side, and an orange bar (a robot link) the parser
    // also called forearm, touching the hand: one forearm cluster with it.
    let [upper, forearm, bar] = parts(
        &mut s,
        [
            ([0.17, -0.04, 1.2], [0.21, 0.0, 1.48], Class::UpperArms),
            ([0.21, -0.04, 1.2], [0.45, 0.0, 1.24], Class::LowerArms),
            ([0.47, -0.1, 1.16], [0.55, 0.3, 1.24], Class::LowerArms),
        ],
    );
    let mut cloud = s.cloud();
    let (skin, shirt, orange) = ([200, 150, 120], [40, 60, 160], [215, 115, 15]);
    let mut colors = vec![skin; cloud.len()];
    for (p, c) in [
        (torso, shirt),
        (upper, shirt),
        (forearm, skin),
        (bar, orange),
    ] {
        colors[s.parts[p].clone()].fill(c);
    }
    cloud.colors = Some(colors);
    let boxes = [PersonBox::axis_aligned(
        0,
        [0.15, 0.1, 1.2],
        [0.5, 0.5, 0.6],
    )];
    let off = contact("M-R-N");
    let on = RefineConfig {
        foreign_color_density: 0.03,
        ..off.clone()
    };
    let run = |cfg: &RefineConfig| refine(&cloud, &boxes, cfg).expect("valid").cloud.labels;
    // Off: the bar is part of the arm's chain and stays forearm.
    let out = run(&off);
    assert!(all(&s, &out, bar, Class::LowerArms));
    // On: the bar is background; the arm (shirt sleeve, skin forearm) stays.
    let out = run(&on);
    assert!(all(&s, &out, bar, Class::Background), "the orange bar");
    assert!(all(&s, &out, forearm, Class::LowerArms), "the skin forearm");
    assert!(all(&s, &out, upper, Class::UpperArms), "the sleeve");
    assert!(all(&s, &out, torso, Class::Torso));

    // Without colors the mode cannot run: a clear error, not a silent skip.
    cloud.colors = None;
    let err = refine(&cloud, &boxes, &on).expect_err("no colors");
    assert!(matches!(err, RefineError::NoColors { .. }), "{err}");
    assert!(err.to_string().contains("foreign_color_density"), "{err}");
}

#[test]
fn foreign_colors_leave_a_hand_reaching_into_another_persons_box_to_its_owner() {
    // Person A at x = 0 (skin A, blue shirt); person B at x = 0.8 (skin B, green shirt), its
    // forearm reaching into A's box, nearer A's box centre than B's. Half of the forearm's
    // points have no projected label (DSA left them unknown), so where A and B disagree the
    // projected label cannot settle it.
    let mut s = Scene::default();
    let torso_a = slab_body(&mut s);
    let torso_b = s.add(cuboid(
        [0.65, -0.1, 0.9],
        [0.95, 0.1, 1.5],
        0.02,
        l(Class::Torso),
    ));
    let head_b = s.add(ball([0.8, 0.0, 1.6], 0.08, 0.02, l(Class::Head)));
    let [upper_b, forearm_b] = parts(
        &mut s,
        [
            ([0.45, -0.04, 1.2], [0.63, 0.0, 1.24], Class::UpperArms),
            ([0.21, -0.04, 1.2], [0.43, 0.0, 1.24], Class::LowerArms),
        ],
    );
    let mut cloud = s.cloud();
    let forearm = s.parts[forearm_b].clone();
    // (Its hand end only: next to B's upper arm, N would give them B's upper-arm label.)
    for i in forearm.clone().step_by(2) {
        if cloud.positions_m[i][0] < 0.35 {
            cloud.labels[i] = Label::UNKNOWN;
        }
    }
    let (skin_a, shirt_a) = ([200, 150, 120], [40, 60, 160]);
    let (skin_b, shirt_b) = ([170, 110, 70], [40, 160, 60]);
    let mut colors = vec![skin_a; cloud.len()];
    for (p, c) in [
        (torso_a, shirt_a),
        (torso_b, shirt_b),
        (head_b, skin_b),
        (upper_b, shirt_b),
        (forearm_b, skin_b),
    ] {
        colors[s.parts[p].clone()].fill(c);
    }
    cloud.colors = Some(colors);
    let boxes = [
        PersonBox::axis_aligned(0, [0.0, 0.0, 1.0], [0.45, 0.3, 1.0]),
        PersonBox::axis_aligned(1, [0.8, 0.0, 1.0], [0.65, 0.3, 1.0]),
    ];
    let cfg = RefineConfig {
        foreign_color_density: 0.03,
        ..contact("M-N")
    };
    let out = refine(&cloud, &boxes, &cfg).expect("valid").cloud.labels;
    // A does not wear B's skin and abstains; B does and keeps its forearm.
    assert!(all(&s, &out, forearm_b, Class::LowerArms), "B's forearm");
    assert!(all(&s, &out, upper_b, Class::UpperArms));
    assert!(all(&s, &out, torso_a, Class::Torso));
}
