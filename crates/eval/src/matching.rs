//! Pairing predicted points with ground-truth points through their origin.

use crate::confusion::ConfusionMatrix;
use crate::error::{CloudRole, EvalError};
use bodyseg_core::{Class, Label, LabeledCloud, PointOrigin};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::ops::AddAssign;

/// Points that were not evaluated, or evaluated with a substitution, so a report can say so.
///
/// For one pair of clouds, every ground-truth point is exactly one of: evaluated
/// ([`MatchStats::evaluated`]), `gt_unknown`, `gt_unmatched`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct PointCounts {
    /// Evaluated points whose predicted label was unknown; they were counted as background.
    pub pred_unknown: u64,
    /// Ground-truth points whose label is unknown, matched or not; never evaluated.
    pub gt_unknown: u64,
    /// Ground-truth points with a class label and no predicted point at their origin.
    pub gt_unmatched: u64,
    /// Predicted points with no ground-truth point at their origin.
    pub pred_unmatched: u64,
}

impl PointCounts {
    /// The field-by-field sum, or `None` on `u64` overflow.
    pub fn checked_add(&self, other: &PointCounts) -> Option<PointCounts> {
        Some(PointCounts {
            pred_unknown: self.pred_unknown.checked_add(other.pred_unknown)?,
            gt_unknown: self.gt_unknown.checked_add(other.gt_unknown)?,
            gt_unmatched: self.gt_unmatched.checked_add(other.gt_unmatched)?,
            pred_unmatched: self.pred_unmatched.checked_add(other.pred_unmatched)?,
        })
    }
}

impl AddAssign<&PointCounts> for PointCounts {
    /// Field-by-field sum (saturating).
    fn add_assign(&mut self, other: &PointCounts) {
        self.pred_unknown = self.pred_unknown.saturating_add(other.pred_unknown);
        self.gt_unknown = self.gt_unknown.saturating_add(other.gt_unknown);
        self.gt_unmatched = self.gt_unmatched.saturating_add(other.gt_unmatched);
        self.pred_unmatched = self.pred_unmatched.saturating_add(other.pred_unmatched);
    }
}

/// The result of scoring one or more (prediction, ground truth) pairs: the confusion
/// matrix of the evaluated points and the counts of the points that were not evaluated.
///
/// Sums over frames and shards with `+=`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MatchStats {
    /// Evaluated points, rows = ground truth, columns = prediction.
    pub confusion: ConfusionMatrix,
    /// Points left out or substituted.
    pub counts: PointCounts,
}

impl MatchStats {
    /// Number of evaluated points (the confusion matrix's total).
    pub fn evaluated(&self) -> u64 {
        self.confusion.total()
    }

    /// The sum, or `None` on `u64` overflow.
    pub fn checked_add(&self, other: &MatchStats) -> Option<MatchStats> {
        Some(MatchStats {
            confusion: self.confusion.checked_merge(&other.confusion)?,
            counts: self.counts.checked_add(&other.counts)?,
        })
    }
}

impl AddAssign<&MatchStats> for MatchStats {
    /// Sums matrices and counts (saturating).
    fn add_assign(&mut self, other: &MatchStats) {
        self.confusion += &other.confusion;
        self.counts += &other.counts;
    }
}

impl AddAssign for MatchStats {
    /// Sums matrices and counts (saturating).
    fn add_assign(&mut self, other: MatchStats) {
        *self += &other;
    }
}

/// Scores `pred` against `gt` (ALGORITHM.md §6).
///
/// Points are paired through their origin `(camera, pixel)`, so the clouds may be in any
/// order and need not hold the same points. For each pair:
/// - ground truth unknown: not evaluated (counted in [`PointCounts::gt_unknown`]);
/// - ground truth a class, prediction unknown: counted as predicted **background**, because
///   that is how a consumer of the cloud reads a point without a label: not a body part.
///   Leaving such points out instead would let a method score well by abstaining on hard
///   points (counted in [`PointCounts::pred_unknown`]);
/// - otherwise: one count in the confusion matrix at `[gt][pred]`.
///
/// Points without a partner in the other cloud are not evaluated but counted
/// ([`PointCounts::pred_unmatched`], [`PointCounts::gt_unmatched`]).
///
/// Positions and colours are not looked at.
///
/// # Errors
/// [`EvalError::LengthMismatch`] when a cloud's labels and origins differ in length;
/// [`EvalError::DuplicateOrigin`] when two points of one cloud share an origin.
pub fn match_clouds(pred: &LabeledCloud, gt: &LabeledCloud) -> Result<MatchStats, EvalError> {
    check_lengths(pred, CloudRole::Prediction)?;
    check_lengths(gt, CloudRole::GroundTruth)?;

    // Origin → index of the ground-truth point.
    let gt_index = index_origins(gt, CloudRole::GroundTruth)?;
    let mut gt_matched = vec![false; gt.labels.len()];
    // Origin → index of the predicted point, only to detect duplicates.
    let mut pred_seen: HashMap<PointOrigin, usize> = HashMap::with_capacity(pred.origins.len());

    let mut stats = MatchStats::default();
    for (i, (&origin, &pred_label)) in pred.origins.iter().zip(&pred.labels).enumerate() {
        match pred_seen.entry(origin) {
            Entry::Occupied(first) => {
                return Err(duplicate(CloudRole::Prediction, origin, *first.get(), i));
            }
            Entry::Vacant(slot) => {
                slot.insert(i);
            }
        }
        let Some(&j) = gt_index.get(&origin) else {
            stats.counts.pred_unmatched += 1;
            continue;
        };
        gt_matched[j] = true;
        let Some(gt_class) = gt.labels[j].class() else {
            continue; // Counted with the other unknown ground-truth points below.
        };
        let pred_class = predicted_class(pred_label);
        if pred_label.is_unknown() {
            stats.counts.pred_unknown += 1;
        }
        stats.confusion.add(gt_class, pred_class);
    }

    for (label, matched) in gt.labels.iter().zip(&gt_matched) {
        if label.is_unknown() {
            stats.counts.gt_unknown += 1;
        } else if !matched {
            stats.counts.gt_unmatched += 1;
        }
    }
    Ok(stats)
}

/// [`match_clouds`] for two labellings of the same points (the pipeline scores each
/// configuration against a ground truth built on the projected cloud itself): point `i`
/// of `pred` is point `i` of `gt`, so no origin look-up is needed. Counts as
/// [`match_clouds`] does on two clouds with equal origins.
///
/// # Errors
/// [`EvalError::AlignedLengths`] when the two label lists differ in length.
pub fn score_aligned(pred: &[Label], gt: &[Label]) -> Result<MatchStats, EvalError> {
    if pred.len() != gt.len() {
        return Err(EvalError::AlignedLengths {
            pred: pred.len(),
            gt: gt.len(),
        });
    }
    let mut stats = MatchStats::default();
    for (&p, &g) in pred.iter().zip(gt) {
        let Some(gt_class) = g.class() else {
            stats.counts.gt_unknown += 1;
            continue;
        };
        if p.is_unknown() {
            stats.counts.pred_unknown += 1;
        }
        stats.confusion.add(gt_class, predicted_class(p));
    }
    Ok(stats)
}

/// The class a predicted label is scored as: unknown is background (see [`match_clouds`]).
fn predicted_class(label: Label) -> Class {
    label.class().unwrap_or(Class::Background)
}

fn check_lengths(cloud: &LabeledCloud, role: CloudRole) -> Result<(), EvalError> {
    if cloud.labels.len() == cloud.origins.len() {
        Ok(())
    } else {
        Err(EvalError::LengthMismatch {
            cloud: role,
            labels: cloud.labels.len(),
            origins: cloud.origins.len(),
        })
    }
}

fn index_origins(
    cloud: &LabeledCloud,
    role: CloudRole,
) -> Result<HashMap<PointOrigin, usize>, EvalError> {
    let mut index = HashMap::with_capacity(cloud.origins.len());
    for (i, &origin) in cloud.origins.iter().enumerate() {
        match index.entry(origin) {
            Entry::Occupied(first) => return Err(duplicate(role, origin, *first.get(), i)),
            Entry::Vacant(slot) => {
                slot.insert(i);
            }
        }
    }
    Ok(index)
}

fn duplicate(cloud: CloudRole, origin: PointOrigin, first: usize, second: usize) -> EvalError {
    EvalError::DuplicateOrigin {
        cloud,
        camera: origin.camera,
        pixel: origin.pixel,
        first,
        second,
    }
}
