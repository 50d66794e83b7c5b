//! `bodyseg boxes`: geometry mode on a PCL file (the organised binary_compressed PCD
//! fixture of a synthetic hand-over, written by `scripts/gen_pcd_fixtures.py` with
//! pypcd4), labels and file mode on a synthetic recording, and bad input (one `error:`
//! line naming the file, exit 1, no output file).

use crate::common::{assert_ok, bodyseg, bodyseg_line, fails_in, stderr, tempdir};
use bodyseg_io::read_boxes;
use bodyseg_people::match_boxes;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/io/tests/data")
        .join(name)
}

#[test]
fn geometry_mode_finds_the_people_of_a_pcd_scene() {
    let dir = tempdir();
    let d = dir.path();
    // The fixture keeps every 4th depth pixel: a 4 cm voxel holds ~16x fewer points.
    std::fs::write(d.join("sparse.toml"), "[boxes]\nmin_voxel_points = 1\n").expect("config");
    let scene = fixture("scene_handover.pcd");
    let out = bodyseg(
        d,
        &[
            "boxes",
            "--cloud",
            &scene.display().to_string(),
            "--mode",
            "geometry",
            "--config",
            "sparse.toml",
            "--out",
            "boxes.json",
            "--preview",
            "top.png",
        ],
    );
    assert_ok(&out, "boxes --mode geometry");
    let err = stderr(&out);
    assert!(err.contains("2 person boxes (mode geometry)"), "{err}");
    let found = read_boxes(&d.join("boxes.json")).expect("boxes written");
    assert_eq!(found.frame, "scene_handover");
    let truth = read_boxes(&fixture("scene_handover_boxes.json")).expect("truth");
    let m = match_boxes(&truth.boxes, &found.boxes);
    assert!(m.is_good(), "{m:?}\n{found:?}");
    assert!(d.join("top.png").is_file());
    assert!(d.join("boxes.config.resolved.toml").is_file());
}

#[test]
fn labels_and_file_modes_on_a_recording() {
    let dir = tempdir();
    let d = dir.path();
    let out = bodyseg_line(
        d,
        "synth --preset handover --frames 1 --seed 5 --out rec --no-preview",
    );
    assert_ok(&out, "synth");
    let out = bodyseg_line(d, "boxes --recording rec --frame 000000 --out found.json");
    assert_ok(&out, "boxes --recording");
    let found = read_boxes(&d.join("found.json")).expect("found");
    let truth = read_boxes(&d.join("rec/boxes/000000.json")).expect("truth");
    let m = match_boxes(&truth.boxes, &found.boxes);
    assert!(m.is_good(), "{m:?}");
    assert_eq!(found.frame, "000000");
    // `bodyseg boxes` on frame 000000 of the recording in another mode.
    let args = |mode: &'static str, out: &'static str| {
        [
            "boxes",
            "--recording",
            "rec",
            "--frame",
            "000000",
            "--mode",
            mode,
            "--out",
            out,
        ]
    };
    // File mode reads the recording's own boxes back.
    let out = bodyseg(d, &args("file", "file.json"));
    assert_ok(&out, "boxes --mode file");
    assert_eq!(read_boxes(&d.join("file.json")).expect("file"), truth);
    // Geometry mode on a recording splits by the points' colours too: it reads the colour
    // images, and says which one is missing.
    let out = bodyseg(d, &args("geometry", "geometry.json"));
    assert_ok(&out, "boxes --mode geometry --recording");
    let found = read_boxes(&d.join("geometry.json")).expect("geometry");
    assert!(
        match_boxes(&truth.boxes, &found.boxes).is_good(),
        "{found:?}"
    );
    std::fs::remove_file(d.join("rec/cam0/color/000000.png")).expect("colour image");
    fails_in(d, &args("geometry", "none.json"), &["cam0", "000000.png"]);
}

const HEADER: &str = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

#[test]
fn bad_pcd_files_are_clear_errors() {
    let dir = tempdir();
    let d = dir.path();
    let write = |name: &str, bytes: &[u8]| std::fs::write(d.join(name), bytes).expect("write");
    write(
        "kind.pcd",
        format!("{HEADER}WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_lz4\n").as_bytes(),
    );
    let mut truncated = format!("{HEADER}WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA binary\n").into_bytes();
    truncated.extend_from_slice(&[0u8; 30]);
    write("truncated.pcd", &truncated);
    write(
        "count.pcd",
        format!("{HEADER}WIDTH 4\nHEIGHT 2\nPOINTS 7\nDATA ascii\n").as_bytes(),
    );
    let compressed = std::fs::read(fixture("xyzrgb_binary_compressed.pcd")).expect("fixture");
    write("cut.pcd", &compressed[..compressed.len() - 40]);
    let run = |cloud: &str, needles: &[&str]| {
        fails_in(
            d,
            &[
                "boxes", "--cloud", cloud, "--mode", "geometry", "--out", "b.json",
            ],
            needles,
        );
    };
    run(
        "kind.pcd",
        &["kind.pcd: unsupported PCD DATA kind 'binary_lz4'"],
    );
    run(
        "truncated.pcd",
        &["truncated.pcd: truncated PCD data: header declares 3 points of 12 bytes"],
    );
    run(
        "count.pcd",
        &["count.pcd: PCD header says WIDTH 4 x HEIGHT 2 = 8 but POINTS 7"],
    );
    run("cut.pcd", &["cut.pcd: truncated PCD data"]);
    run("missing.pcd", &["missing.pcd: cannot read"]);
    write("cloud.xyz", b"0 0 0\n");
    run("cloud.xyz", &["cloud.xyz: unknown cloud format"]);
    // File mode belongs to a recording frame.
    fails_in(
        d,
        &[
            "boxes", "--cloud", "kind.pcd", "--mode", "file", "--out", "b.json",
        ],
        &["--recording"],
    );
    // A configuration value out of range names the field.
    write("bad.toml", b"[boxes]\nperson_gap_m = 0.01\n");
    fails_in(
        d,
        &[
            "boxes", "--cloud", "kind.pcd", "--config", "bad.toml", "--out", "b.json",
        ],
        &["bad.toml: boxes.person_gap_m must be > boxes.voxel_m"],
    );
}
