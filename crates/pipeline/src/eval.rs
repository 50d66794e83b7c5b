//! `bodyseg eval`: labelled PLY predictions + ground-truth PLY → metrics report; and the
//! merge of shard reports.

use crate::outputs::read_labelled_ply;
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_core::{LabeledCloud, PointOrigin};
use bodyseg_eval::{Report, match_clouds};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The configuration name given to a single prediction when none is named.
pub const DEFAULT_PREDICTION_NAME: &str = "prediction";

/// One predicted cloud to score, under a configuration name ("M-R-N", "Reference", ...).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NamedPrediction {
    /// The row name in the report.
    pub name: String,
    /// The predicted cloud (PLY).
    pub path: PathBuf,
}

/// What [`eval_files`] scores.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Predicted clouds, in report order (the first is the reference of the change rows).
    pub predictions: Vec<NamedPrediction>,
    /// Ground-truth cloud (PLY); points are matched by origin `(camera, pixel)`.
    pub gt: PathBuf,
}

/// What [`eval_files`] computed.
#[derive(Clone, Debug)]
pub struct EvalSummary {
    /// One configuration per prediction.
    pub report: Report,
    /// Per stage (read, match): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// How a report is printed or written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ReportFormat {
    /// The paper's tables as markdown (`report.md`).
    #[default]
    Markdown,
    /// Matrices and metrics as JSON (`report.json`); mergeable with [`merge_reports`].
    Json,
}

/// Scores each predicted cloud against the ground truth (bodyseg-eval's [`match_clouds`]):
/// one report configuration per prediction, in the given order.
///
/// # Errors
/// No prediction; two predictions with one name; a cloud cannot be read or is malformed
/// (the error names the file); a cloud has two points with one origin.
pub fn eval_files(opts: &EvalOptions) -> Result<EvalSummary> {
    if opts.predictions.is_empty() {
        bail!("no predicted cloud to evaluate");
    }
    for (i, p) in opts.predictions.iter().enumerate() {
        if opts.predictions[..i].iter().any(|q| q.name == p.name) {
            bail!(
                "two predictions are named {:?}; name each with --pred NAME=PATH",
                p.name
            );
        }
    }
    let (gt, mut read) =
        timed(|| read_labelled_ply(&opts.gt).context("ground-truth cloud (--gt)"))?;
    let mut report = Report::new();
    let mut matching = std::time::Duration::ZERO;
    let mut points = 0;
    for p in &opts.predictions {
        let (pred, took) = timed(|| {
            read_labelled_ply(&p.path)
                .with_context(|| format!("predicted cloud {:?} (--pred)", p.name))
        })?;
        read += took;
        points += pred.len();
        check_same_points(&pred, &gt, &p.path, &opts.gt)?;
        let (stats, took) = timed(|| {
            match_clouds(&pred, &gt).with_context(|| {
                format!(
                    "cannot match {} against {}",
                    p.path.display(),
                    opts.gt.display()
                )
            })
        })?;
        matching += took;
        report.push(p.name.clone(), stats)?;
    }
    let evaluated: Vec<String> = report
        .configurations()
        .iter()
        .map(|c| format!("{} {}", c.name(), c.evaluated()))
        .collect();
    Ok(EvalSummary {
        stages: vec![
            Stage::new(
                "read",
                read,
                format!(
                    "{} ground truth, {} predicted in {}",
                    plural(gt.len(), "point", "points"),
                    plural(points, "point", "points"),
                    plural(opts.predictions.len(), "cloud", "clouds"),
                ),
            ),
            Stage::new(
                "match",
                matching,
                format!("evaluated points: {}", evaluated.join(", ")),
            ),
        ],
        report,
    })
}

/// Share of a prediction's points that must have a ground-truth point at the same origin
/// and position; below it, the clouds are of different frames (or recordings) and
/// [`eval_files`] refuses them.
pub(crate) const MIN_SAME_POINTS: f64 = 0.5;

/// Two points with one origin are the same point when their positions are this close,
/// metres (PLY stores f32 positions: written and read again they are equal).
const SAME_POSITION_M: f32 = 0.01;

/// Fraction of `pred`'s points that have a point of `gt` at the same origin `(camera,
/// pixel)` and the same position (within [`SAME_POSITION_M`]); 1 for an empty `pred`.
pub(crate) fn same_points_fraction(pred: &LabeledCloud, gt: &LabeledCloud) -> f64 {
    if pred.is_empty() {
        return 1.0;
    }
    let index: HashMap<PointOrigin, usize> = gt
        .origins
        .iter()
        .enumerate()
        .map(|(i, o)| (*o, i))
        .collect();
    let same = pred
        .origins
        .iter()
        .zip(&pred.positions_m)
        .filter(|(o, p)| {
            index.get(o).is_some_and(|&j| {
                let q = gt.positions_m[j];
                (0..3).all(|a| (p[a] - q[a]).abs() <= SAME_POSITION_M)
            })
        })
        .count();
    same as f64 / pred.len() as f64
}

/// Refuses a prediction whose points are mostly not the ground truth's (fewer than
/// [`MIN_SAME_POINTS`] at the same origin and position: another frame's cloud scores
/// plausibly otherwise) and warns when some are not.
///
/// # Errors
/// Fewer than half the points match; the message names both files and the share.
fn check_same_points(
    pred: &LabeledCloud,
    gt: &LabeledCloud,
    pred_path: &Path,
    gt_path: &Path,
) -> Result<()> {
    let f = same_points_fraction(pred, gt);
    if f < MIN_SAME_POINTS {
        bail!(
            "{}: only {:.1}% of its points are points of the ground truth {} (same camera, pixel and position; at least {:.0}% needed): clouds of different frames or recordings?",
            pred_path.display(),
            100.0 * f,
            gt_path.display(),
            100.0 * MIN_SAME_POINTS
        );
    }
    if f < 1.0 {
        tracing::warn!(
            "{}: {:.1}% of its points are not points of the ground truth {} (no point at their camera and pixel, or at another position)",
            pred_path.display(),
            100.0 * (1.0 - f),
            gt_path.display()
        );
    }
    Ok(())
}

/// Reads `report.json` files (written by `bodyseg eval --format json`) and sums them
/// ([`Report::merge`]): per configuration, confusion matrices and point counts add up
/// and the metrics are recomputed.
///
/// # Errors
/// No file; a file cannot be read or is not a report (the error names it); the reports
/// hold different configurations.
pub fn merge_reports(paths: &[PathBuf]) -> Result<Report> {
    if paths.is_empty() {
        bail!("no report to merge");
    }
    let reports = paths
        .iter()
        .map(|path| {
            let text = bodyseg_io::read_text(path)?;
            Report::from_json(&text)
                .with_context(|| format!("{}: not a bodyseg report", path.display()))
        })
        .collect::<Result<Vec<_>>>()?;
    let merged = Report::merge(&reports).with_context(|| {
        let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        format!("reports {} (in this order)", names.join(", "))
    })?;
    Ok(merged)
}

/// The report as text in `format`, ending with a newline.
///
/// # Errors
/// JSON serialization fails (it does not for reports).
pub fn render_report(report: &Report, format: ReportFormat) -> Result<String> {
    Ok(match format {
        ReportFormat::Markdown => {
            let mut s = report.to_markdown();
            if !s.ends_with('\n') {
                s.push('\n');
            }
            s
        }
        ReportFormat::Json => {
            let mut s = report
                .to_json()
                .context("cannot write the report as JSON")?;
            s.push('\n');
            s
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::Label;

    /// A cloud of `n` points at pixels `first..first + n` of camera 0, each at
    /// `(pixel, z, 0)`.
    fn cloud(first: u32, n: u32, z: f32) -> LabeledCloud {
        LabeledCloud {
            positions_m: (first..first + n).map(|i| [i as f32, z, 0.0]).collect(),
            labels: vec![Label::BACKGROUND; n as usize],
            colors: None,
            origins: (first..first + n)
                .map(|pixel| PointOrigin { camera: 0, pixel })
                .collect(),
        }
    }

    #[test]
    fn clouds_of_other_points_are_refused_and_partial_ones_noted() {
        let gt = cloud(0, 100, 0.0);
        assert_eq!(same_points_fraction(&cloud(0, 100, 0.0), &gt), 1.0);
        // Same pixels, other positions: another frame of the recording.
        assert_eq!(same_points_fraction(&cloud(0, 100, 0.5), &gt), 0.0);
        assert_eq!(same_points_fraction(&cloud(60, 100, 0.0), &gt), 0.4);
        let p = Path::new("pred.ply");
        let g = Path::new("gt.ply");
        let e = format!(
            "{:#}",
            check_same_points(&cloud(0, 100, 0.5), &gt, p, g).expect_err("other frame")
        );
        assert_eq!(
            e,
            "pred.ply: only 0.0% of its points are points of the ground truth gt.ply (same \
             camera, pixel and position; at least 50% needed): clouds of different frames or \
             recordings?"
        );
        assert!(check_same_points(&cloud(40, 100, 0.0), &gt, p, g).is_ok());
    }
}
