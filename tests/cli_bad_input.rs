//! Bad input: exit status 1, one `error:` line on stderr naming the file or the
//! configuration field, and no output file (an existing one is left as it was).

use crate::common::{assert_one_error, bodyseg, files_in, refine_scene, tempdir, write_scene};
use std::path::Path;

/// Runs `bodyseg refine` with the scene's inputs, `extra` args, and `--out out.ply`.
fn refine(d: &Path, cloud: &str, boxes: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["refine", "--cloud", cloud, "--boxes", boxes];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", "out.ply"]);
    bodyseg(d, &args)
}

/// Asserts exit status 1, exactly one stderr line `error: ...` holding every `needle`,
/// and that the folder holds the same files as before (no output, no temporary).
fn assert_fails(out: &std::process::Output, d: &Path, before: &[String], needles: &[&str]) {
    let err = assert_one_error(out, d, before, needles);
    // Each cause once: an error printing its cause in its message must not also chain it
    // as `source()` (`x.ply: cannot read: No such file ...: No such file ...`).
    let parts: Vec<&str> = err.trim_end_matches('\n').split(": ").collect();
    for (i, part) in parts.iter().enumerate() {
        assert!(
            !parts[i + 1..].contains(part),
            "{part:?} printed twice: {err}"
        );
    }
}

/// A hand-written ASCII PLY with the given vertex property lines and data lines.
fn ascii_ply(props: &[&str], rows: &[&str]) -> String {
    let mut s = format!("ply\nformat ascii 1.0\nelement vertex {}\n", rows.len());
    for p in props {
        s.push_str(&format!("property {p}\n"));
    }
    s.push_str("end_header\n");
    for r in rows {
        s.push_str(r);
        s.push('\n');
    }
    s
}

const XYZ_LABEL: [&str; 4] = ["float x", "float y", "float z", "uchar label"];

#[test]
fn ply_without_label_property() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let text = ascii_ply(&XYZ_LABEL[..3], &["0 0 1", "0.1 0 1"]);
    std::fs::write(d.join("nolabel.ply"), text).expect("write");
    let before = files_in(d);
    let out = refine(d, "nolabel.ply", "boxes.json", &[]);
    assert_fails(&out, d, &before, &["nolabel.ply", "'label'"]);
}

#[test]
fn truncated_ply() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let bytes = std::fs::read(d.join("in.ply")).expect("in.ply");
    std::fs::write(d.join("cut.ply"), &bytes[..bytes.len() / 2]).expect("write");
    let before = files_in(d);
    let out = refine(d, "cut.ply", "boxes.json", &[]);
    assert_fails(&out, d, &before, &["cut.ply", "truncated"]);
}

#[test]
fn boxes_file_that_is_not_json() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    std::fs::write(d.join("boxes.txt"), "person at 0, 0\n").expect("write");
    let before = files_in(d);
    let out = refine(d, "in.ply", "boxes.txt", &[]);
    assert_fails(&out, d, &before, &["boxes.txt", "JSON"]);
}

#[test]
fn non_positive_radius_in_the_config_file() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    for (name, value) in [
        ("neg.toml", "-1"),
        ("zero.toml", "0.0"),
        ("nan.toml", "nan"),
    ] {
        std::fs::write(d.join(name), format!("[refine]\neps_m = {value}\n")).expect("write");
    }
    let before = files_in(d);
    for name in ["neg.toml", "zero.toml", "nan.toml"] {
        let out = refine(d, "in.ply", "boxes.json", &["--config", name]);
        assert_fails(&out, d, &before, &[name, "refine.eps_m must be"]);
    }
}

#[test]
fn non_positive_radius_on_the_command_line() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let before = files_in(d);
    for flag in [
        &["--eps-m", "-1"][..],
        &["--eps-m=0"],
        &["--eps-m", "-0.05"],
    ] {
        let out = refine(d, "in.ply", "boxes.json", flag);
        assert_fails(&out, d, &before, &["--eps-m", "refine.eps_m must be"]);
    }
}

#[test]
fn nan_coordinates() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let text = ascii_ply(&XYZ_LABEL, &["0 0 1 2", "nan 0 1 2", "0.1 0 1 2"]);
    std::fs::write(d.join("nan.ply"), text).expect("write");
    let before = files_in(d);
    let out = refine(d, "nan.ply", "boxes.json", &[]);
    assert_fails(&out, d, &before, &["nan.ply", "vertex 1", "x is NaN"]);
}

#[test]
fn missing_input_files() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let before = files_in(d);
    let out = refine(d, "missing.ply", "boxes.json", &[]);
    assert_fails(&out, d, &before, &["missing.ply", "cannot read"]);
    let out = refine(d, "in.ply", "missing.json", &[]);
    assert_fails(&out, d, &before, &["missing.json", "cannot read"]);
    let out = refine(d, "in.ply", "boxes.json", &["--config", "missing.toml"]);
    assert_fails(&out, d, &before, &["missing.toml", "cannot read"]);
    let out = bodyseg(d, &["eval", "--pred", "in.ply", "--gt", "missing_gt.ply"]);
    assert_fails(&out, d, &before, &["missing_gt.ply", "cannot read"]);
    let out = bodyseg(d, &["eval", "--merge", "missing.json"]);
    assert_fails(&out, d, &before, &["missing.json", "cannot read"]);
}

#[test]
fn unknown_config_key() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    std::fs::write(
        d.join("typo.toml"),
        "[refine]\neps_m = 0.05\nmin_pts = 10\n",
    )
    .expect("write");
    let before = files_in(d);
    let out = refine(d, "in.ply", "boxes.json", &["--config", "typo.toml"]);
    assert_fails(&out, d, &before, &["typo.toml", "line 3", "refine.min_pts"]);
}

#[test]
fn bad_set_key_or_value_names_the_key() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let before = files_in(d);
    let out = refine(d, "in.ply", "boxes.json", &["--set", "refine.min_pts=10"]);
    assert_fails(
        &out,
        d,
        &before,
        &["--set refine.min_pts=10", "unknown key `refine.min_pts`"],
    );
    let out = refine(d, "in.ply", "boxes.json", &["--set", "refine.eps_m=wide"]);
    assert_fails(
        &out,
        d,
        &before,
        &["--set refine.eps_m=wide", "refine.eps_m: "],
    );
    let out = refine(d, "in.ply", "boxes.json", &["--set", "refine.eps_m=-1"]);
    assert_fails(
        &out,
        d,
        &before,
        &["--set refine.eps_m=-1", "refine.eps_m must be"],
    );
    let out = refine(d, "in.ply", "boxes.json", &["--set", "refine.eps_m"]);
    assert_fails(&out, d, &before, &["refine.eps_m", "KEY=VALUE"]);
}

#[test]
fn report_that_is_not_json() {
    let dir = tempdir();
    let d = dir.path();
    std::fs::write(d.join("report.json"), "not a report").expect("write");
    let before = files_in(d);
    let out = bodyseg(d, &["eval", "--merge", "report.json", "--out", "merged.md"]);
    assert_fails(&out, d, &before, &["report.json", "not a bodyseg report"]);
}

#[test]
fn a_failed_run_leaves_an_existing_output_untouched() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    std::fs::write(d.join("out.ply"), "previous result").expect("write");
    std::fs::write(d.join("bad.json"), "{\"boxes\": [").expect("write");
    let before = files_in(d);
    let out = refine(d, "in.ply", "bad.json", &[]);
    assert_fails(&out, d, &before, &["bad.json"]);
    let kept = std::fs::read_to_string(d.join("out.ply")).expect("out.ply");
    assert_eq!(kept, "previous result");
}

#[test]
fn output_in_a_missing_folder() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let before = files_in(d);
    let out = refine_scene(d, &["--out", "no/such/dir/o.ply"]);
    assert_fails(&out, d, &before, &["no/such/dir/o.ply", "cannot write"]);
}

#[test]
fn multi_view_vote_on_a_cloud_file() {
    // The vote needs every camera's images: `bodyseg refine` on a cloud has none, and says
    // so instead of silently refining the projected labels.
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    std::fs::write(d.join("vote.toml"), "[refine]\nvote = \"multi_view\"\n").expect("write");
    let before = files_in(d);
    let out = refine(d, "in.ply", "boxes.json", &["--config", "vote.toml"]);
    assert_fails(&out, d, &before, &["refine.vote", "bodyseg run"]);
}
