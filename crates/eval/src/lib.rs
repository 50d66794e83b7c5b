//! bodyseg-eval: scores labelled point clouds against their ground truth (ALGORITHM.md §6).
//!
//! Place in the pipeline: the last stage.
//!
//! ```text
//! (predicted LabeledCloud, ground-truth LabeledCloud) pairs
//!   → match_clouds          → MatchStats (ConfusionMatrix + PointCounts), summed over frames
//!   → Metrics::from_matrix  → per-class IoU / precision / recall / F1, mIoU, BIoU, AP, F1
//!   → Report                → report.json (matrices + metrics) and report.md (paper's table)
//! ```
//!
//! A [`Report`] holds one [`Configuration`] per refinement variant ("Reference", "M", "N",
//! "M-N", "M-R-N"). Confusion matrices add up, so an evaluation can be split across machines
//! and the shards' reports joined with [`Report::merge`].
//!
//! # Conventions
//! - Classes are Pascal-Person-Part's 7 ([`Class`], background = 0). Confusion matrices are
//!   indexed by [`Class::index`]: **rows = ground truth, columns = prediction**, the same
//!   layout as scikit-learn's `confusion_matrix(y_true, y_pred, labels=range(7))`.
//! - Points are matched through their origin `(camera, depth pixel)` ([`PointOrigin`]), never
//!   through their index or position: the two clouds may be in any order.
//! - A ground-truth point whose label is unknown is not evaluated. A predicted point whose
//!   label is unknown counts as background (see [`match_clouds`]). Points present in only one
//!   cloud are not evaluated but counted ([`PointCounts`]).
//! - Metrics are fractions in `0..=1`. A ratio whose denominator is 0 is 0 (scikit-learn's
//!   `zero_division=0`). A class absent from both prediction and ground truth has no value
//!   (`None`, JSON `null`) and is left out of every mean; the markdown table shows it as `–`
//!   and says so under the table.
//! - Markdown tables print percentages with 2 decimals, as the paper does; change rows are
//!   percentage points, signed.
//!
//! [`Class`]: bodyseg_core::Class
//! [`Class::index`]: bodyseg_core::Class::index
//! [`PointOrigin`]: bodyseg_core::PointOrigin

mod confusion;
mod error;
mod matching;
mod metrics;
mod report;

pub use confusion::ConfusionMatrix;
pub use error::{CloudRole, EvalError};
pub use matching::{MatchStats, PointCounts, match_clouds, score_aligned};
pub use metrics::{ClassMetrics, Metrics};
pub use report::{Configuration, REPORT_VERSION, Report};
