//! bodyseg-eval against scikit-learn: confusion matrix and per-class IoU (jaccard_score),
//! precision, recall and F1 with `average=None, labels=range(7), zero_division=0`, from
//! `tests/data/sklearn_fixture.json` (made by `scripts/gen_eval_fixture.py`).

use bodyseg_core::{Class, NUM_CLASSES};
use bodyseg_eval::{ConfusionMatrix, Metrics};
use serde::Deserialize;

/// Both sides divide the same integers in f64; 1e-12 only allows for the fixture's decimal
/// round trip (Python repr → serde_json parse) and a different order of operations.
const TOL: f64 = 1e-12;

#[derive(Deserialize)]
struct Fixture {
    labels: Vec<u8>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    y_true: Vec<u8>,
    y_pred: Vec<u8>,
    confusion_matrix: [[u64; NUM_CLASSES]; NUM_CLASSES],
    jaccard: [f64; NUM_CLASSES],
    precision: [f64; NUM_CLASSES],
    recall: [f64; NUM_CLASSES],
    f1: [f64; NUM_CLASSES],
}

fn fixture() -> Fixture {
    serde_json::from_str(include_str!("data/sklearn_fixture.json"))
        .expect("tests/data/sklearn_fixture.json parses")
}

fn class(id: u8) -> Class {
    Class::from_id(id).expect("fixture labels are 0..7")
}

fn matrix_of(case: &Case) -> ConfusionMatrix {
    assert_eq!(case.y_true.len(), case.y_pred.len(), "{}", case.name);
    let mut m = ConfusionMatrix::new();
    for (&t, &p) in case.y_true.iter().zip(&case.y_pred) {
        m.add(class(t), class(p));
    }
    m
}

fn assert_close(ours: Option<f64>, sklearn: f64, what: &str) {
    // Absent classes are None here and 0 (zero_division) in scikit-learn.
    let ours = ours.unwrap_or(0.0);
    assert!(
        (ours - sklearn).abs() <= TOL,
        "{what}: ours {ours}, scikit-learn {sklearn}"
    );
}

/// Mean over the present classes among `classes`, computed from scikit-learn's arrays.
fn sklearn_mean(
    values: &[f64; NUM_CLASSES],
    present: &[bool; NUM_CLASSES],
    classes: &[Class],
) -> f64 {
    let kept: Vec<f64> = classes
        .iter()
        .filter(|c| present[c.index()])
        .map(|c| values[c.index()])
        .collect();
    kept.iter().sum::<f64>() / kept.len() as f64
}

#[test]
fn fixture_covers_the_edge_cases() {
    let f = fixture();
    assert_eq!(f.labels, (0..7).collect::<Vec<u8>>());
    let mut absent_from_both = false;
    let mut only_predicted = false;
    let mut never_predicted = false;
    for case in &f.cases {
        for c in 0..NUM_CLASSES {
            let row: u64 = case.confusion_matrix[c].iter().sum();
            let col: u64 = case.confusion_matrix.iter().map(|r| r[c]).sum();
            absent_from_both |= row == 0 && col == 0;
            only_predicted |= row == 0 && col > 0;
            never_predicted |= row > 0 && col == 0;
        }
    }
    assert!(absent_from_both && only_predicted && never_predicted);
}

#[test]
fn confusion_matrix_equals_sklearn() {
    for case in fixture().cases {
        let m = matrix_of(&case);
        assert_eq!(m.counts(), &case.confusion_matrix, "case {}", case.name);
        assert_eq!(m.total(), case.y_true.len() as u64, "case {}", case.name);
    }
}

#[test]
fn per_class_metrics_equal_sklearn() {
    for case in fixture().cases {
        let metrics = Metrics::from_matrix(&matrix_of(&case));
        for c in Class::ALL {
            let i = c.index();
            let ours = metrics.class(c);
            let what = |metric: &str| format!("case {} class {c} {metric}", case.name);
            assert_close(ours.iou, case.jaccard[i], &what("IoU"));
            assert_close(ours.precision, case.precision[i], &what("precision"));
            assert_close(ours.recall, case.recall[i], &what("recall"));
            assert_close(ours.f1, case.f1[i], &what("F1"));
        }
    }
}

#[test]
fn means_leave_absent_classes_out() {
    let mut saw_absent = false;
    for case in fixture().cases {
        let metrics = Metrics::from_matrix(&matrix_of(&case));
        let cm = &case.confusion_matrix;
        let present: [bool; NUM_CLASSES] = std::array::from_fn(|c| {
            cm[c].iter().sum::<u64>() + cm.iter().map(|r| r[c]).sum::<u64>() > 0
        });
        for c in Class::ALL {
            let ours = metrics.class(c);
            assert_eq!(
                ours.present,
                present[c.index()],
                "case {} class {c}",
                case.name
            );
            if !ours.present {
                saw_absent = true;
                assert_eq!(
                    (ours.iou, ours.precision, ours.recall, ours.f1),
                    (None, None, None, None),
                    "case {} class {c}",
                    case.name
                );
            }
        }
        let check = |name: &str, ours: Option<f64>, want: f64| {
            let ours = ours.expect("every case has a present body class");
            assert!(
                (ours - want).abs() <= TOL,
                "case {} {name}: ours {ours}, by hand {want}",
                case.name
            );
        };
        let mean = |per_class: &[f64; NUM_CLASSES], classes: &[Class]| {
            sklearn_mean(per_class, &present, classes)
        };
        check("mIoU", metrics.miou, mean(&case.jaccard, &Class::ALL));
        check("BIoU", metrics.biou, mean(&case.jaccard, &Class::BODY));
        check("AP", metrics.ap, mean(&case.precision, &Class::ALL));
        check("F1", metrics.f1, mean(&case.f1, &Class::ALL));
        // Where a class is absent, the plain 7-class mean (sklearn's average="macro" with
        // labels=range(7)) is lower: proof that leaving it out changed something.
        if present.contains(&false) {
            let macro_7 = case.jaccard.iter().sum::<f64>() / 7.0;
            assert!(
                metrics.miou.is_some_and(|m| m > macro_7 + 1e-3),
                "case {}",
                case.name
            );
        }
    }
    assert!(saw_absent, "the fixture has an absent class");
}
