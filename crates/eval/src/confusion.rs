//! The 7×7 confusion matrix.

use bodyseg_core::{Class, NUM_CLASSES};
use serde::{Deserialize, Serialize};
use std::ops::AddAssign;

/// Point counts per (ground-truth class, predicted class): `counts[gt][pred]`, both indexed
/// by [`Class::index`]. Rows are ground truth, columns prediction, as scikit-learn's
/// `confusion_matrix(y_true, y_pred, labels=range(7))`.
///
/// Matrices from different frames or shards add up ([`ConfusionMatrix::merge`], `+=`).
/// Serialized as `{"counts": [[u64; 7]; 7]}`.
///
/// Counts saturate at `u64::MAX` (1.8·10¹⁹ points) instead of wrapping or panicking;
/// [`ConfusionMatrix::checked_merge`] reports an overflow instead.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ConfusionMatrix {
    counts: [[u64; NUM_CLASSES]; NUM_CLASSES],
}

impl ConfusionMatrix {
    /// An all-zero matrix.
    pub fn new() -> ConfusionMatrix {
        ConfusionMatrix::default()
    }

    /// A matrix with these counts, `counts[gt][pred]`.
    pub fn from_counts(counts: [[u64; NUM_CLASSES]; NUM_CLASSES]) -> ConfusionMatrix {
        ConfusionMatrix { counts }
    }

    /// The counts, `counts[gt][pred]`.
    pub fn counts(&self) -> &[[u64; NUM_CLASSES]; NUM_CLASSES] {
        &self.counts
    }

    /// Number of points of ground-truth class `gt` predicted as `pred`.
    pub fn get(&self, gt: Class, pred: Class) -> u64 {
        self.counts[gt.index()][pred.index()]
    }

    /// Counts one point of ground-truth class `gt` predicted as `pred`.
    pub fn add(&mut self, gt: Class, pred: Class) {
        self.add_count(gt, pred, 1);
    }

    /// Counts `n` points of ground-truth class `gt` predicted as `pred`.
    pub fn add_count(&mut self, gt: Class, pred: Class, n: u64) {
        let cell = &mut self.counts[gt.index()][pred.index()];
        *cell = cell.saturating_add(n);
    }

    /// Adds another matrix cell by cell (saturating).
    pub fn merge(&mut self, other: &ConfusionMatrix) {
        for (row, other_row) in self.counts.iter_mut().zip(&other.counts) {
            for (cell, other_cell) in row.iter_mut().zip(other_row) {
                *cell = cell.saturating_add(*other_cell);
            }
        }
    }

    /// The cell-by-cell sum, or `None` if a cell or the total would exceed `u64::MAX`.
    pub fn checked_merge(&self, other: &ConfusionMatrix) -> Option<ConfusionMatrix> {
        let mut out = ConfusionMatrix::new();
        let mut total: u64 = 0;
        for gt in 0..NUM_CLASSES {
            for pred in 0..NUM_CLASSES {
                let cell = self.counts[gt][pred].checked_add(other.counts[gt][pred])?;
                total = total.checked_add(cell)?;
                out.counts[gt][pred] = cell;
            }
        }
        Some(out)
    }

    /// Number of points counted (saturating).
    pub fn total(&self) -> u64 {
        self.counts
            .iter()
            .flatten()
            .fold(0u64, |acc, &n| acc.saturating_add(n))
    }

    /// Points of class `c` predicted as `c`.
    pub fn true_positives(&self, c: Class) -> u64 {
        self.get(c, c)
    }

    /// Points predicted as `c` whose ground truth is another class (column sum minus TP).
    pub fn false_positives(&self, c: Class) -> u64 {
        self.predicted(c).saturating_sub(self.true_positives(c))
    }

    /// Points of ground-truth class `c` predicted as another class (row sum minus TP).
    pub fn false_negatives(&self, c: Class) -> u64 {
        self.support(c).saturating_sub(self.true_positives(c))
    }

    /// Points whose ground truth is `c` (the row sum; scikit-learn's "support").
    pub fn support(&self, c: Class) -> u64 {
        self.counts[c.index()]
            .iter()
            .fold(0u64, |acc, &n| acc.saturating_add(n))
    }

    /// Points predicted as `c` (the column sum).
    pub fn predicted(&self, c: Class) -> u64 {
        self.counts
            .iter()
            .fold(0u64, |acc, row| acc.saturating_add(row[c.index()]))
    }
}

impl AddAssign<&ConfusionMatrix> for ConfusionMatrix {
    fn add_assign(&mut self, other: &ConfusionMatrix) {
        self.merge(other);
    }
}

impl AddAssign for ConfusionMatrix {
    fn add_assign(&mut self, other: ConfusionMatrix) {
        self.merge(&other);
    }
}

impl Extend<(Class, Class)> for ConfusionMatrix {
    /// Counts each `(gt, pred)` pair.
    fn extend<I: IntoIterator<Item = (Class, Class)>>(&mut self, pairs: I) {
        for (gt, pred) in pairs {
            self.add(gt, pred);
        }
    }
}

impl FromIterator<(Class, Class)> for ConfusionMatrix {
    /// The matrix of these `(gt, pred)` pairs.
    fn from_iter<I: IntoIterator<Item = (Class, Class)>>(pairs: I) -> ConfusionMatrix {
        let mut m = ConfusionMatrix::new();
        m.extend(pairs);
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_ground_truth_and_columns_prediction() {
        let mut m = ConfusionMatrix::new();
        m.add(Class::Head, Class::Torso);
        m.add(Class::Head, Class::Torso);
        m.add(Class::Head, Class::Head);
        m.add(Class::Background, Class::Head);
        assert_eq!(m.counts()[Class::Head.index()][Class::Torso.index()], 2);
        assert_eq!(m.get(Class::Torso, Class::Head), 0);
        assert_eq!(m.total(), 4);
        assert_eq!(m.true_positives(Class::Head), 1);
        assert_eq!(m.false_negatives(Class::Head), 2);
        assert_eq!(m.false_positives(Class::Head), 1);
        assert_eq!(m.support(Class::Head), 3);
        assert_eq!(m.predicted(Class::Torso), 2);
        assert_eq!(m.false_positives(Class::Torso), 2);
    }

    #[test]
    fn serializes_as_counts_object() {
        let mut m = ConfusionMatrix::new();
        m.add(Class::LowerLegs, Class::Background);
        let json = serde_json::to_value(&m).expect("a matrix serializes");
        assert_eq!(json["counts"][6][0], 1);
        assert_eq!(json["counts"].as_array().map(Vec::len), Some(7));
        let back: ConfusionMatrix = serde_json::from_value(json).expect("and reads back");
        assert_eq!(back, m);
        // A 6×7 matrix is rejected rather than padded.
        let short = serde_json::json!({ "counts": vec![[0u64; 7]; 6] });
        assert!(serde_json::from_value::<ConfusionMatrix>(short).is_err());
    }

    #[test]
    fn merge_saturates_and_checked_merge_reports_overflow() {
        let mut a = ConfusionMatrix::new();
        a.add_count(Class::Head, Class::Head, u64::MAX - 1);
        let mut b = ConfusionMatrix::new();
        b.add_count(Class::Head, Class::Head, 5);
        assert_eq!(a.checked_merge(&b), None);
        let mut c = a.clone();
        c += &b;
        assert_eq!(c.get(Class::Head, Class::Head), u64::MAX);
        // Cells that fit but a total that does not is an overflow too.
        let mut d = ConfusionMatrix::new();
        d.add_count(Class::Torso, Class::Torso, 5);
        assert_eq!(a.checked_merge(&d), None);
        assert!(ConfusionMatrix::new().checked_merge(&b).is_some());
    }
}
