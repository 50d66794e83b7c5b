//! DBSCAN against the O(n²) brute-force reference on seeded random cases.
//! Seed: `BODYSEG_TEST_SEED` (default 20261122), printed on failure.

use bodyseg_core::{Class, Label};
use bodyseg_refine::{DbscanParams, dbscan, dbscan_brute_force};
use bodyseg_testkit::{human_cloud, random_cloud, rng};
use rand::Rng;

fn base_seed() -> u64 {
    std::env::var("BODYSEG_TEST_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_261_122)
}

#[test]
fn dbscan_equals_brute_force_on_200_seeded_cases() {
    let seed = base_seed();
    let mut r = rng(seed);
    let all_labels: Vec<Label> = Class::ALL
        .iter()
        .map(|&c| Label::from(c))
        .chain([Label::UNKNOWN])
        .collect();
    let mut stats = [0usize; 4]; // cases with: clusters, noise, border points, finite penalty
    for case in 0..200 {
        // Sizes from 0 to 3000, small ones more often.
        let n = match case % 10 {
            0 => case % 3,
            1..=5 => r.random_range(1..300),
            6..=8 => r.random_range(300..1500),
            _ => r.random_range(1500..=3000),
        };
        let nlab = r.random_range(1..=all_labels.len());
        let labels = &all_labels[..nlab];
        let dup = if case % 4 == 0 { 0.3 } else { 0.02 };
        let side = 1.0f32;
        let (pos, lab) = random_cloud(&mut r, n, side, labels, dup);
        let min_points = match case % 7 {
            0 => 1,
            1 => n + 1 + r.random_range(0..3),
            _ => r.random_range(2..60),
        };
        // eps so that a point expects about 0.3–3× min_points neighbours of its label.
        let per_label = (n.max(1) as f32 / nlab as f32).max(1.0);
        let want = min_points as f32 * r.random_range(0.3f32..3.0);
        let eps = (want / per_label * side.powi(3) * 3.0 / (4.0 * std::f32::consts::PI))
            .cbrt()
            .clamp(0.005, 0.6);
        let label_penalty_m = if case % 5 == 0 {
            eps * r.random_range(0.0f32..1.0)
        } else {
            f32::INFINITY
        };
        let params = DbscanParams {
            eps_m: eps,
            min_points,
            label_penalty_m,
        };
        let fast = dbscan(&pos, &lab, &params);
        let slow = dbscan_brute_force(&pos, &lab, &params);
        assert_eq!(
            fast, slow,
            "seed {seed} case {case}: n={n} labels={nlab} eps={eps} min_points={min_points} penalty={label_penalty_m}"
        );
        stats[0] += usize::from(fast.num_clusters() > 0);
        stats[1] += usize::from(fast.num_noise() > 0);
        let border = fast
            .cluster_of
            .iter()
            .zip(&fast.is_core)
            .any(|(c, &core)| c.is_some() && !core);
        stats[2] += usize::from(border);
        stats[3] += usize::from(label_penalty_m.is_finite());
    }
    // The cases must actually exercise every part of the definition.
    assert!(
        stats.iter().all(|&s| s >= 20),
        "too few interesting cases: {stats:?}"
    );
}

#[test]
fn dbscan_on_a_human_cloud_equals_brute_force_and_ignores_point_order() {
    let person = human_cloud(3000, 5);
    let params = DbscanParams {
        eps_m: 0.06,
        min_points: 8,
        label_penalty_m: f32::INFINITY,
    };
    let (pos, lab) = (&person.cloud.positions_m, &person.cloud.labels);
    let fast = dbscan(pos, lab, &params);
    assert_eq!(fast, dbscan_brute_force(pos, lab, &params));
    assert!(fast.num_clusters() >= 7, "{} clusters", fast.num_clusters());

    // Reverse the order: the same points must be grouped the same way.
    let rev_pos: Vec<_> = pos.iter().rev().copied().collect();
    let rev_lab: Vec<_> = lab.iter().rev().copied().collect();
    let rev = dbscan(&rev_pos, &rev_lab, &params);
    let n = pos.len();
    let mut map = std::collections::HashMap::new();
    for i in 0..n {
        let a = fast.cluster_of[i];
        let b = rev.cluster_of[n - 1 - i];
        assert_eq!(fast.is_core[i], rev.is_core[n - 1 - i]);
        assert_eq!(a.is_some(), b.is_some(), "point {i}");
        if let (Some(a), Some(b)) = (a, b) {
            assert_eq!(*map.entry(a).or_insert(b), b, "point {i} changed cluster");
        }
    }
}

#[test]
fn unknown_points_are_always_noise_and_label_groups_never_mix() {
    // Two touching blobs of different labels and a blob of unknown points.
    let mut pos = Vec::new();
    let mut lab = Vec::new();
    for i in 0..200 {
        let t = i as f32 * 0.001;
        pos.push([t, 0.0, 0.0]);
        lab.push(Label::from(Class::Head));
        pos.push([t, 0.001, 0.0]);
        lab.push(Label::from(Class::Torso));
        pos.push([t, 0.0, 0.001]);
        lab.push(Label::UNKNOWN);
    }
    let params = DbscanParams {
        eps_m: 0.01,
        min_points: 3,
        label_penalty_m: f32::INFINITY,
    };
    let c = dbscan(&pos, &lab, &params);
    assert_eq!(c.num_clusters(), 2);
    assert_eq!(
        c.cluster_labels,
        vec![Label::from(Class::Head), Label::from(Class::Torso)]
    );
    for (i, l) in lab.iter().enumerate() {
        if l.is_unknown() {
            assert_eq!(c.cluster_of[i], None);
            assert!(!c.is_core[i]);
        }
    }
    // A penalty below eps lets the two labels join into one cluster.
    let mixed = dbscan(
        &pos,
        &lab,
        &DbscanParams {
            label_penalty_m: 0.005,
            ..params
        },
    );
    assert_eq!(mixed.num_clusters(), 1);
}

#[test]
fn a_border_point_equidistant_from_two_clusters_joins_the_smaller_core_index() {
    let head = Label::from(Class::Head);
    let line = |sign: f32| -> Vec<[f32; 3]> {
        [1.0, 1.25, 1.5, 1.75]
            .iter()
            .map(|&x| [sign * x, 0.0, 0.0])
            .collect()
    };
    let params = DbscanParams {
        eps_m: 1.0,
        min_points: 4,
        label_penalty_m: f32::INFINITY,
    };
    for right_first in [true, false] {
        let (first, second) = if right_first {
            (line(1.0), line(-1.0))
        } else {
            (line(-1.0), line(1.0))
        };
        let mut pos = first.clone();
        pos.extend(&second);
        pos.push([0.0, 0.0, 0.0]);
        let lab = vec![head; pos.len()];
        let c = dbscan(&pos, &lab, &params);
        assert_eq!(c, dbscan_brute_force(&pos, &lab, &params));
        assert_eq!(c.num_clusters(), 2);
        assert!(!c.is_core[8] && c.cluster_of[8].is_some());
        // Both clusters hold a core point at distance exactly 1; index 0 wins.
        assert_eq!(
            c.cluster_of[8], c.cluster_of[0],
            "right_first={right_first}"
        );
    }
}
