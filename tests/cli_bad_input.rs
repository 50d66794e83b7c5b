//! Bad input: exit status 1, one `error:` line on stderr naming the file or the
//! configuration field, and no output file (an existing one is left as it was).

use crate::common::{SceneDir, words};

/// Runs `bodyseg ARGS` in the scene's folder and asserts exit status 1, exactly one stderr
/// line `error: ...` holding every `needle`, and that the folder holds the same files as
/// before (no output, no temporary).
fn fails(s: &SceneDir, args: &[&str], needles: &[&str]) {
    let err = s.fails(args, needles);
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

/// [`fails`] for `bodyseg refine --cloud CLOUD --boxes BOXES EXTRA... --out out.ply`.
fn refine_fails(s: &SceneDir, cloud: &str, boxes: &str, extra: &[&str], needles: &[&str]) {
    let mut args = vec!["refine", "--cloud", cloud, "--boxes", boxes];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", "out.ply"]);
    fails(s, &args, needles);
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

/// With the scene's cloud and boxes: `refine --config NAME` for each (name, text) written.
const BAD_CONFIG_FILES: [(&str, &str, &[&str]); 4] = [
    (
        "neg.toml",
        "[refine]\neps_m = -1\n",
        &["refine.eps_m must be"],
    ),
    (
        "zero.toml",
        "[refine]\neps_m = 0.0\n",
        &["refine.eps_m must be"],
    ),
    (
        "nan.toml",
        "[refine]\neps_m = nan\n",
        &["refine.eps_m must be"],
    ),
    (
        "typo.toml",
        "[refine]\neps_m = 0.05\nmin_pts = 10\n",
        &["line 3", "refine.min_pts"],
    ),
];

#[test]
fn bad_config_files() {
    let s = SceneDir::new();
    for (name, text, needles) in BAD_CONFIG_FILES {
        s.write(name, text);
        let needles: Vec<&str> = [name].iter().chain(needles).copied().collect();
        refine_fails(&s, "in.ply", "boxes.json", &["--config", name], &needles);
    }
}

#[test]
fn bad_cloud_and_boxes_files() {
    let s = SceneDir::new();
    let bytes = std::fs::read(s.path().join("in.ply")).expect("in.ply");
    s.write("cut.ply", &bytes[..bytes.len() / 2])
        .write(
            "nolabel.ply",
            ascii_ply(&XYZ_LABEL[..3], &["0 0 1", "0.1 0 1"]),
        )
        .write(
            "nan.ply",
            ascii_ply(&XYZ_LABEL, &["0 0 1 2", "nan 0 1 2", "0.1 0 1 2"]),
        )
        .write("boxes.txt", "person at 0, 0\n");
    for (cloud, boxes, needles) in [
        ("nolabel.ply", "boxes.json", &["nolabel.ply", "'label'"][..]),
        ("cut.ply", "boxes.json", &["cut.ply", "truncated"]),
        (
            "nan.ply",
            "boxes.json",
            &["nan.ply", "vertex 1", "x is NaN"],
        ),
        ("in.ply", "boxes.txt", &["boxes.txt", "JSON"]),
        ("missing.ply", "boxes.json", &["missing.ply", "cannot read"]),
        ("in.ply", "missing.json", &["missing.json", "cannot read"]),
    ] {
        refine_fails(&s, cloud, boxes, &[], needles);
    }
}

#[test]
fn bad_command_lines() {
    let s = SceneDir::new();
    for (extra, needles) in [
        (
            &["--eps-m", "-1"][..],
            &["--eps-m", "refine.eps_m must be"][..],
        ),
        (&["--eps-m=0"], &["--eps-m", "refine.eps_m must be"]),
        (&["--eps-m", "-0.05"], &["--eps-m", "refine.eps_m must be"]),
        (
            &["--config", "missing.toml"],
            &["missing.toml", "cannot read"],
        ),
        (
            &["--set", "refine.min_pts=10"],
            &["--set refine.min_pts=10", "unknown key `refine.min_pts`"],
        ),
        (
            &["--set", "refine.eps_m=wide"],
            &["--set refine.eps_m=wide", "refine.eps_m: "],
        ),
        (
            &["--set", "refine.eps_m=-1"],
            &["--set refine.eps_m=-1", "refine.eps_m must be"],
        ),
        (&["--set", "refine.eps_m"], &["refine.eps_m", "KEY=VALUE"]),
    ] {
        refine_fails(&s, "in.ply", "boxes.json", extra, needles);
    }
}

#[test]
fn bad_eval_inputs() {
    let s = SceneDir::new();
    s.write("report.json", "not a report");
    fails(
        &s,
        &["eval", "--pred", "in.ply", "--gt", "missing_gt.ply"],
        &["missing_gt.ply", "cannot read"],
    );
    fails(
        &s,
        &["eval", "--merge", "missing.json"],
        &["missing.json", "cannot read"],
    );
    fails(
        &s,
        &["eval", "--merge", "report.json", "--out", "merged.md"],
        &["report.json", "not a bodyseg report"],
    );
}

#[test]
fn a_failed_run_leaves_an_existing_output_untouched() {
    let s = SceneDir::new();
    s.write("out.ply", "previous result")
        .write("bad.json", "{\"boxes\": [");
    refine_fails(&s, "in.ply", "bad.json", &[], &["bad.json"]);
    let kept = std::fs::read_to_string(s.path().join("out.ply")).expect("out.ply");
    assert_eq!(kept, "previous result");
}

#[test]
fn output_in_a_missing_folder() {
    let s = SceneDir::new();
    let args = words("refine --cloud in.ply --boxes boxes.json --out no/such/dir/o.ply");
    fails(&s, &args, &["no/such/dir/o.ply", "cannot write"]);
}

#[test]
fn multi_view_vote_on_a_cloud_file() {
    // The vote needs every camera's images: `bodyseg refine` on a cloud has none, and says
    // so instead of silently refining the projected labels.
    let s = SceneDir::new();
    s.write("vote.toml", "[refine]\nvote = \"multi_view\"\n");
    let needles = ["refine.vote", "bodyseg run"];
    refine_fails(
        &s,
        "in.ply",
        "boxes.json",
        &["--config", "vote.toml"],
        &needles,
    );
}
