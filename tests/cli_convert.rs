//! `bodyseg convert`: a folder of recordings converted whole, then in shards through the
//! Slurm scripts (run here as plain bash with the array variables Slurm would set); the
//! merged shard reports equal the whole conversion's report.

use crate::common::{
    FRAMES, assert_ok, bodyseg, bodyseg_line, convert_data, copy_tree, recording, stderr, tempdir,
    tree,
};
use bodyseg_eval::Report;
use std::path::Path;
use std::process::Command;

fn report(path: &Path) -> Report {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Report::from_json(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs a script of scripts/slurm with bash and the given environment.
fn slurm_script(dir: &Path, script: &str, args: &[&str], env: &[(&str, String)]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scripts/slurm")
        .join(script);
    let out = Command::new("bash")
        .arg(&path)
        .args(args)
        .current_dir(dir)
        .env("BODYSEG", env!("CARGO_BIN_EXE_bodyseg"))
        .envs(env.iter().map(|(k, v)| (*k, v.as_str())))
        .output()
        .expect("run bash");
    assert_ok(&out, &format!("{script} {args:?}"));
}

#[test]
fn a_folder_of_recordings_converts_whole_and_in_merged_shards_alike() {
    let dir = tempdir();
    let data = dir.path().join("data");
    // Two recordings (the same frames under two names) and a folder that is not one.
    copy_tree(recording(), &data.join("a"));
    copy_tree(recording(), &data.join("b"));
    std::fs::create_dir_all(data.join("notes")).expect("mkdir");

    let whole = convert_data(dir.path(), "whole", &[]);
    assert_ok(&whole, "bodyseg convert");
    let w = dir.path().join("whole");
    let files = tree(&w);
    for name in ["a", "b"] {
        for i in 0..FRAMES {
            for f in [
                format!("{name}/clouds/{i:06}.ply"),
                format!("{name}/boxes/{i:06}.json"),
            ] {
                assert!(files.contains(&f), "{f} missing: {files:?}");
            }
        }
        assert!(files.contains(&format!("{name}/report.json")), "{files:?}");
    }
    // No figures or label images in a conversion.
    assert!(
        files
            .iter()
            .all(|f| !f.contains("figures/") && !f.contains("labels/"))
    );
    let all = report(&w.join("report.json"));
    let a = report(&w.join("a/report.json"));
    assert_eq!(
        all.get("M-R-N").expect("M-R-N").confusion().total(),
        2 * a.get("M-R-N").expect("M-R-N").confusion().total(),
        "the overall report sums both recordings"
    );

    // Three shards through the Slurm scripts, array ids 1-3 (the shard counts from the
    // first), then the merge job.
    let out = dir.path().join("sharded");
    for task in 1..=3 {
        slurm_script(
            dir.path(),
            "convert.sbatch",
            &["data", "recording", out.to_str().expect("utf-8"), "-q"],
            &[
                ("SLURM_ARRAY_TASK_ID", task.to_string()),
                ("SLURM_ARRAY_TASK_MIN", "1".into()),
                ("SLURM_ARRAY_TASK_COUNT", "3".into()),
            ],
        );
    }
    slurm_script(
        dir.path(),
        "merge.sbatch",
        &[out.to_str().expect("utf-8"), "3"],
        &[],
    );
    let merged = report(&out.join("report.json"));
    for name in all.names() {
        assert_eq!(
            merged.get(name).map(|c| c.stats().clone()),
            all.get(name).map(|c| c.stats().clone()),
            "{name}: merged shards = whole conversion"
        );
    }
    // Every frame converted exactly once, with the same bytes.
    let sharded: Vec<String> = tree(&out)
        .into_iter()
        .filter(|f| f.contains("/clouds/"))
        .collect();
    let whole_clouds: Vec<String> = files
        .into_iter()
        .filter(|f| f.contains("/clouds/"))
        .collect();
    assert_eq!(sharded, whole_clouds);
    for f in &sharded {
        assert!(
            std::fs::read(out.join(f)).expect("read") == std::fs::read(w.join(f)).expect("read"),
            "{f}"
        );
    }
    // A shard run again skips its frames.
    let again = convert_data(dir.path(), "sharded", &["--shard", "0/3"]);
    assert_ok(&again, "shard again");
    assert!(stderr(&again).contains("0 processed"), "{}", stderr(&again));

    // A shard holding frames of one recording only (job 9 of 16: b's second frame) reports
    // on that one; it failed writing a report into the other's folder, which it never made.
    let sparse = convert_data(dir.path(), "sparse", &["--shard", "9/24"]);
    assert_ok(&sparse, "a shard with one recording's frames");
    let files = tree(&dir.path().join("sparse"));
    assert!(
        files.contains(&"b/report.shard-9-of-24.md".to_string())
            && files.contains(&"report.shard-9-of-24.md".to_string())
            && !files.iter().any(|f| f.starts_with("a/")),
        "{files:?}"
    );
}

#[test]
fn convert_errors_name_the_input() {
    let dir = tempdir();
    std::fs::create_dir_all(dir.path().join("empty")).expect("mkdir");
    let out = bodyseg_line(
        dir.path(),
        "convert --input empty --format recording --out o",
    );
    assert_eq!(out.status.code(), Some(1));
    let e = stderr(&out);
    assert!(e.contains("empty") && e.contains("no recording"), "{e}");
    let out = bodyseg_line(
        dir.path(),
        "convert --input empty --format recording --out o --shard 3/3",
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("K/N"), "{}", stderr(&out));
}

#[test]
fn a_3dpeople_dataset_converts_to_labelled_clouds_and_reports_the_broken_view() {
    let dir = tempdir();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/3dpeople");
    let args = [
        "convert",
        "--input",
        fixture.to_str().expect("utf-8"),
        "--format",
        "3dpeople",
        "--out",
        "out",
        "--intrinsics",
        "64,48,70,70,32,24",
    ];
    let first = bodyseg(dir.path(), &args);
    assert_eq!(first.status.code(), Some(3), "{}", stderr(&first));
    let log = stderr(&first);
    assert!(
        log.contains("error: frame man01/01_01_walk/camera01/0001") && log.contains("depth.mat"),
        "{log}"
    );
    let out = dir.path().join("out");
    let camera = bodyseg_pipeline::ThreeDPeopleCamera::pinhole(64, 48, 70.0, 70.0, 32.0, 24.0);
    let views = bodyseg_pipeline::list_3dpeople_views(&fixture).expect("list");
    let mut converted = 0;
    for view in &views {
        let ply = out.join(format!("clouds/{}.ply", view.stem()));
        match bodyseg_pipeline::read_3dpeople_view(view, &camera) {
            Ok(want) => {
                let got = bodyseg_io::read_ply(&ply).expect("converted cloud");
                assert_eq!(got.labels, want.labels, "{}", view.stem());
                assert_eq!(got.positions_m, want.positions_m, "{}", view.stem());
                assert_eq!(got.colors, want.colors, "camera colours: {}", view.stem());
                assert!(got.labels.iter().any(|l| l.is_body()), "{}", view.stem());
                converted += 1;
            }
            Err(_) => assert!(!ply.exists(), "{}", view.stem()),
        }
    }
    assert_eq!(converted, 4);
    // Run again: the good views are skipped, the broken one fails again.
    let again = bodyseg(dir.path(), &args);
    assert_eq!(again.status.code(), Some(3));
    assert!(stderr(&again).contains("4 skipped"), "{}", stderr(&again));
    // Without the fixture's intrinsics every view has the wrong size: each one is named.
    let mut without_intrinsics = args[..args.len() - 3].to_vec();
    without_intrinsics.push("o2");
    let wrong = bodyseg(dir.path(), &without_intrinsics);
    assert_eq!(wrong.status.code(), Some(3));
    assert!(
        stderr(&wrong).contains("5 frames failed"),
        "{}",
        stderr(&wrong)
    );
}
