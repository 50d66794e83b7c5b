//! `bodyseg refine` on a synthetic person, then `bodyseg eval` of its output.

use crate::common::{
    SEED, assert_ok, bodyseg, index_origins, refine_scene, stderr, tempdir, words, write_scene,
};
use bodyseg_io::read_ply;
use bodyseg_pipeline::PipelineConfig;

/// BIoU of the single configuration of a `bodyseg eval --format json` report.
fn biou(json: &str) -> f64 {
    let v: serde_json::Value = serde_json::from_str(json).expect("report is JSON");
    let configurations = v["configurations"].as_array().expect("configurations");
    assert_eq!(configurations.len(), 1, "{json}");
    configurations[0]["metrics"]["biou"]
        .as_f64()
        .expect("biou is a number")
}

#[test]
fn refine_keeps_the_points_and_raises_biou() {
    let dir = tempdir();
    let d = dir.path();
    let scene = write_scene(d);
    let out = refine_scene(d, &["--out", "refined.ply"]);
    assert_ok(&out, "bodyseg refine");

    // One summary line per stage, with its time.
    let err = stderr(&out);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "seed {SEED}: {err}");
    for (line, stage) in lines.iter().zip(["read", "refine", "write"]) {
        assert!(line.starts_with(stage) && line.contains(" ms "), "{err}");
    }
    assert!(lines[0].contains("20000 points"), "{err}");
    assert!(
        lines[1].contains("1 person,") && lines[1].contains("labels changed"),
        "{err}"
    );

    // Same points, same order, same origins; every label known.
    let refined = read_ply(&d.join("refined.ply")).expect("refined.ply reads back");
    let input = &scene.person.cloud;
    assert_eq!(refined.positions_m, input.positions_m);
    assert_eq!(refined.origins, index_origins(input.len()));
    assert!(refined.labels.iter().all(|l| !l.is_unknown()));
    assert_ne!(refined.labels, input.labels, "refinement changed no label");

    // The resolved configuration sits beside the output and is the defaults.
    let resolved = PipelineConfig::load(&d.join("refined.config.resolved.toml"));
    assert_eq!(resolved.ok(), Some(PipelineConfig::default()));

    // BIoU of refined vs GT beats input vs GT.
    let score = |pred: &str| {
        let out = bodyseg(
            d,
            &["eval", "--pred", pred, "--gt", "gt.ply", "--format", "json"],
        );
        assert_ok(&out, "bodyseg eval");
        biou(&String::from_utf8_lossy(&out.stdout))
    };
    let before = score("in.ply");
    let after = score("refined.ply");
    assert!(
        after > before,
        "seed {SEED}: BIoU input {before:.4}, refined {after:.4}"
    );
}

#[test]
fn flags_override_the_config_file_and_ascii_output_reads_back() {
    let dir = tempdir();
    let d = dir.path();
    let scene = write_scene(d);
    std::fs::write(
        d.join("my.toml"),
        "[refine]\neps_m = 0.04\nmin_points = 30\nsteps = \"M-R-N\"\n",
    )
    .expect("write my.toml");
    let out = refine_scene(
        d,
        &words("--config my.toml --steps m,n --min-points 20 --ascii --quiet --out r.ply"),
    );
    assert_ok(&out, "bodyseg refine --config --steps --ascii");
    assert_eq!(stderr(&out), "", "--quiet prints nothing");
    let head = std::fs::read(d.join("r.ply")).expect("r.ply exists");
    assert!(head.starts_with(b"ply\nformat ascii 1.0\n"));
    let refined = read_ply(&d.join("r.ply")).expect("ASCII output reads back");
    assert_eq!(refined.positions_m, scene.person.cloud.positions_m);

    let resolved = PipelineConfig::load(&d.join("r.config.resolved.toml")).expect("resolved");
    assert_eq!(resolved.refine.eps_m, 0.04, "from the file");
    assert_eq!(resolved.refine.min_points, 20, "the flag beats the file");
    assert_eq!(
        resolved.refine.steps.to_string(),
        "M-N",
        "the flag beats the file"
    );
    assert_eq!(resolved.refine.label_penalty_m, f32::INFINITY, "a default");
}

#[test]
fn reference_steps_leave_labels_untouched() {
    let dir = tempdir();
    let d = dir.path();
    let scene = write_scene(d);
    let out = refine_scene(d, &["--steps", "reference", "--out", "same.ply"]);
    assert_ok(&out, "bodyseg refine --steps reference");
    let same = read_ply(&d.join("same.ply")).expect("same.ply reads back");
    assert_eq!(same.labels, scene.person.cloud.labels);
    assert!(
        stderr(&out).contains(" 0 labels changed"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn config_files_layer_then_set_then_flags() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    std::fs::write(
        d.join("a.toml"),
        "[refine]\neps_m = 0.04\nmin_points = 30\n",
    )
    .expect("a");
    std::fs::write(d.join("b.toml"), "[refine]\neps_m = 0.045\n").expect("b");
    let out = refine_scene(
        d,
        &words(
            "--config a.toml --config b.toml --set refine.steps=M-N --set refine.min_points=25 --min-points 20 --out r.ply",
        ),
    );
    assert_ok(&out, "bodyseg refine --config --config --set");
    let resolved = PipelineConfig::load(&d.join("r.config.resolved.toml")).expect("resolved");
    assert_eq!(resolved.refine.eps_m, 0.045, "the later file wins");
    assert_eq!(
        resolved.refine.steps.to_string(),
        "M-N",
        "--set beats the files"
    );
    assert_eq!(resolved.refine.min_points, 20, "the flag beats --set");
}
