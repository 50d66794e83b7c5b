//! Per-class and mean metrics derived from a confusion matrix.

use crate::confusion::ConfusionMatrix;
use bodyseg_core::{Class, NUM_CLASSES};
use serde::{Deserialize, Serialize};

/// The metrics of one class, fractions in `0..=1`.
///
/// With TP, FP, FN the class's true positives, false positives and false negatives:
/// IoU = TP/(TP+FP+FN), precision = TP/(TP+FP), recall = TP/(TP+FN), F1 = 2PR/(P+R).
/// A ratio with a zero denominator is 0 (scikit-learn's `zero_division=0`): a class that is
/// predicted but not in the ground truth has recall 0, a class in the ground truth that is
/// never predicted has precision 0.
///
/// A class absent from both ground truth and prediction (its row and column are all zero)
/// has `present == false` and every value `None` (JSON `null`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassMetrics {
    /// The class.
    pub class: Class,
    /// True when the class occurs in the ground truth or the prediction.
    pub present: bool,
    /// Ground-truth points of this class (row sum).
    pub support: u64,
    /// Points predicted as this class (column sum).
    pub predicted: u64,
    /// Intersection over union, TP/(TP+FP+FN).
    pub iou: Option<f64>,
    /// TP/(TP+FP).
    pub precision: Option<f64>,
    /// TP/(TP+FN).
    pub recall: Option<f64>,
    /// Harmonic mean of precision and recall, 2PR/(P+R).
    pub f1: Option<f64>,
}

impl ClassMetrics {
    /// The metrics of class `c` in `m`.
    pub fn from_matrix(m: &ConfusionMatrix, c: Class) -> ClassMetrics {
        // Sums in u128 so that no count near u64::MAX can overflow them.
        let counts = m.counts();
        let i = c.index();
        let tp = u128::from(counts[i][i]);
        let row: u128 = counts[i].iter().map(|&n| u128::from(n)).sum();
        let column: u128 = counts.iter().map(|r| u128::from(r[i])).sum();
        let fp = column - tp;
        let fn_ = row - tp;
        let present = tp + fp + fn_ > 0;
        let value = |x: f64| present.then_some(x);
        ClassMetrics {
            class: c,
            present,
            support: m.support(c),
            predicted: m.predicted(c),
            iou: value(ratio(tp, tp + fp + fn_)),
            precision: value(ratio(tp, tp + fp)),
            recall: value(ratio(tp, tp + fn_)),
            // 2PR/(P+R) written as 2TP/(2TP+FP+FN): the same value whenever P+R > 0, and 0
            // (zero_division) exactly when TP = 0; scikit-learn computes it this way too,
            // which keeps the two equal to the last bit.
            f1: value(ratio(2 * tp, 2 * tp + fp + fn_)),
        }
    }
}

/// num/den, or 0 when den is 0 (scikit-learn's `zero_division=0`).
fn ratio(num: u128, den: u128) -> f64 {
    if den == 0 {
        0.0
    } else {
        num as f64 / den as f64
    }
}

/// Everything the paper's tables report for one configuration, fractions in `0..=1`.
///
/// The means run over the classes that are present ([`ClassMetrics::present`]); they are
/// `None` when no class they cover is present (an empty matrix, or no body class for BIoU).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Per class, in [`Class::ALL`] order (background first).
    pub per_class: [ClassMetrics; NUM_CLASSES],
    /// Mean IoU over the present classes of all 7.
    pub miou: Option<f64>,
    /// Mean IoU over the present body classes (1..=6): the paper's BIoU.
    pub biou: Option<f64>,
    /// Mean precision over the present classes: the paper's AP (average precision).
    pub ap: Option<f64>,
    /// Mean F1 over the present classes.
    pub f1: Option<f64>,
}

impl Metrics {
    /// Derives all metrics from a confusion matrix (ALGORITHM.md §6).
    pub fn from_matrix(m: &ConfusionMatrix) -> Metrics {
        let per_class = Class::ALL.map(|c| ClassMetrics::from_matrix(m, c));
        let mean_of = |classes: &[Class], value: fn(&ClassMetrics) -> Option<f64>| {
            mean(classes.iter().filter_map(|c| value(&per_class[c.index()])))
        };
        Metrics {
            miou: mean_of(&Class::ALL, |c| c.iou),
            biou: mean_of(&Class::BODY, |c| c.iou),
            ap: mean_of(&Class::ALL, |c| c.precision),
            f1: mean_of(&Class::ALL, |c| c.f1),
            per_class,
        }
    }

    /// The metrics of class `c`.
    pub fn class(&self, c: Class) -> &ClassMetrics {
        &self.per_class[c.index()]
    }

    /// Classes absent from both ground truth and prediction, left out of the means; in id
    /// order.
    pub fn absent_classes(&self) -> Vec<Class> {
        self.per_class
            .iter()
            .filter(|c| !c.present)
            .map(|c| c.class)
            .collect()
    }
}

/// Arithmetic mean, summed in iteration order; `None` for no values.
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0u32), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / f64::from(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-computed values are exact fractions; 1e-15 allows for the last bit of a division.
    const TOL: f64 = 1e-15;

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() < TOL)
    }

    #[test]
    fn hand_computed_example() {
        let mut m = ConfusionMatrix::new();
        m.add_count(Class::Head, Class::Head, 6);
        m.add_count(Class::Head, Class::Torso, 2);
        m.add_count(Class::Torso, Class::Torso, 3);
        m.add_count(Class::Torso, Class::Head, 1);
        m.add_count(Class::Background, Class::Background, 10);
        m.add_count(Class::UpperArms, Class::Background, 4); // never predicted
        m.add_count(Class::Background, Class::LowerLegs, 2); // only predicted
        let x = Metrics::from_matrix(&m);

        let head = x.class(Class::Head);
        assert!(close(head.iou, 6.0 / 9.0));
        assert!(close(head.precision, 6.0 / 7.0));
        assert!(close(head.recall, 6.0 / 8.0));
        let (p, r) = (6.0 / 7.0, 6.0 / 8.0);
        assert!(close(head.f1, 2.0 * p * r / (p + r)));

        let arms = x.class(Class::UpperArms);
        assert!(arms.present);
        assert_eq!(
            (arms.iou, arms.precision, arms.f1),
            (Some(0.0), Some(0.0), Some(0.0))
        );
        assert_eq!(arms.recall, Some(0.0));
        let legs = x.class(Class::LowerLegs);
        assert!(legs.present);
        assert_eq!(
            (legs.iou, legs.recall, legs.f1),
            (Some(0.0), Some(0.0), Some(0.0))
        );

        assert_eq!(x.absent_classes(), vec![Class::LowerArms, Class::UpperLegs]);
        assert_eq!(x.class(Class::LowerArms).iou, None);

        let bg_iou = 10.0 / 16.0;
        let torso_iou = 3.0 / 6.0;
        let head_iou = 6.0 / 9.0;
        assert!(close(x.miou, (bg_iou + head_iou + torso_iou) / 5.0));
        assert!(close(x.biou, (head_iou + torso_iou) / 4.0));
        let ap = (10.0 / 14.0 + 6.0 / 7.0 + 3.0 / 5.0) / 5.0;
        assert!(close(x.ap, ap));
    }

    #[test]
    fn empty_matrix_has_no_means() {
        let x = Metrics::from_matrix(&ConfusionMatrix::new());
        assert_eq!(x.absent_classes(), Class::ALL.to_vec());
        assert_eq!((x.miou, x.biou, x.ap, x.f1), (None, None, None, None));
    }

    #[test]
    fn background_only_has_no_biou() {
        let mut m = ConfusionMatrix::new();
        m.add_count(Class::Background, Class::Background, 3);
        let x = Metrics::from_matrix(&m);
        assert_eq!(x.miou, Some(1.0));
        assert_eq!(x.biou, None);
    }
}
