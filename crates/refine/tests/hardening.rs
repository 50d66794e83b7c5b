//! Bad numbers never panic or hang (issue 27): radii far below the f32 resolution of the
//! cloud or far beyond a person, points kilometres away inside a box, counts out of reason.
//! Each case panicked or never ended before the grids were made overflow-safe and the
//! configuration range-checked.

use bodyseg_core::{Class, Label, LabeledCloud, PersonBox};
use bodyseg_refine::{
    DbscanParams, RefineConfig, dbscan, dbscan_brute_force, refine, smooth_labels,
};
use bodyseg_testkit::human_cloud;
use std::sync::mpsc;
use std::time::Duration;

/// Runs `f` on another thread and fails the test when it does not end within `secs`
/// (a hang must fail, not block the test run). A panic inside `f` fails the test too.
fn within<T: Send + 'static>(secs: u64, what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(Duration::from_secs(secs)) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: still running after {secs} s"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: panicked"),
    }
}

fn error_of(cloud: LabeledCloud, boxes: Vec<PersonBox>, cfg: RefineConfig) -> String {
    within(60, "refine", move || match refine(&cloud, &boxes, &cfg) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    })
}

#[test]
fn an_eps_below_the_clouds_resolution_is_an_error_naming_eps_m() {
    let p = human_cloud(20_000, 3);
    let cfg = RefineConfig {
        eps_m: 1e-7,
        ..Default::default()
    };
    let e = error_of(p.cloud, vec![p.person_box], cfg);
    assert!(e.starts_with("refine.eps_m"), "{e}");
    assert!(e.contains("extent"), "the message says why: {e}");
}

#[test]
fn dbscan_with_a_tiny_eps_ends_and_equals_brute_force() {
    // Called directly (no configuration check): every point is noise, and nothing
    // overflows however many cells the eps makes.
    let p = human_cloud(1_500, 4);
    for eps_m in [1e-7, 1e-12, f32::MIN_POSITIVE] {
        let params = DbscanParams {
            eps_m,
            min_points: 2,
            label_penalty_m: f32::INFINITY,
        };
        let (pos, lab) = (p.cloud.positions_m.clone(), p.cloud.labels.clone());
        let fast = within(60, "dbscan", move || dbscan(&pos, &lab, &params));
        let slow = dbscan_brute_force(&p.cloud.positions_m, &p.cloud.labels, &params);
        assert_eq!(fast, slow, "eps {eps_m}");
    }
}

/// A person plus two stray points 120 km away on every axis, all inside one box.
fn person_with_far_outliers() -> (LabeledCloud, PersonBox, usize) {
    let p = human_cloud(3_000, 5);
    let mut cloud = p.cloud.clone();
    let head = Label::from(Class::Head);
    for s in [1.0f32, -1.0] {
        cloud
            .positions_m
            .push([s * 120_000.0, s * 120_000.0, 120_000.0]);
        cloud.labels.push(head);
        cloud.origins.push(bodyseg_core::PointOrigin {
            camera: 0,
            pixel: cloud.origins.len() as u32,
        });
    }
    let person_box = PersonBox::axis_aligned(0, [0.0, 0.0, 0.0], [130_000.0, 130_000.0, 130_000.0]);
    (cloud, person_box, p.cloud.len())
}

#[test]
fn points_120_km_away_inside_a_box_are_clustered_exactly() {
    let (cloud, person_box, n) = person_with_far_outliers();
    let params = RefineConfig::default().dbscan_params();
    let (pos, lab) = (cloud.positions_m.clone(), cloud.labels.clone());
    let fast = within(60, "dbscan", move || dbscan(&pos, &lab, &params));
    let slow = dbscan_brute_force(&cloud.positions_m, &cloud.labels, &params);
    assert_eq!(fast, slow);
    assert_eq!(fast.cluster_of[n..], [None, None], "the strays are noise");
    // The whole refinement runs on them (the strays take the nearest cluster's label).
    let boxes = vec![person_box];
    let refined = within(60, "refine", move || {
        refine(&cloud, &boxes, &RefineConfig::default()).map(|r| r.cloud.labels.len())
    });
    assert_eq!(refined.ok(), Some(n + 2));
}

#[test]
fn radii_beyond_a_few_metres_are_errors_naming_the_field() {
    let p = human_cloud(5_000, 6);
    let base = RefineConfig::default();
    for (field, cfg) in [
        (
            "smooth_radius_m",
            RefineConfig {
                smooth_radius_m: 1e20,
                ..base.clone()
            },
        ),
        (
            "noise_doubt_radius_m",
            RefineConfig {
                noise_doubt_radius_m: 1e20,
                ..base.clone()
            },
        ),
        (
            "eps_m",
            RefineConfig {
                eps_m: 1e6,
                ..base.clone()
            },
        ),
        (
            "contact_gap_m",
            RefineConfig {
                contact_gap_m: 1e9,
                ..base.clone()
            },
        ),
        (
            "floor_contact_m",
            RefineConfig {
                floor_contact_m: 1e30,
                ..base.clone()
            },
        ),
    ] {
        let e = error_of(p.cloud.clone(), vec![p.person_box.clone()], cfg);
        assert!(
            e.starts_with(&format!("refine.{field} must be")),
            "{field}: {e}"
        );
    }
}

#[test]
fn counts_out_of_reason_are_errors_naming_the_field() {
    let base = RefineConfig::default();
    for (field, cfg) in [
        (
            "min_points",
            RefineConfig {
                min_points: usize::MAX,
                ..base.clone()
            },
        ),
        (
            "noise_k",
            RefineConfig {
                noise_k: usize::MAX,
                ..base.clone()
            },
        ),
        (
            "noise_doubt_k",
            RefineConfig {
                noise_doubt_k: 1 << 40,
                ..base.clone()
            },
        ),
    ] {
        let e = cfg
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.starts_with(&format!("refine.{field} must be")),
            "{field}: {e}"
        );
    }
}

#[test]
fn smoothing_with_a_huge_radius_ends_and_gives_every_body_point_the_majority() {
    // Called directly (no configuration check): every body point is within the radius of
    // every other, so all take the label most of them carry.
    let p = human_cloud(4_000, 7);
    let (pos, lab) = (p.cloud.positions_m.clone(), p.cloud.labels.clone());
    let out = within(60, "smooth_labels", move || smooth_labels(&pos, &lab, 1e20));
    let mut counts = [0usize; 7];
    for l in &p.cloud.labels {
        if l.is_body() {
            counts[usize::from(l.id())] += 1;
        }
    }
    let majority = (1..7).max_by_key(|&c| (counts[c], std::cmp::Reverse(c)));
    for (o, l) in out.iter().zip(&p.cloud.labels) {
        if l.is_body() {
            assert_eq!(Some(usize::from(o.id())), majority);
        } else {
            assert_eq!(o, l, "background and unknown keep their label");
        }
    }
}
