//! The reports of a batch (`bodyseg run`, `bodyseg convert`): the frames' scores merged
//! into the paper's table (`report.md`, `report.json`), the resolved configuration, and
//! the run's log (`run.json`).

use crate::batch::{BatchOutcome, FrameFailure, Shard};
use crate::eval::{ReportFormat, render_report};
use crate::outputs::write_text;
use crate::stage::{Stage, plural};
use anyhow::{Context, Result};
use bodyseg_eval::Report;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What [`crate::run_recording`] (and [`crate::convert_dataset`]) did.
#[derive(Debug)]
pub struct RunSummary {
    /// Frames of this shard.
    pub frames: usize,
    /// The frame loop's outcome: records, counts, failures, stage times.
    pub outcome: BatchOutcome,
    /// The merged report (when the recording has ground truth).
    pub report: Option<Report>,
    /// Report files written (`report.md`, `report.json`, `config.resolved.toml`,
    /// `run.json`).
    pub written: Vec<PathBuf>,
    /// Figures written or already present, in frame order.
    pub figures: Vec<PathBuf>,
    /// Setup, frame-loop totals per stage, and the report.
    pub stages: Vec<Stage>,
}

/// This run's log (`run.json`): counts, failures and times; unlike the other outputs it
/// differs from run to run.
#[derive(Serialize)]
struct RunLog<'a> {
    recording: String,
    shard: String,
    frames: usize,
    processed: usize,
    skipped: usize,
    failed: &'a [FrameFailure],
    /// Stems a camera lacks: skipped, not frames.
    incomplete_frames: Vec<IncompleteFrame<'a>>,
    seconds: f64,
    frames_per_second: f64,
    stage_seconds: Vec<(&'static str, f64)>,
}

/// A stem some cameras lack (`run.json`).
#[derive(Serialize)]
struct IncompleteFrame<'a> {
    frame: &'a str,
    missing_cameras: &'a [String],
}

/// Where a batch's reports go and what they describe.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReportTarget<'a> {
    /// The output folder.
    pub out: &'a Path,
    /// The input (recording or data set), as the reports name it.
    pub input: &'a Path,
    /// This process's shard.
    pub shard: Shard,
    /// `report.md` starts with what ran (input, frame counts) and lists failed frames,
    /// frames a camera lacks and figures (`bodyseg run`); without it, `report.md` is the
    /// tables only, byte for byte what `bodyseg eval --merge --format md` writes for the
    /// same scores (`bodyseg convert`: a sharded conversion merged equals the unsharded
    /// one; the rest is in `run.json`).
    pub header: bool,
    /// Stems some cameras lack (not frames), with those cameras: listed in `run.json`
    /// and, with the header, in `report.md`.
    pub incomplete: &'a [(String, Vec<String>)],
}

/// Merges the frames' scores and writes `report.md`, `report.json` (when there are
/// scores), `config.resolved.toml` and `run.json`; with a shard, the report files carry
/// its suffix (`report.shard-0-of-4.json`) so shards can share one folder.
pub(crate) fn write_reports(
    opts: ReportTarget<'_>,
    frames: &[String],
    outcome: &BatchOutcome,
    resolved: &str,
    fps: f64,
) -> Result<(Option<Report>, Vec<PathBuf>)> {
    // The groups' sums (one group but for `convert`'s overall report): sums of counts, the
    // same as merging every frame's report at once.
    let report = match outcome.scores.len() {
        0 => None,
        1 => outcome.scores.values().next().cloned(),
        _ => {
            Some(Report::merge(outcome.scores.values()).context("merging the recordings' scores")?)
        }
    };
    let suffix = opts.shard.suffix();
    let mut written = Vec::new();
    if let Some(report) = &report {
        let path = opts.out.join(format!("report{suffix}.json"));
        write_text(&path, &render_report(report, ReportFormat::Json)?)?;
        written.push(path);
    }
    let md = match (opts.header, &report) {
        (true, _) => report_markdown(opts, frames, outcome, report.as_ref()),
        (false, Some(r)) => render_report(r, ReportFormat::Markdown)?,
        (false, None) => "No ground truth: no scores.\n".to_string(),
    };
    let path = opts.out.join(format!("report{suffix}.md"));
    write_text(&path, &md)?;
    written.push(path);
    let path = opts.out.join("config.resolved.toml");
    write_text(&path, resolved)?;
    written.push(path);
    let log = RunLog {
        recording: opts.input.display().to_string(),
        shard: opts.shard.to_string(),
        frames: frames.len(),
        processed: outcome.processed,
        skipped: outcome.skipped,
        failed: &outcome.failed,
        incomplete_frames: opts
            .incomplete
            .iter()
            .map(|(frame, missing_cameras)| IncompleteFrame {
                frame,
                missing_cameras,
            })
            .collect(),
        seconds: outcome.elapsed.as_secs_f64(),
        frames_per_second: fps,
        stage_seconds: outcome
            .stage_totals
            .iter()
            .map(|(n, d)| (*n, d.as_secs_f64()))
            .collect(),
    };
    let path = opts.out.join(format!("run{suffix}.json"));
    write_text(&path, &serde_json::to_string_pretty(&log)?)?;
    written.push(path);
    Ok((report, written))
}

/// The figures among the frames' outputs (paths relative to the output folder).
pub(crate) fn figure_outputs(outcome: &BatchOutcome) -> impl Iterator<Item = &str> {
    outcome
        .records
        .iter()
        .flat_map(|r| &r.outputs)
        .map(|o| o.path.as_str())
        .filter(|p| p.starts_with("figures/"))
}

/// `report.md`: what ran, the paper's table, the failed frames and the figures. No times
/// (they are in `run.json`), so that a resumed run writes the same file.
fn report_markdown(
    opts: ReportTarget<'_>,
    frames: &[String],
    outcome: &BatchOutcome,
    report: Option<&Report>,
) -> String {
    let mut md = String::new();
    md.push_str("# bodyseg report\n\n");
    md.push_str(&format!(
        "Input `{}`: {} complete of {} in shard {} ({} frames selected in all).\n\n",
        opts.input.display(),
        plural(outcome.records.len(), "frame", "frames"),
        outcome.records.len() + outcome.failed.len(),
        opts.shard,
        frames.len()
    ));
    match report {
        Some(r) => {
            md.push_str(
                "Per-point scores against the recording's ground truth (`depth_labels/`), \
                 all frames together; under each configuration its change from Reference.\n\n",
            );
            md.push_str(&r.to_markdown());
            md.push('\n');
        }
        None => md.push_str("No ground truth: no scores.\n\n"),
    }
    if !opts.incomplete.is_empty() {
        md.push_str(&format!(
            "## Skipped: a camera lacks them ({})\n\n",
            opts.incomplete.len()
        ));
        for (frame, cameras) in opts.incomplete {
            md.push_str(&format!(
                "- `{frame}`: no depth image of {}\n",
                cameras.join(", ")
            ));
        }
        md.push('\n');
    }
    if !outcome.failed.is_empty() {
        md.push_str(&format!("## Failed frames ({})\n\n", outcome.failed.len()));
        for f in &outcome.failed {
            md.push_str(&format!("- `{}`: {}\n", f.frame, f.error));
        }
        md.push('\n');
    }
    let figures: Vec<&str> = figure_outputs(outcome).collect();
    if !figures.is_empty() {
        md.push_str("## Figures\n\n");
        for f in figures {
            md.push_str(&format!("![{f}]({f})\n"));
        }
    }
    md
}
