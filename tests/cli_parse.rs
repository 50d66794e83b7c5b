//! `bodyseg parse` on a small synthetic recording (one camera, colour 320x180): the default
//! parser (BlazePose on the person found from depth) and the bundled model against the
//! recording's exact 2D truth, `--recorded`, and every bad input of the
//! issue (ONNX Runtime library missing, model output not 7 channels, sidecar missing or
//! inconsistent, colour image that does not decode): one error line, exit 1, no output.
//!
//! Needs the ONNX Runtime library (`scripts/setup_onnxruntime.sh`, which scripts/test.sh
//! runs) and the bundled model `models/bodyseg_parser_small.onnx`.

use crate::common::{assert_ok, bodyseg, bodyseg_env, bodyseg_line, stderr, tempdir};
use bodyseg_core::{Class, Label};
use bodyseg_io::read_label_png;
use std::path::{Path, PathBuf};

/// Frame parsed by the tests.
const FRAME: &str = "000000";

/// Writes a one-camera, one-frame synthetic recording `rec` in `dir`.
fn recording(dir: &Path) -> PathBuf {
    let out = bodyseg_line(
        dir,
        "synth --preset single --seed 7 --frames 1 --no-preview --set rig.cameras=1 --set rig.color_width=320 --out rec",
    );
    assert_ok(&out, "synth");
    dir.join("rec")
}

/// A committed test model of bodyseg-parsing.
fn test_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/parsing/tests/data")
        .join(name)
}

/// Asserts a failed run: exit 1, one `error:` line containing `want`, no `parsed/`.
fn assert_fails(dir: &Path, out: &std::process::Output, want: &str) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(
        err.starts_with("error: ") && err.contains(want),
        "want {want:?}: {err}"
    );
    assert!(!dir.join("parsed").exists(), "nothing written on failure");
}

/// `parse --recording rec --frame FRAME --out parsed EXTRA...`.
fn parse_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "parse",
        "--recording",
        "rec",
        "--frame",
        FRAME,
        "--out",
        "parsed",
    ];
    args.extend_from_slice(extra);
    args
}

/// Parses [`FRAME`] of `rec` in `d` into `parsed` with `extra` arguments, checks the
/// outputs and the model named on stderr, and returns the person-vs-background IoU
/// against the recording's exact 2D truth.
fn parse_person_iou(d: &Path, rec: &Path, extra: &[&str], model: &str) -> f64 {
    let out = bodyseg(d, &parse_args(extra));
    assert_ok(&out, "parse");
    let err = stderr(&out);
    assert!(err.contains(&format!("model {model}")), "{err}");
    let pred = read_label_png(&d.join("parsed/cam0/parsing/000000.png")).expect("labels");
    assert!(d.join("parsed/cam0/parsing_preview/000000.png").is_file());
    assert!(d.join("parsed/parse.config.resolved.toml").is_file());
    let truth = read_label_png(&rec.join("cam0/labels/000000.png")).expect("truth");
    assert_eq!((pred.width, pred.height), (truth.width, truth.height));
    let body = |l: &Label| l.class().is_some_and(|c| c != Class::Background);
    let (mut inter, mut union) = (0usize, 0usize);
    for (p, t) in pred.labels.iter().zip(&truth.labels) {
        inter += usize::from(body(p) && body(t));
        union += usize::from(body(p) || body(t));
    }
    assert!(union > 0, "the person is in view");
    inter as f64 / union as f64
}

#[test]
fn bundled_model_labels_the_person() {
    let dir = tempdir();
    let d = dir.path();
    let rec = recording(d);
    let iou = parse_person_iou(
        d,
        &rec,
        &["--set", "parsing.segmenter=onnx"],
        "bodyseg_parser_small.onnx",
    );
    // Person vs background: the bundled model reaches ~0.9 IoU on held-out synthetic
    // frames (models/bodyseg_parser_small.metrics.json); 0.6 leaves room for one hard view.
    assert!(iou >= 0.6, "person IoU {iou:.3}");
}

/// Person-vs-background IoU the default parser must reach on the test recording (it
/// measured 0.925 there; 0.6 as for the bundled model leaves room for other renderings).
const BLAZEPOSE_SYNTH_MIN_IOU: f64 = 0.6;

/// The default parser: BlazePose full on the person found from depth.
#[test]
fn blazepose_default_labels_the_person_found_from_depth() {
    let dir = tempdir();
    let d = dir.path();
    let rec = recording(d);
    let iou = parse_person_iou(d, &rec, &[], "blazepose_full.onnx");
    // Fails when no region or no person is found (IoU 0) or the mask misses the body.
    assert!(iou >= BLAZEPOSE_SYNTH_MIN_IOU, "person IoU {iou:.3}");
}

#[test]
fn recorded_labels_come_back_unchanged() {
    let dir = tempdir();
    let d = dir.path();
    let rec = recording(d);
    let out = bodyseg(d, &parse_args(&["--recorded"]));
    assert_ok(&out, "parse --recorded");
    let got = read_label_png(&d.join("parsed/cam0/parsing/000000.png")).expect("written");
    let want = read_label_png(&rec.join("cam0/parsing/000000.png")).expect("recorded");
    assert_eq!(got, want);
}

#[test]
fn bad_inputs_are_one_line_errors() {
    let dir = tempdir();
    let d = dir.path();
    recording(d);
    let parse = |model: &str| bodyseg(d, &parse_args(&["--model", model]));

    // ONNX Runtime library missing.
    std::fs::copy(test_data("tiny.onnx"), d.join("tiny.onnx")).expect("copy");
    std::fs::copy(test_data("tiny.json"), d.join("tiny.json")).expect("copy");
    let out = bodyseg_env(
        d,
        &parse_args(&["--model", "tiny.onnx"]),
        &[("ORT_DYLIB_PATH", "/nonexistent/libonnxruntime.so")],
    );
    assert_fails(
        d,
        &out,
        "/nonexistent/libonnxruntime.so: cannot load the ONNX Runtime library",
    );

    // Output of 5 channels (the model is otherwise valid, its sidecar too).
    std::fs::copy(test_data("tiny_5ch.onnx"), d.join("five.onnx")).expect("copy");
    std::fs::copy(test_data("tiny.json"), d.join("five.json")).expect("copy");
    assert_fails(
        d,
        &parse("five.onnx"),
        "five.onnx: model output has 5 channels, expected 7",
    );

    // Sidecar missing.
    std::fs::copy(test_data("tiny.onnx"), d.join("alone.onnx")).expect("copy");
    assert_fails(d, &parse("alone.onnx"), "alone.json: cannot read");

    // Sidecar inconsistent with the model (input 64 vs the model's 32), and invalid.
    std::fs::copy(test_data("tiny.onnx"), d.join("big.onnx")).expect("copy");
    let sidecar = std::fs::read_to_string(test_data("tiny.json")).expect("sidecar");
    let big = sidecar.replace("[\n    32,\n    32\n  ]", "[64, 64]");
    assert_ne!(big, sidecar, "tiny.json layout changed");
    std::fs::write(d.join("big.json"), big).expect("write");
    assert_fails(
        d,
        &parse("big.onnx"),
        "big.json: input_size is [64, 64] but the model's input is 32x32",
    );
    let bad = sidecar.replace("\"std\": [", "\"std\": [0, ");
    std::fs::write(d.join("big.json"), bad).expect("write");
    assert_fails(d, &parse("big.onnx"), "big.json: bad model sidecar: ");

    // Colour image that does not decode.
    std::fs::write(d.join("rec/cam0/color/000000.png"), b"not a png").expect("write junk");
    assert_fails(
        d,
        &parse("tiny.onnx"),
        "color/000000.png: cannot decode colour image",
    );
}
