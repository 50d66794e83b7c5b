//! `bodyseg eval`: labelled PLY predictions + ground-truth PLY → metrics report; and the
//! merge of shard reports.

use crate::outputs::read_labelled_ply;
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_eval::{Report, match_clouds};
use std::path::PathBuf;

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
