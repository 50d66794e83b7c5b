//! `bodyseg synth`: recordings the readers load, byte-identical per seed, clear errors.

use crate::common::{assert_ok, bodyseg, bodyseg_line, stderr, tree};
use bodyseg_calib::read_rig_toml;
use bodyseg_io::{read_boxes, read_depth_png, read_label_png, read_ply};
use std::collections::BTreeMap;
use std::path::Path;

/// Every file under `root` with its bytes, keyed by relative path.
fn files(root: &Path) -> BTreeMap<String, Vec<u8>> {
    tree(root)
        .into_iter()
        .map(|rel| {
            let bytes = std::fs::read(root.join(&rel)).expect("read");
            (rel, bytes)
        })
        .collect()
}

#[test]
fn handover_recording_loads_and_the_seed_fixes_every_byte() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let synth = |seed: &str, out: &str| {
        bodyseg(
            d,
            &[
                "synth", "--preset", "handover", "--frames", "20", "--seed", seed, "--out", out,
            ],
        )
    };
    let out = synth("1", "rec");
    assert_ok(&out, "synth");
    assert!(stderr(&out).contains("20 frames"), "{}", stderr(&out));
    let rec = d.join("rec");

    // The readers load it: rig, depth, parsing, truth, boxes.
    let rig = read_rig_toml(&rec.join("rig.toml")).expect("rig.toml");
    assert_eq!(rig.cameras.len(), 3);
    for camera in &rig.cameras {
        let depth =
            read_depth_png(&rec.join(&camera.name).join("depth/000019.png")).expect("depth");
        assert_eq!((depth.width, depth.height), (512, 424));
        let parsing =
            read_label_png(&rec.join(&camera.name).join("parsing/000019.png")).expect("parsing");
        assert_eq!((parsing.width, parsing.height), (960, 540));
        for kind in ["color", "labels", "depth_labels", "depth_person"] {
            assert!(
                rec.join(&camera.name)
                    .join(kind)
                    .join("000000.png")
                    .is_file(),
                "{kind}"
            );
        }
    }
    let boxes = read_boxes(&rec.join("boxes/000007.json")).expect("boxes");
    assert_eq!(boxes.boxes.len(), 2);
    assert!(rec.join("preview/000019.png").is_file());
    assert!(rec.join("scene.toml").is_file());

    // …and the pipeline projects a frame of it.
    let out = bodyseg_line(d, "project --recording rec --frame 000003 --out p.ply");
    assert_ok(&out, "project");
    let cloud = read_ply(&d.join("p.ply")).expect("projected cloud");
    assert!(cloud.len() > 100_000, "{}", cloud.len());

    // Same seed, same bytes; another seed, other people.
    let first = files(&rec);
    assert_ok(&synth("1", "again"), "synth again");
    assert_eq!(files(&d.join("again")), first);
    assert_ok(&synth("2", "other"), "synth other seed");
    let other = files(&d.join("other"));
    assert_ne!(other["boxes/000000.json"], first["boxes/000000.json"]);
    assert_ne!(
        other["cam0/depth/000000.png"],
        first["cam0/depth/000000.png"]
    );
}

#[test]
fn existing_output_is_kept_without_force_and_bad_scenes_name_the_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::create_dir(d.join("rec")).expect("mkdir");
    std::fs::write(d.join("rec/keep.txt"), "mine").expect("write");
    let out = bodyseg(d, &["synth", "--frames", "1", "--out", "rec"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("already exists"), "{}", stderr(&out));
    assert_eq!(
        std::fs::read_to_string(d.join("rec/keep.txt")).expect("kept"),
        "mine"
    );

    for (scene, field) in [
        ("[people]\ncount = 2\nbogus = 1\n", "bogus"),
        ("[scene]\nroom_half_m = -3.0\n", "scene.room_half_m"),
        ("[rig]\ncameras = 0\n", "rig.cameras"),
    ] {
        std::fs::write(d.join("bad.toml"), scene).expect("write");
        let out = bodyseg(
            d,
            &[
                "synth", "--scene", "bad.toml", "--frames", "1", "--out", "x",
            ],
        );
        assert!(!out.status.success(), "{scene}");
        let err = stderr(&out);
        assert!(
            err.contains(field) && err.contains("bad.toml"),
            "{scene}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "one error line: {err}");
        assert!(!d.join("x").exists(), "no output left behind");
    }
    let out = bodyseg(d, &["synth", "--set", "rig.cameras=0", "--out", "x"]);
    assert!(stderr(&out).contains("rig.cameras"), "{}", stderr(&out));
    let out = bodyseg(d, &["synth", "--preset", "nope", "--out", "x"]);
    assert!(stderr(&out).contains("robot_cell"), "{}", stderr(&out));
    // No staging folder is left behind by the failures.
    let leftovers: Vec<_> = std::fs::read_dir(d)
        .expect("read_dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}
