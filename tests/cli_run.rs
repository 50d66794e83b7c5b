//! `bodyseg run` on a small synthetic recording (`bodyseg synth --preset handover`): the
//! outputs and the paper's table, a second run skipping every frame, a corrupt depth PNG
//! failing only its frame, and a run killed midway finished by running it again with the
//! same outputs as an uninterrupted run.

use crate::common::{
    FRAMES, assert_ok, bodyseg, bodyseg_line, recording, recording_copy, stderr, stdout, tempdir,
    tree, words,
};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn stem(i: usize) -> String {
    format!("{i:06}")
}

fn metrics(report: &bodyseg_eval::Report, name: &str) -> bodyseg_eval::Metrics {
    report
        .get(name)
        .unwrap_or_else(|| panic!("report has {name}"))
        .metrics()
        .clone()
}

/// `COMMAND --recording REC --out OUT EXTRA...`: the command line of these tests.
fn on_recording<'a>(
    command: &'a str,
    rec: &'a Path,
    out: &'a str,
    extra: &[&'a str],
) -> Vec<&'a str> {
    let mut args = vec![
        command,
        "--recording",
        rec.to_str().expect("utf-8"),
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn run_writes_every_output_and_a_second_run_skips_every_frame() {
    let rec = recording();
    let dir = tempdir();
    let args = on_recording("run", rec, "out", &["--write-stages"]);
    let first = bodyseg(dir.path(), &args);
    assert_ok(&first, "bodyseg run");
    let out = dir.path().join("out");
    // The paper's table on stdout and in the report; the refinement helps.
    let table = stdout(&first);
    assert!(table.contains("| M-R-N |"), "{table}");
    let report = bodyseg_eval::Report::from_json(
        &std::fs::read_to_string(out.join("report.json")).expect("report.json"),
    )
    .expect("report parses");
    assert_eq!(report.names(), ["Reference", "M", "N", "M-N", "M-R-N"]);
    let (reference, mrn) = (metrics(&report, "Reference"), metrics(&report, "M-R-N"));
    let (b0, b1) = (reference.biou.expect("BIoU"), mrn.biou.expect("BIoU"));
    assert!(b1 >= b0, "M-R-N BIoU {b1:.4} < Reference {b0:.4}");
    for f in ["report.md", "config.resolved.toml", "run.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(md.contains("| M-R-N |") && md.contains("figures/"), "{md}");
    // The figure of the middle frame, and its path on stdout.
    let figure = out
        .join("figures")
        .join(format!("{}.png", stem(FRAMES / 2)));
    assert!(figure.is_file(), "{}", figure.display());
    assert!(table.contains("figure: "), "{table}");

    // Per frame: the refined cloud has every projected point.
    for i in [0, FRAMES - 1] {
        let f = stem(i);
        let refined = bodyseg_io::read_ply(&out.join(format!("clouds/{f}.ply"))).expect("ply");
        let projected =
            bodyseg_io::read_ply(&out.join(format!("stages/{f}/projected.ply"))).expect("ply");
        let mrn = bodyseg_io::read_ply(&out.join(format!("stages/{f}/M-R-N.ply"))).expect("ply");
        // `bodyseg project` on the same frame gives the same points.
        let alone = dir.path().join(format!("{f}.ply"));
        let p = bodyseg(
            dir.path(),
            &on_recording(
                "project",
                rec,
                alone.to_str().expect("utf-8"),
                &["--frame", &f],
            ),
        );
        assert_ok(&p, "bodyseg project");
        let alone = bodyseg_io::read_ply(&alone).expect("ply");
        assert_eq!(
            projected, alone,
            "frame {f}: run's projection = bodyseg project"
        );
        assert_eq!(refined.len(), alone.len(), "frame {f}");
        assert_eq!(refined.origins, alone.origins, "frame {f}");
        assert_eq!(
            refined.labels, mrn.labels,
            "frame {f}: refine.steps is M-R-N"
        );
        assert_ne!(
            refined.labels, alone.labels,
            "frame {f}: refinement changed labels"
        );
        for cam in ["cam0", "cam1", "cam2"] {
            let l = bodyseg_io::read_label_png(&out.join(format!("labels/{cam}/{f}.png")))
                .expect("label png");
            let body = l.labels.iter().filter(|x| x.is_body()).count();
            assert!(body > 1000, "frame {f} {cam}: {body} body pixels");
        }
        assert!(out.join(format!("boxes/{f}.json")).is_file());
    }

    // A second run into the same folder skips every frame and changes nothing.
    let before: Vec<(String, Vec<u8>)> = tree(&out)
        .into_iter()
        .filter(|f| f != "run.json")
        .map(|f| {
            let bytes = std::fs::read(out.join(&f)).expect("read");
            (f, bytes)
        })
        .collect();
    let second = bodyseg(dir.path(), &args);
    assert_ok(&second, "second bodyseg run");
    let log = stderr(&second);
    assert!(
        log.contains("0 processed") && log.contains(&format!("{FRAMES} skipped")),
        "{log}"
    );
    for (f, bytes) in &before {
        assert_eq!(
            &std::fs::read(out.join(f)).expect("read"),
            bytes,
            "{f} changed"
        );
    }
}

#[test]
fn a_corrupt_depth_png_fails_its_frame_only() {
    let (dir, rec) = recording_copy();
    let bad = stem(2);
    let depth = rec.join("cam1").join("depth").join(format!("{bad}.png"));
    let bytes = std::fs::read(&depth).expect("read");
    std::fs::write(&depth, &bytes[..bytes.len() / 3]).expect("truncate");

    let out = bodyseg_line(dir.path(), "run --recording rec --out out --figure none");
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    let log = stderr(&out);
    assert!(
        log.contains(&format!("error: frame {bad}")) && log.contains(&format!("{bad}.png")),
        "{log}"
    );
    let o = dir.path().join("out");
    let files = tree(&o);
    for i in (0..FRAMES).filter(|&i| stem(i) != bad) {
        assert!(
            files.contains(&format!("clouds/{}.ply", stem(i))),
            "{files:?}"
        );
    }
    // Nothing of the bad frame, and no temporary file anywhere.
    assert!(
        files
            .iter()
            .all(|f| !f.contains(&bad) && !f.contains(".bodyseg-")),
        "{files:?}"
    );
    let md = std::fs::read_to_string(o.join("report.md")).expect("report.md");
    assert!(
        md.contains("Failed frames (1)") && md.contains(&bad),
        "{md}"
    );
    let log: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(o.join("run.json")).expect("run.json"))
            .expect("json");
    assert_eq!(log["failed"][0]["frame"], bad.as_str());
}

#[test]
fn a_killed_run_finishes_when_started_again_with_identical_outputs() {
    let rec = recording();
    let dir = tempdir();
    let args = |out: &str| -> Vec<String> {
        on_recording("run", rec, out, &["-q"])
            .into_iter()
            .map(String::from)
            .collect()
    };
    let whole = bodyseg(
        dir.path(),
        &args("whole").iter().map(String::as_str).collect::<Vec<_>>(),
    );
    assert_ok(&whole, "uninterrupted run");

    // Start, wait for the first finished frame, kill (SIGKILL: no clean-up).
    let mut child = Command::new(env!("CARGO_BIN_EXE_bodyseg"))
        .args(args("killed"))
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let records = dir.path().join("killed").join("frames");
    let start = Instant::now();
    let done_at_kill = loop {
        let n = std::fs::read_dir(&records).map_or(0, |d| d.count());
        if n >= 1 || start.elapsed() > Duration::from_secs(120) {
            child.kill().expect("kill");
            break std::fs::read_dir(&records).map_or(0, |d| d.count());
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let _ = child.wait();
    assert!(
        done_at_kill < FRAMES,
        "the run finished before it could be killed ({done_at_kill} frames)"
    );

    let again = bodyseg(
        dir.path(),
        &args("killed")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert_ok(&again, "restarted run");
    let (a, b) = (dir.path().join("whole"), dir.path().join("killed"));
    let files: Vec<String> = tree(&a).into_iter().filter(|f| f != "run.json").collect();
    let files_b: Vec<String> = tree(&b).into_iter().filter(|f| f != "run.json").collect();
    assert_eq!(files, files_b, "the same files");
    for f in &files {
        assert!(
            std::fs::read(a.join(f)).expect("read") == std::fs::read(b.join(f)).expect("read"),
            "{f} differs between the uninterrupted and the restarted run"
        );
    }
}

/// `bodyseg run` on the first 2 frames of `rec` into `dir/out` with `extra` arguments: its
/// report and its run log.
fn run_two_frames(
    dir: &Path,
    rec: &Path,
    out: &str,
    extra: &[&str],
) -> (bodyseg_eval::Report, String) {
    let quick = words("--limit 2 --figure none --no-label-images -q");
    let mut args = on_recording("run", rec, out, &quick);
    args.extend_from_slice(extra);
    let o = bodyseg(dir, &args);
    assert_ok(&o, "bodyseg run");
    let out = dir.join(out);
    let report = bodyseg_eval::Report::from_json(
        &std::fs::read_to_string(out.join("report.json")).expect("report.json"),
    )
    .expect("report parses");
    let log = std::fs::read_to_string(out.join("run.json")).expect("run.json");
    (report, log)
}

#[test]
fn the_multi_view_vote_changes_the_steps_and_leaves_reference_alone() {
    let rec = recording();
    let dir = tempdir();
    std::fs::write(
        dir.path().join("vote.toml"),
        "[refine]\nvote = \"multi_view\"\n",
    )
    .expect("write");
    let run = |out: &str, extra: &[&str]| run_two_frames(dir.path(), rec, out, extra);
    let (paper, paper_log) = run("paper", &[]);
    let (vote, vote_log) = run("vote", &["--config", "vote.toml"]);
    // Reference is the projection in both: the same confusion matrix, hence equal metrics.
    assert_eq!(metrics(&paper, "Reference"), metrics(&vote, "Reference"));
    // The vote runs (its own stage) only when asked for.
    assert!(vote_log.contains("\"vote\""), "{vote_log}");
    assert!(!paper_log.contains("\"vote\""), "{paper_log}");
    // M alone starts from the voted labels: points DSA left unknown that another camera
    // sees get that camera's label, so M scores higher than the paper's M (where they
    // count as background).
    let (m_paper, m_vote) = (
        metrics(&paper, "M").biou.expect("BIoU"),
        metrics(&vote, "M").biou.expect("BIoU"),
    );
    assert!(
        m_vote > m_paper + 0.01,
        "M BIoU: vote {m_vote:.4}, paper {m_paper:.4}"
    );
}

/// `refine.noise = "probability"` reads the ONNX model's probabilities: against
/// `"weighted"` it changes N with the model and nothing with recorded label images (which
/// carry none).
#[test]
fn probability_noise_uses_the_models_probabilities() {
    let rec = recording();
    let dir = tempdir();
    for (name, mode) in [("weighted", "weighted"), ("probability", "probability")] {
        std::fs::write(
            dir.path().join(format!("{name}.toml")),
            format!("[refine]\nnoise = \"{mode}\"\n"),
        )
        .expect("write");
    }
    let run = |out: &str, parser: &str, config: &str| {
        run_two_frames(
            dir.path(),
            rec,
            out,
            &["--parser", parser, "--config", config],
        )
        .0
    };
    let model_w = run("model_w", "model", "weighted.toml");
    let model_p = run("model_p", "model", "probability.toml");
    assert_eq!(
        metrics(&model_w, "Reference"),
        metrics(&model_p, "Reference")
    );
    let (n_w, n_p) = (
        metrics(&model_w, "N").biou.expect("BIoU"),
        metrics(&model_p, "N").biou.expect("BIoU"),
    );
    assert!(
        (n_w - n_p).abs() > 1e-4,
        "N BIoU: weighted {n_w}, probability {n_p}"
    );
    let rec_w = run("rec_w", "recorded", "weighted.toml");
    let rec_p = run("rec_p", "recorded", "probability.toml");
    for name in ["Reference", "M", "N", "M-N", "M-R-N"] {
        assert_eq!(metrics(&rec_w, name), metrics(&rec_p, name), "{name}");
    }
}

#[test]
fn sigterm_and_sigint_leave_no_temporary_and_the_run_resumes() {
    let rec = recording();
    let dir = tempdir();
    for (signal, status) in [("-TERM", 143), ("-INT", 130)] {
        let out = format!("out{status}");
        let child = Command::new(env!("CARGO_BIN_EXE_bodyseg"))
            .args(on_recording("run", rec, &out, &["-q"]))
            .current_dir(dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        // Signal it while it writes (a frame's files are in flight most of the time).
        let clouds = dir.path().join(&out).join("clouds");
        let start = Instant::now();
        while std::fs::read_dir(&clouds).map_or(0, |d| d.count()) == 0
            && start.elapsed() < Duration::from_secs(120)
        {
            std::thread::sleep(Duration::from_millis(2));
        }
        let kill = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .expect("kill");
        assert!(kill.success());
        let result = child.wait_with_output().expect("wait");
        let err = String::from_utf8_lossy(&result.stderr).into_owned();
        if result.status.code() == Some(0) {
            continue; // finished before the signal: nothing to check
        }
        assert_eq!(result.status.code(), Some(status), "{err}");
        assert!(err.starts_with("error: interrupted ("), "{err}");
        let hidden: Vec<String> = tree(&dir.path().join(&out))
            .into_iter()
            .filter(|f| f.rsplit('/').next().is_some_and(|n| n.starts_with('.')))
            .collect();
        assert!(hidden.is_empty(), "left behind: {hidden:?}");
        let again = bodyseg(dir.path(), &on_recording("run", rec, &out, &["-q"]));
        assert_ok(&again, "resumed run");
    }
}
