//! Pins the refinement's result on the regression subset of the fixed benchmark
//! (configs/benchmarks/paper.toml: the first seed of each preset, the subset's first
//! frames, synthetic parser errors, DSA projection, paper configuration) to the figure
//! scripts/reproduce.sh wrote into docs/results.md, within ±0.2 BIoU.

use crate::common::{assert_ok, bodyseg, tempdir};
use std::path::Path;

/// Half-width of the band around the documented BIoU, percentage points.
const TOLERANCE: f64 = 0.2;

fn repo(path: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The documented figure: `regression-subset M-R-N BIoU: 75.12` in docs/results.md.
fn documented_biou() -> f64 {
    let text = std::fs::read_to_string(repo("docs/results.md")).expect("docs/results.md");
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("regression-subset M-R-N BIoU: "))
        .expect("docs/results.md has the regression-subset line");
    line.trim().parse().expect("a number")
}

/// (preset, first seed) of each benchmark recording group, and the subset's frame count.
fn subset() -> (Vec<(String, u64)>, usize) {
    let text = std::fs::read_to_string(repo("configs/benchmarks/paper.toml")).expect("benchmark");
    let doc: toml::Table = text.parse().expect("toml");
    let groups = doc["recording"].as_array().expect("[[recording]]");
    let first = groups
        .iter()
        .map(|g| {
            let preset = g["preset"].as_str().expect("preset").to_string();
            let seed = g["seeds"].as_array().expect("seeds")[0]
                .as_integer()
                .expect("seed");
            (preset, seed as u64)
        })
        .collect();
    let frames = doc["subset"]["frames"].as_integer().expect("subset.frames") as usize;
    (first, frames)
}

#[test]
fn m_r_n_biou_on_the_regression_subset_matches_the_documented_figure() {
    let want = documented_biou();
    let (recordings, frames) = subset();
    let dir = tempdir();
    let mut reports = Vec::new();
    for (preset, seed) in &recordings {
        let rec = format!("{preset}_{seed}");
        let out = bodyseg(
            dir.path(),
            &[
                "synth",
                "--preset",
                preset,
                "--seed",
                &seed.to_string(),
                "--frames",
                &frames.to_string(),
                "--no-preview",
                "--out",
                &rec,
                "-q",
            ],
        );
        assert_ok(&out, "bodyseg synth");
        let run = format!("run_{rec}");
        let out = bodyseg(
            dir.path(),
            &[
                "run",
                "--recording",
                &rec,
                "--out",
                &run,
                "--figure",
                "none",
                "--no-label-images",
                "-q",
            ],
        );
        assert_ok(&out, "bodyseg run");
        reports.push(format!("{run}/report.json"));
    }
    let mut args = vec!["eval", "--merge"];
    args.extend(reports.iter().map(String::as_str));
    args.extend(["--format", "json", "--out", "subset.json", "-q"]);
    assert_ok(&bodyseg(dir.path(), &args), "bodyseg eval --merge");
    let text = std::fs::read_to_string(dir.path().join("subset.json")).expect("subset.json");
    let report = bodyseg_eval::Report::from_json(&text).expect("report");
    let got = 100.0
        * report
            .get("M-R-N")
            .expect("M-R-N")
            .metrics()
            .biou
            .expect("BIoU");
    assert!(
        (got - want).abs() <= TOLERANCE,
        "M-R-N BIoU on the regression subset is {got:.2}, docs/results.md says {want:.2} (±{TOLERANCE}): \
         rerun scripts/reproduce.sh if the change is intended"
    );
}
