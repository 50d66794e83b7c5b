//! Clouds from other tools (issue 28): PCL's real organised Kinect cloud of five people
//! (`tests/fixtures/real/pcl/five_people.pcd`, camera optical frame: y down, z forward)
//! through `bodyseg boxes --mode geometry` with no option (its floor found) and through
//! `bodyseg import cloud` + `bodyseg run`; the same points without labels (PLY), with
//! PCL's segment ids as labels, in millimetres and unorganised: a note, a refusal naming
//! the fix, a warning naming the unit, an error naming HEIGHT; and the view above the
//! floor only: warnings that no floor and no person are found, with the likely cause.

use crate::common::{assert_ok, bodyseg, bodyseg_line, files_in, stderr, tempdir};
use bodyseg_core::PersonBoxes;
use bodyseg_core::math::Vec3;
use bodyseg_io::{FileLabels, read_boxes, read_cloud_file};
use bodyseg_people::match_boxes;
use std::path::{Path, PathBuf};

fn five_people() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/real/pcl/five_people.pcd")
}

/// The five heads in the cloud's 640x480 colour image, (column, row), measured once by
/// hand on `cam0/color/000000.png` of `bodyseg import cloud five_people.pcd` (the middle
/// of each head, left to right: green shirt, blue top, white shirt, grey shirt, dark
/// shirt); independent of the box finder.
const HEADS_PX: [(u32, u32); 5] = [(85, 95), (180, 130), (345, 125), (418, 125), (545, 85)];

/// The cloud's points (camera frame) and, per head, the valid point nearest its pixel
/// (within 6 px: a head pixel can fall on a hole of the depth).
fn cloud_and_heads() -> (Vec<Vec3>, Vec<Vec3>) {
    let file = read_cloud_file(&five_people()).expect("five_people.pcd reads");
    let grid = file.grid.as_ref().expect("organised");
    assert_eq!((grid.width, grid.height), (640, 480));
    assert_eq!(file.labels, FileLabels::Absent);
    let cloud = file.cloud;
    let heads = HEADS_PX
        .iter()
        .map(|&(u, v)| {
            let near = cloud
                .origins
                .iter()
                .zip(&cloud.positions_m)
                .filter_map(|(o, &p)| {
                    let (pu, pv) = (o.pixel % 640, o.pixel / 640);
                    let d = pu.abs_diff(u).max(pv.abs_diff(v));
                    (d <= 6).then_some((d, p))
                })
                .min_by_key(|&(d, _)| d);
            near.unwrap_or_else(|| panic!("no depth near head pixel ({u}, {v})"))
                .1
        })
        .collect();
    (cloud.positions_m, heads)
}

/// Each box holds exactly one head and each head is in exactly one box (heads mapped
/// into the boxes' frame by `world_from_cloud`).
fn assert_one_head_per_box(boxes: &PersonBoxes, heads_cloud: &[Vec3], what: &str) {
    let t = boxes
        .world_from_cloud
        .unwrap_or_else(|| panic!("{what}: a camera-frame cloud's boxes record world_from_cloud"));
    let heads: Vec<Vec3> = heads_cloud.iter().map(|&h| t.apply(h)).collect();
    for (k, b) in boxes.boxes.iter().enumerate() {
        let inside = heads.iter().filter(|&&h| b.contains(h)).count();
        assert_eq!(
            inside, 1,
            "{what}: box {k} holds {inside} heads: {b:?}\nheads {heads:?}"
        );
    }
    for (k, &h) in heads.iter().enumerate() {
        let holding = boxes.boxes.iter().filter(|b| b.contains(h)).count();
        assert_eq!(
            holding, 1,
            "{what}: head {k} at {h:?} is in {holding} boxes"
        );
        // Heads are 1.5–2 m above the floor found (z up, floor at z = 0).
        assert!(
            (1.4..2.1).contains(&h[2]),
            "{what}: head {k} at height {}",
            h[2]
        );
    }
}

fn boxes_geometry(dir: &Path, cloud: &Path, extra: &[&str]) -> std::process::Output {
    let cloud = cloud.display().to_string();
    let mut args = vec![
        "boxes",
        "--cloud",
        &cloud,
        "--mode",
        "geometry",
        "--out",
        "boxes.json",
    ];
    args.extend_from_slice(extra);
    bodyseg(dir, &args)
}

/// Asserts that `boxes --mode labels` on `cloud` in `dir` fails with `why` and names the
/// fix (`--mode geometry`), writing nothing.
fn labels_mode_is_refused(dir: &Path, cloud: &str, why: &str) {
    let line = format!("boxes --cloud {cloud} --mode labels --out l.json");
    let out = bodyseg_line(dir, &line);
    assert!(!out.status.success(), "{line}");
    let err = stderr(&out);
    assert!(
        err.contains(why) && err.contains("--mode geometry"),
        "{err}"
    );
    assert!(!dir.join("l.json").exists(), "{line}");
}

#[test]
fn pcls_five_people_in_the_camera_frame_get_five_boxes_then_import_and_run_too() {
    let dir = tempdir();
    let d = dir.path();
    let (_, heads) = cloud_and_heads();

    // No option: the floor is found, the boxes are in its frame.
    let out = boxes_geometry(d, &five_people(), &["--preview", "top.png"]);
    assert_ok(&out, "boxes --mode geometry");
    let err = stderr(&out);
    assert!(err.contains("5 person boxes (mode geometry)"), "{err}");
    assert!(!err.contains("warning:"), "no warning expected:\n{err}");
    let boxes = read_boxes(&d.join("boxes.json")).expect("boxes written");
    assert_eq!(boxes.boxes.len(), 5, "{boxes:?}");
    assert_one_head_per_box(&boxes, &heads, "boxes --cloud");
    assert!(d.join("top.png").is_file());

    // The floor given as PCL's ground coefficients (typed by hand: the floor 1.28 m below
    // the camera, which looks down by ~5 degrees) or the camera's up axis gives the same
    // people.
    for hint in [["--ground", "0,-1,-0.08,1.28"], ["--up", "-y"]] {
        let out = boxes_geometry(d, &five_people(), &hint);
        assert_ok(&out, &format!("boxes {hint:?}"));
        let given = read_boxes(&d.join("boxes.json")).expect("boxes written");
        assert_one_head_per_box(&given, &heads, &format!("{hint:?}"));
    }

    // import cloud: a one-camera recording whose world frame is the floor's.
    let out = bodyseg(
        d,
        &[
            "import",
            "cloud",
            &five_people().display().to_string(),
            "--out",
            "rec",
        ],
    );
    assert_ok(&out, "import cloud");
    let err = stderr(&out);
    assert!(
        err.contains("fx 525.00 fy 525.00 cx 319.50 cy 239.50 px"),
        "{err}"
    );
    assert!(err.contains("RMS residual 0.0000 px"), "{err}");
    assert_eq!(
        files_in(&d.join("rec/cam0/depth")),
        vec!["000000.png".to_string()]
    );
    assert!(d.join("rec/cam0/color/000000.png").is_file());
    assert!(d.join("rec/rig.toml").is_file());

    // run on it, geometry-mode boxes: every person gets a box, the same boxes.
    let out = bodyseg_line(
        d,
        "run --recording rec --out run1 --set boxes.mode=geometry",
    );
    assert_ok(&out, "run on the imported recording");
    let run_boxes = read_boxes(&d.join("run1/boxes/000000.json")).expect("run's boxes");
    assert_eq!(run_boxes.boxes.len(), 5, "{run_boxes:?}");
    let m = match_boxes(&boxes.boxes, &run_boxes.boxes);
    assert!(m.is_good(), "{m:?}");
    assert!(d.join("run1/clouds/000000.ply").is_file());
}

/// Writes `points` as a binary PCD: `height` rows (1: unorganised), x y z and, when
/// given, a `label` field (U 4).
fn write_pcd(path: &Path, points: &[Vec3], labels: Option<&[u32]>, height: usize) {
    let fields = if labels.is_some() {
        "x y z label"
    } else {
        "x y z"
    };
    let k = if labels.is_some() { 4 } else { 3 };
    let mut bytes = format!(
        "VERSION 0.7\nFIELDS {fields}\nSIZE{}\nTYPE F F F{}\nCOUNT{}\nWIDTH {}\nHEIGHT \
         {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA binary\n",
        " 4".repeat(k),
        if labels.is_some() { " U" } else { "" },
        " 1".repeat(k),
        points.len() / height,
        points.len()
    )
    .into_bytes();
    for (i, p) in points.iter().enumerate() {
        for v in p {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        if let Some(labels) = labels {
            bytes.extend_from_slice(&labels[i].to_le_bytes());
        }
    }
    std::fs::write(path, bytes).expect("write pcd");
}

/// Writes `points` as a binary PLY with x y z only (no label), as trimesh or a scanner.
fn write_bare_ply(path: &Path, points: &[Vec3]) {
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\ncomment no labels\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    )
    .into_bytes();
    for p in points {
        for v in p {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).expect("write ply");
}

#[test]
fn unlabelled_foreign_labelled_millimetre_and_unorganised_clouds() {
    let dir = tempdir();
    let d = dir.path();
    let (points, _) = cloud_and_heads();

    // A PLY without `label`: geometry mode finds the five; labels mode names the fix.
    let ply = d.join("bare.ply");
    write_bare_ply(&ply, &points);
    let out = boxes_geometry(d, &ply, &[]);
    assert_ok(&out, "geometry mode on a PLY without labels");
    assert!(stderr(&out).contains("5 person boxes"), "{}", stderr(&out));
    labels_mode_is_refused(d, "bare.ply", "no 'label' field");

    // PCL's segment ids (PointXYZRGBL): ignored with a note in geometry mode, refused in
    // labels mode with the fix named.
    let segments: Vec<u32> = (0..points.len() as u32).map(|i| 40 + i % 7).collect();
    let pcd = d.join("segments.pcd");
    write_pcd(&pcd, &points, Some(&segments), 1);
    let out = boxes_geometry(d, &pcd, &[]);
    assert_ok(&out, "geometry mode with segment ids");
    let err = stderr(&out);
    assert!(err.contains("5 person boxes"), "{err}");
    assert!(
        err.contains("note:") && err.contains("not bodyseg's class ids"),
        "{err}"
    );
    labels_mode_is_refused(d, "segments.pcd", "label is 40, not a bodyseg class id");

    // The same cloud in millimetres: a warning that names the unit.
    let mm: Vec<Vec3> = points.iter().map(|p| p.map(|v| v * 1000.0)).collect();
    let pcd = d.join("mm.pcd");
    write_pcd(&pcd, &mm, None, 1);
    let out = boxes_geometry(d, &pcd, &[]);
    assert_ok(&out, "geometry mode in millimetres");
    let err = stderr(&out);
    assert!(
        err.contains("warning:") && err.contains("millimetres"),
        "{err}"
    );

    // The camera's view above the floor (rows 0..260 of the grid: heads and trunks,
    // walls, no floor): warnings that no floor and no person are found, naming that.
    let file = read_cloud_file(&five_people()).expect("five_people.pcd reads");
    let upper: Vec<Vec3> = file
        .cloud
        .positions_m
        .iter()
        .zip(&file.cloud.origins)
        .filter(|(_, o)| o.pixel / 640 < 260)
        .map(|(&p, _)| p)
        .collect();
    write_pcd(&d.join("upper.pcd"), &upper, None, 1);
    let out = boxes_geometry(d, &d.join("upper.pcd"), &[]);
    assert_ok(&out, "geometry mode without a floor in view");
    let err = stderr(&out);
    assert!(err.contains("no floor found"), "{err}");
    assert!(err.contains("no person found"), "{err}");
    assert!(err.contains("a camera's view with no floor in it"), "{err}");

    // An unorganised PCD cannot be imported: one error naming HEIGHT, nothing written.
    let flat = d.join("flat.pcd");
    write_pcd(&flat, &points, None, 1);
    let out = bodyseg(d, &["import", "cloud", "flat.pcd", "--out", "rec"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("flat.pcd") && err.contains("HEIGHT"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!d.join("rec").exists());
    assert_eq!(
        files_in(d).iter().filter(|f| f.contains("rec")).count(),
        0,
        "nothing half-written: {:?}",
        files_in(d)
    );
}
