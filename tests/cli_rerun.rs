//! `bodyseg run --rerun` and `bodyseg view` on the shared 3-camera synthetic recording, the
//! `.rrd` read back by the Rerun Python SDK of the same version (`scripts/check_rrd.py`,
//! its dataframe API): every entity for every frame, colour images equal to the
//! recording's files byte for byte, point counts equal to the PLY files',
//! box counts equal to the boxes JSON, the timeline's length. Built with the `rerun`
//! feature (without it: the flag's error); the SDK check is skipped (saying why) when the
//! Python SDK is not installed.
//! `BODYSEG_RERUN_PYTHON` names the Python that has it (default `python3`).

#[cfg(feature = "rerun")]
use crate::common::{FRAMES, assert_ok, bodyseg, stdout};
use crate::common::{convert_data, recording, run_recording, stderr, tempdir};
#[cfg(feature = "rerun")]
use std::path::Path;
#[cfg(feature = "rerun")]
use std::process::Command;

#[cfg(feature = "rerun")]
const CAMERAS: &str = "cam0,cam1,cam2";

#[cfg(feature = "rerun")]
fn python() -> String {
    std::env::var("BODYSEG_RERUN_PYTHON").unwrap_or_else(|_| "python3".into())
}

#[cfg(feature = "rerun")]
/// Whether `python` has `rerun` and `datafusion` (the dataframe API).
fn sdk_installed() -> bool {
    Command::new(python())
        .args(["-c", "import rerun, datafusion"])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[cfg(feature = "rerun")]
/// Runs scripts/check_rrd.py on `rrd` against the run `out`; panics with its output on
/// failure.
fn check(rrd: &Path, out: &Path, rec: &Path, extra: &[&str]) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check_rrd.py");
    let o = Command::new(python())
        .arg(script)
        .arg(rrd)
        .arg("--run")
        .arg(out)
        .args(["--cameras", CAMERAS])
        .arg("--recording")
        .arg(rec)
        .args(extra)
        .output()
        .expect("run python");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "check_rrd.py failed:\n{text}");
    text
}

#[cfg(feature = "rerun")]
#[test]
fn run_rerun_writes_a_file_the_rerun_sdk_reads_with_every_entity() {
    let rec = recording();
    let rig = std::fs::read_to_string(rec.join("rig.toml")).expect("rig.toml");
    for c in CAMERAS.split(',') {
        assert!(rig.contains(c), "the shared recording has camera {c}");
    }
    let dir = tempdir();
    // With the clusters layer (off by default: `bodyseg view`'s file below has none).
    let run = run_recording(
        dir.path(),
        &[
            "--write-stages",
            "--rerun",
            "out/run.rrd",
            "--rerun-clusters",
        ],
    );
    assert_ok(&run, "bodyseg run --rerun --rerun-clusters");
    let out = dir.path().join("out");
    let rrd = out.join("run.rrd");
    assert!(rrd.is_file(), "{}", rrd.display());
    assert!(!out.join("run.rrd.partial").exists(), "partial file left");
    // The file streams: it grows with the frames, a few MB for 8 small frames.
    let size = std::fs::metadata(&rrd).expect("size").len();
    assert!(size > 100_000, "{size} bytes");

    // From the finished run's files, without recomputing.
    let view = bodyseg(
        dir.path(),
        &[
            "view",
            rec.to_str().expect("utf-8"),
            "--run",
            "out",
            "--rerun",
            "view.rrd",
        ],
    );
    assert_ok(&view, "bodyseg view");
    assert!(
        stdout(&view).contains(&format!("({FRAMES} frames)")),
        "{}",
        stdout(&view)
    );

    if !sdk_installed() {
        eprintln!(
            "SKIPPED the Rerun SDK check: {} has no `rerun` / `datafusion` \
             (pip install \"rerun-sdk[datafusion]==0.36.3\", or set BODYSEG_RERUN_PYTHON)",
            python()
        );
        return;
    }
    // The colour images are the recording's files, byte for byte (`--recording`).
    let text = check(&rrd, &out, rec, &["--expect-scores", "--clusters", "yes"]);
    assert!(text.contains(&format!("{FRAMES} frames")), "{text}");
    let text = check(
        &dir.path().join("view.rrd"),
        &out,
        rec,
        &["--expect-scores", "--clusters", "no"],
    );
    assert!(text.contains(&format!("{FRAMES} frames")), "{text}");
}

#[test]
fn rerun_on_several_recordings_is_refused() {
    let rec = recording();
    let dir = tempdir();
    let data = dir.path().join("data");
    std::fs::create_dir_all(&data).expect("mkdir");
    for name in ["a", "b"] {
        crate::common::copy_tree(rec, &data.join(name));
    }
    let o = convert_data(dir.path(), "conv", &["--rerun", "conv.rrd"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("one recording"), "{}", stderr(&o));
    assert!(!dir.path().join("conv.rrd").exists());
}

#[cfg(not(feature = "rerun"))]
#[test]
fn rerun_without_the_feature_says_how_to_build() {
    let dir = tempdir();
    let o = run_recording(dir.path(), &["--rerun", "run.rrd"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--features rerun"), "{}", stderr(&o));
    assert!(!dir.path().join("run.rrd").exists());
}
