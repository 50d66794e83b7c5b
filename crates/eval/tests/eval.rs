//! Matching, merging and reports, against naive references where there is one.

use bodyseg_core::rng::SplitMix64;
use bodyseg_core::{Class, Label, LabeledCloud, PointOrigin};
use bodyseg_eval::{
    CloudRole, ConfusionMatrix, EvalError, MatchStats, Metrics, PointCounts, Report, match_clouds,
    score_aligned,
};

/// Seed of the randomised tests; override with `BODYSEG_TEST_SEED=<u64>` to reproduce.
fn seed() -> u64 {
    std::env::var("BODYSEG_TEST_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5eed_b0d7)
}

/// SplitMix64 (core's), enough for test data, with draws of classes and labels.
struct Rng(SplitMix64);

impl Rng {
    fn below(&mut self, n: u64) -> u64 {
        self.0.below(n)
    }
    fn class(&mut self) -> Class {
        Class::ALL[self.below(7) as usize]
    }
    /// A class label, or unknown one time in eight.
    fn label(&mut self) -> Label {
        if self.below(8) == 0 {
            Label::UNKNOWN
        } else {
            Label::from(self.class())
        }
    }
    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, self.below(i as u64 + 1) as usize);
        }
    }
}

fn origin(camera: u8, pixel: u32) -> PointOrigin {
    PointOrigin { camera, pixel }
}

fn cloud(points: &[(PointOrigin, Label)]) -> LabeledCloud {
    LabeledCloud {
        positions_m: vec![[0.0; 3]; points.len()],
        labels: points.iter().map(|p| p.1).collect(),
        colors: None,
        origins: points.iter().map(|p| p.0).collect(),
    }
}

fn stats_of(pairs: &[(Class, Class)]) -> MatchStats {
    MatchStats {
        confusion: pairs.iter().copied().collect(),
        counts: PointCounts::default(),
    }
}

/// O(n·m) reference for `match_clouds`: for every ground-truth point, scan the prediction.
fn naive_match(pred: &[(PointOrigin, Label)], gt: &[(PointOrigin, Label)]) -> MatchStats {
    let mut s = MatchStats::default();
    for &(o, g) in gt {
        let p = pred.iter().find(|q| q.0 == o).map(|q| q.1);
        match (g.class(), p) {
            (None, _) => s.counts.gt_unknown += 1,
            (Some(_), None) => s.counts.gt_unmatched += 1,
            (Some(g), Some(p)) => {
                if p.is_unknown() {
                    s.counts.pred_unknown += 1;
                }
                s.confusion.add(g, p.class().unwrap_or(Class::Background));
            }
        }
    }
    s.counts.pred_unmatched = pred
        .iter()
        .filter(|p| !gt.iter().any(|g| g.0 == p.0))
        .count() as u64;
    s
}

/// The Markdown table row right under the row of configuration `name` (its change row)
/// starts with `want`.
fn assert_row_under(md: &str, name: &str, want: &str) {
    let mut lines = md.lines();
    let start = format!("| {name} |");
    lines
        .position(|l| l.starts_with(&start))
        .unwrap_or_else(|| panic!("a {name} row: {md}"));
    let row = lines
        .next()
        .unwrap_or_else(|| panic!("a row under {name}: {md}"));
    assert!(row.starts_with(want), "{row}");
}

#[test]
fn merged_matrices_equal_the_matrix_of_the_concatenated_data() {
    let seed = seed();
    let mut rng = Rng(SplitMix64::new(seed));
    for trial in 0..50 {
        let a: Vec<(Class, Class)> = (0..rng.below(300))
            .map(|_| (rng.class(), rng.class()))
            .collect();
        let b: Vec<(Class, Class)> = (0..rng.below(300))
            .map(|_| (rng.class(), rng.class()))
            .collect();
        let ma: ConfusionMatrix = a.iter().copied().collect();
        let mb: ConfusionMatrix = b.iter().copied().collect();
        let whole: ConfusionMatrix = a.iter().chain(&b).copied().collect();

        let mut merged = ma.clone();
        merged.merge(&mb);
        assert_eq!(merged, whole, "seed {seed} trial {trial}");
        let mut summed = mb.clone();
        summed += ma.clone();
        assert_eq!(
            summed, whole,
            "merge is commutative; seed {seed} trial {trial}"
        );
        assert_eq!(
            ma.checked_merge(&mb),
            Some(whole.clone()),
            "seed {seed} trial {trial}"
        );
        assert_eq!(merged.total(), (a.len() + b.len()) as u64);
        assert_eq!(Metrics::from_matrix(&merged), Metrics::from_matrix(&whole));
    }
}

#[test]
fn match_clouds_is_independent_of_order_and_agrees_with_brute_force() {
    let seed = seed();
    let mut rng = Rng(SplitMix64::new(seed));
    for trial in 0..30 {
        // Ground truth over two cameras; the prediction covers most of the same pixels,
        // misses some, and has a few of its own.
        let mut gt = Vec::new();
        let mut pred = Vec::new();
        for camera in 0..2u8 {
            for pixel in 0..(50 + rng.below(150) as u32) {
                let o = origin(camera, pixel);
                match rng.below(10) {
                    0 => gt.push((o, rng.label())),   // only in ground truth
                    1 => pred.push((o, rng.label())), // only in prediction
                    _ => {
                        let g = rng.label();
                        gt.push((o, g));
                        // Mostly right, sometimes wrong or unknown.
                        let p = if rng.below(3) == 0 { rng.label() } else { g };
                        pred.push((o, p));
                    }
                }
            }
        }
        let want = naive_match(&pred, &gt);
        let in_order = match_clouds(&cloud(&pred), &cloud(&gt)).expect("no duplicates");
        assert_eq!(in_order, want, "seed {seed} trial {trial}");

        rng.shuffle(&mut pred);
        rng.shuffle(&mut gt);
        let shuffled = match_clouds(&cloud(&pred), &cloud(&gt)).expect("no duplicates");
        assert_eq!(shuffled, want, "seed {seed} trial {trial}");

        // Every ground-truth point is evaluated, unknown, or unmatched.
        let c = shuffled.counts;
        assert_eq!(
            shuffled.evaluated() + c.gt_unknown + c.gt_unmatched,
            gt.len() as u64,
            "seed {seed} trial {trial}"
        );
    }
}

#[test]
fn score_aligned_equals_match_clouds_on_the_same_points() {
    let seed = seed();
    let mut rng = Rng(SplitMix64::new(seed ^ 0xa11));
    for trial in 0..20 {
        let n = 50 + rng.below(300) as u32;
        let gt: Vec<(PointOrigin, Label)> = (0..n).map(|p| (origin(0, p), rng.label())).collect();
        let pred: Vec<(PointOrigin, Label)> = gt
            .iter()
            .map(|&(o, g)| (o, if rng.below(3) == 0 { rng.label() } else { g }))
            .collect();
        let want = match_clouds(&cloud(&pred), &cloud(&gt)).expect("no duplicates");
        let p: Vec<Label> = pred.iter().map(|x| x.1).collect();
        let g: Vec<Label> = gt.iter().map(|x| x.1).collect();
        assert_eq!(
            score_aligned(&p, &g).expect("same length"),
            want,
            "seed {seed} trial {trial}"
        );
    }
    let e = score_aligned(&[Label::UNKNOWN], &[]).expect_err("lengths differ");
    assert!(
        matches!(e, EvalError::AlignedLengths { pred: 1, gt: 0 }),
        "{e}"
    );
}

#[test]
fn match_clouds_hand_example() {
    let head = Label::from(Class::Head);
    let torso = Label::from(Class::Torso);
    let gt = cloud(&[
        (origin(0, 1), head),
        (origin(0, 2), torso),
        (origin(1, 1), Label::UNKNOWN), // not evaluated
        (origin(1, 2), head),           // no prediction
        (origin(0, 3), Label::BACKGROUND),
    ]);
    let pred = cloud(&[
        (origin(0, 3), Label::BACKGROUND),
        (origin(0, 2), Label::UNKNOWN), // scored as background
        (origin(1, 1), head),           // gt unknown: ignored
        (origin(2, 9), head),           // no ground truth
        (origin(0, 1), head),
    ]);
    let s = match_clouds(&pred, &gt).expect("valid clouds");
    assert_eq!(s.evaluated(), 3);
    assert_eq!(s.confusion.get(Class::Head, Class::Head), 1);
    assert_eq!(s.confusion.get(Class::Torso, Class::Background), 1);
    assert_eq!(s.confusion.get(Class::Background, Class::Background), 1);
    assert_eq!(
        s.counts,
        PointCounts {
            pred_unknown: 1,
            gt_unknown: 1,
            gt_unmatched: 1,
            pred_unmatched: 1,
        }
    );
}

#[test]
fn duplicate_origins_are_errors_naming_the_cloud_and_key() {
    let head = Label::from(Class::Head);
    let ok = cloud(&[(origin(0, 1), head), (origin(0, 2), head)]);
    let dup = cloud(&[
        (origin(0, 1), head),
        (origin(3, 7), head),
        (origin(3, 7), head),
    ]);

    // A duplicate in either cloud: the error names that cloud, the key and both points.
    for (pred, gt, role, named) in [
        (&ok, &dup, CloudRole::GroundTruth, "ground-truth cloud"),
        (&dup, &ok, CloudRole::Prediction, "predicted cloud"),
    ] {
        let err = match_clouds(pred, gt).expect_err("a duplicate origin");
        assert!(
            matches!(
                err,
                EvalError::DuplicateOrigin {
                    cloud,
                    camera: 3,
                    pixel: 7,
                    first: 1,
                    second: 2,
                } if cloud == role
            ),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(
            message.contains(named) && message.contains("camera 3, pixel 7"),
            "{message}"
        );
    }
}

#[test]
fn mismatched_array_lengths_are_errors() {
    let mut bad = cloud(&[(origin(0, 1), Label::BACKGROUND)]);
    bad.labels.push(Label::BACKGROUND);
    let err = match_clouds(&bad, &cloud(&[])).expect_err("2 labels, 1 origin");
    assert!(
        matches!(
            err,
            EvalError::LengthMismatch {
                cloud: CloudRole::Prediction,
                labels: 2,
                origins: 1
            }
        ),
        "{err:?}"
    );
}

/// Reference: perfect except one torso point; M: fixes it but mislabels a head point.
fn two_config_report() -> Report {
    let mut reference = vec![(Class::Head, Class::Head); 10];
    reference.extend([(Class::Torso, Class::Torso); 9]);
    reference.push((Class::Torso, Class::Background));
    reference.extend([(Class::Background, Class::Background); 20]);
    let mut m = vec![(Class::Head, Class::Head); 9];
    m.push((Class::Head, Class::Torso));
    m.extend([(Class::Torso, Class::Torso); 10]);
    m.extend([(Class::Background, Class::Background); 20]);

    let mut report = Report::new();
    let mut stats = stats_of(&reference);
    stats.counts.gt_unmatched = 4;
    report.push("Reference", stats).expect("new name");
    report.push("M", stats_of(&m)).expect("new name");
    report
}

#[test]
fn markdown_has_paper_layout_and_signed_change_rows() {
    let md = two_config_report().to_markdown();
    println!("{md}");
    assert!(md.contains(
        "| Configuration | Head | Torso | Upper arms | Lower arms | Upper legs | Lower legs | Background | mIoU | BIoU | AP | F1 |"
    ));
    // Reference head IoU 100 %, torso 90 %; M head 90 %, torso 10/11.
    assert!(
        md.contains("| Reference | 100.00 | 90.00 | – | – | – | – | 95.24 |"),
        "{md}"
    );
    // Head 100 → 90 (-10.00), torso 90 → 90.91 (+0.91), background 20/21 → 100 (+4.76).
    let delta = "| Δ vs Reference | -10.00 | +0.91 | – | – | – | – | +4.76 |";
    assert_row_under(&md, "M", delta);
    // Only one change row: none under the reference itself.
    assert_eq!(md.matches("Δ vs Reference").count(), 1);
    // Both configurations lack the same classes: named once.
    assert!(
        md.contains("Left out of mIoU, BIoU, AP and F1 (absent from both prediction and ground truth, shown as –): Upper arms, Lower arms, Upper legs, Lower legs."),
        "{md}"
    );
    // Points table says 4 ground-truth points had no prediction.
    assert!(md.contains("| Reference | 40 | 0 | 0 | 4 | 0 |"), "{md}");
}

#[test]
fn markdown_names_absent_classes_per_configuration_when_they_differ() {
    let mut report = two_config_report();
    // "N" predicts one background point as upper arms: upper arms is present there only.
    let mut n = vec![(Class::Head, Class::Head); 10];
    n.extend([(Class::Torso, Class::Torso); 10]);
    n.extend([(Class::Background, Class::Background); 19]);
    n.push((Class::Background, Class::UpperArms));
    report.push("N", stats_of(&n)).expect("new name");
    let md = report.to_markdown();
    assert!(
        md.contains("Reference: Upper arms, Lower arms, Upper legs, Lower legs; M: Upper arms, Lower arms, Upper legs, Lower legs; N: Lower arms, Upper legs, Lower legs."),
        "{md}"
    );
    // N's upper-arms IoU is 0 and has no reference to compare with.
    assert!(md.contains("| N | 100.00 | 100.00 | 0.00 | – |"), "{md}");
    assert_row_under(&md, "N", "| Δ vs Reference | 0.00 | +10.00 | – | – |");
}

#[test]
fn json_round_trip_keeps_matrices_counts_and_metrics() {
    let report = two_config_report();
    let json = report.to_json().expect("serializes");
    let value: serde_json::Value = serde_json::from_str(&json).expect("valid JSON");
    let first = &value["configurations"][0];
    assert_eq!(first["name"], "Reference");
    assert_eq!(first["confusion"]["counts"][2][0], 1); // torso predicted as background
    assert_eq!(first["points"]["evaluated"], 40);
    assert_eq!(first["points"]["gt_unmatched"], 4);
    assert!(first["metrics"]["per_class"][3]["iou"].is_null()); // upper arms absent
    assert_eq!(first["metrics"]["per_class"][3]["present"], false);
    assert!(first["metrics"]["miou"].is_f64());
    assert_eq!(value["classes"][0], "background");

    let back = Report::from_json(&json).expect("reads back");
    assert_eq!(back, report);
    // Also through serde directly, as when embedded in another document.
    let embedded: Report = serde_json::from_value(value).expect("deserializes");
    assert_eq!(embedded, report);
}

#[test]
fn from_json_recomputes_metrics_and_rejects_inconsistent_files() {
    let report = two_config_report();
    let mut value: serde_json::Value =
        serde_json::from_str(&report.to_json().expect("serializes")).expect("valid JSON");

    // Stored metrics are ignored: the matrix is authoritative.
    value["configurations"][0]["metrics"]["miou"] = serde_json::json!(0.123);
    let back = Report::from_json(&value.to_string()).expect("reads");
    assert_eq!(back, report);

    let mut bad = value.clone();
    bad["configurations"][0]["points"]["evaluated"] = serde_json::json!(41);
    assert!(matches!(
        Report::from_json(&bad.to_string()),
        Err(EvalError::InconsistentCounts {
            evaluated: 41,
            matrix_total: 40,
            ..
        })
    ));
    let mut bad = value.clone();
    bad["version"] = serde_json::json!(99);
    assert!(matches!(
        Report::from_json(&bad.to_string()),
        Err(EvalError::UnsupportedVersion { got: 99, .. })
    ));
    let mut bad = value.clone();
    bad["classes"][0] = serde_json::json!("head");
    assert!(matches!(
        Report::from_json(&bad.to_string()),
        Err(EvalError::ClassOrder { .. })
    ));
    let mut bad = value.clone();
    bad["configurations"][1]["name"] = serde_json::json!("Reference");
    assert!(matches!(
        Report::from_json(&bad.to_string()),
        Err(EvalError::DuplicateConfiguration { .. })
    ));
    let mut bad = value;
    bad["configurations"][0]["confusion"]["counts"][0] = serde_json::json!([1, 2]);
    assert!(matches!(
        Report::from_json(&bad.to_string()),
        Err(EvalError::Json { .. })
    ));
    assert!(matches!(
        Report::from_json("not json"),
        Err(EvalError::Json { .. })
    ));
}

#[test]
fn report_merge_sums_matrices_per_configuration() {
    let seed = seed();
    let mut rng = Rng(SplitMix64::new(seed));
    let names = ["Reference", "M", "N", "M-N", "M-R-N"];
    // The whole data set per configuration, split into 3 shards.
    let data: Vec<Vec<(Class, Class)>> = names
        .iter()
        .map(|_| (0..300).map(|_| (rng.class(), rng.class())).collect())
        .collect();
    let shards: Vec<Report> = (0..3)
        .map(|shard| {
            let mut r = Report::new();
            // Shards may list the configurations in any order.
            let mut order: Vec<usize> = (0..names.len()).collect();
            if shard == 1 {
                order.reverse();
            }
            for i in order {
                let part: Vec<_> = data[i].iter().skip(shard).step_by(3).copied().collect();
                let mut stats = stats_of(&part);
                stats.counts.pred_unmatched = 1;
                r.push(names[i], stats).expect("unique names");
            }
            r
        })
        .collect();

    let merged = Report::merge(&shards).expect("same configurations");
    assert_eq!(merged.names(), names.to_vec(), "first shard's order");
    for (i, name) in names.iter().enumerate() {
        let c = merged.get(name).expect("present");
        let whole: ConfusionMatrix = data[i].iter().copied().collect();
        assert_eq!(c.confusion(), &whole, "seed {seed} configuration {name}");
        assert_eq!(c.metrics(), &Metrics::from_matrix(&whole));
        assert_eq!(c.counts().pred_unmatched, 3);
    }

    // Through JSON, as shards written on different machines would be.
    let reread: Vec<Report> = shards
        .iter()
        .map(|r| Report::from_json(&r.to_json().expect("serializes")).expect("reads"))
        .collect();
    assert_eq!(Report::merge(&reread).expect("same configurations"), merged);
}

#[test]
fn report_merge_rejects_different_configuration_sets() {
    let a = two_config_report();
    let mut b = Report::new();
    b.push("Reference", stats_of(&[(Class::Head, Class::Head)]))
        .expect("new");
    b.push("N", stats_of(&[(Class::Head, Class::Head)]))
        .expect("new");
    let err = Report::merge([&a, &b]).expect_err("M vs N");
    assert!(
        matches!(err, EvalError::ConfigurationMismatch { index: 1, .. }),
        "{err:?}"
    );
    let mut c = Report::new();
    c.push("Reference", stats_of(&[])).expect("new");
    assert!(Report::merge([&a, &c]).is_err(), "a subset is a mismatch");
    assert!(matches!(Report::merge([]), Err(EvalError::NoReports)));
    assert!(matches!(
        a.clone().push("M", MatchStats::default()),
        Err(EvalError::DuplicateConfiguration { .. })
    ));
}

#[test]
fn report_merge_reports_overflow_instead_of_wrapping() {
    let mut big = ConfusionMatrix::new();
    big.add_count(Class::Head, Class::Head, u64::MAX);
    let mut a = Report::new();
    a.push(
        "Reference",
        MatchStats {
            confusion: big,
            counts: PointCounts::default(),
        },
    )
    .expect("new");
    let err = Report::merge([&a, &a]).expect_err("overflow");
    assert!(matches!(err, EvalError::CountOverflow { .. }), "{err:?}");
}
