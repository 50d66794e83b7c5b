//! `bodyseg project` on a tiny recording built here: the real Kinect v2 calibration of
//! `../shared/data/iai_kinect2/196605135147` (twice, the second camera 1 m to the side), a
//! depth image of a wall at 2 m with a box at 1.2 m in front of it, and a parsing image
//! holding the true projection of the box (torso) on a background wall. Then both modes,
//! and bad input: a depth image of the wrong size, an 8-bit depth PNG, a missing camera
//! folder.

use crate::common::{assert_ok, bodyseg, fails_in, stderr, tempdir};
use bodyseg_calib::{Pose, RgbdCamera, Rig, write_rig_toml};
use bodyseg_core::{Class, Label, LabelImage, LabeledCloud};
use bodyseg_io::{DepthImage, read_ply, write_depth_png, write_label_png};
use std::path::Path;

/// Frame stem of the recording.
const FRAME: &str = "000000";
/// Depth pixels with a measurement: columns and rows of the wall (the rest is 0, no
/// measurement). Kept inside the part of the depth view the colour camera sees, so the
/// naive projection labels every point.
const WALL_U: std::ops::Range<u32> = 60..452;
const WALL_V: std::ops::Range<u32> = 80..344;
/// Depth pixels of the box, in front of the wall.
const BOX_U: std::ops::Range<u32> = 216..296;
const BOX_V: std::ops::Range<u32> = 172..252;
/// Depths along the optical axis, metres.
const WALL_M: f64 = 2.0;
const BOX_M: f64 = 1.2;
/// World x offset of the second camera, metres.
const CAM1_X_M: f64 = 1.0;

/// The real iai_kinect2 calibration of one Kinect v2.
fn kinect2() -> RgbdCamera {
    bodyseg_calib::testing::kinect_v2_test_camera().expect("read the iai_kinect2 calibration")
}

/// The true depth (metres) of depth pixel (u, v), `None` without measurement.
fn truth_depth_m(u: u32, v: u32) -> Option<f64> {
    if BOX_U.contains(&u) && BOX_V.contains(&v) {
        Some(BOX_M)
    } else if WALL_U.contains(&u) && WALL_V.contains(&v) {
        Some(WALL_M)
    } else {
        None
    }
}

/// The true label of depth pixel `pixel`: torso on the box, background on the wall.
fn truth_label(width: u32, pixel: u32) -> Label {
    let (u, v) = (pixel % width, pixel / width);
    if BOX_U.contains(&u) && BOX_V.contains(&v) {
        Label::from(Class::Torso)
    } else {
        Label::BACKGROUND
    }
}

/// Raw depth image of the scene for `camera` (its scale and shift undone).
fn depth_image(camera: &RgbdCamera) -> DepthImage {
    let (w, h) = (camera.depth.width, camera.depth.height);
    let mut depth_mm = vec![0u16; w as usize * h as usize];
    for v in 0..h {
        for u in 0..w {
            if let Some(z) = truth_depth_m(u, v) {
                let raw = ((z - camera.depth_shift_mm / 1000.0) * camera.depth_scale).round();
                depth_mm[(v * w + u) as usize] = raw as u16;
            }
        }
    }
    DepthImage {
        width: w,
        height: h,
        depth_mm,
    }
}

/// Parsing image of the scene: background, and torso where the box's depth points
/// project into the colour image (5×5 splats: neighbouring depth samples land ~2.9 colour
/// pixels apart, so the box's image is closed).
fn parsing_image(camera: &RgbdCamera) -> LabelImage {
    let (cw, ch) = (camera.color.width as i64, camera.color.height as i64);
    let mut image = LabelImage::filled(cw as u32, ch as u32, Label::BACKGROUND);
    for v in BOX_V {
        for u in BOX_U {
            let ray = camera
                .depth
                .unproject(f64::from(u), f64::from(v))
                .expect("undistortion converges inside the image");
            let p_depth = ray.map(|c| c * BOX_M);
            let p_color = camera.color_from_depth.transform_point(p_depth);
            let [x, y] = camera
                .color
                .project(p_color)
                .expect("the box is in front of the colour camera");
            let (x, y) = (x.round() as i64, y.round() as i64);
            for yy in (y - 2).max(0)..=(y + 2).min(ch - 1) {
                for xx in (x - 2).max(0)..=(x + 2).min(cw - 1) {
                    image.labels[(yy * cw + xx) as usize] = Label::from(Class::Torso);
                }
            }
        }
    }
    image
}

/// Writes `rec/` in `dir` with one camera per name (the real calibration; camera i is
/// `i * CAM1_X_M` metres along world x), and its depth and parsing images of [`FRAME`].
fn write_recording(dir: &Path, names: &[&str]) -> Rig {
    let rec = dir.join("rec");
    let base = kinect2();
    let depth = depth_image(&base);
    let parsing = parsing_image(&base);
    let mut cameras = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let mut camera = base.clone();
        camera.name = (*name).to_string();
        camera.world_from_depth = Pose::from_rotation_translation(
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [i as f64 * CAM1_X_M, 0.0, 0.0],
        )
        .expect("identity rotation");
        for sub in ["depth", "parsing"] {
            std::fs::create_dir_all(rec.join(name).join(sub)).expect("create camera folder");
        }
        write_depth_png(&rec.join(name).join("depth/000000.png"), &depth).expect("write depth");
        write_label_png(&rec.join(name).join("parsing/000000.png"), &parsing)
            .expect("write parsing");
        cameras.push(camera);
    }
    let rig = Rig { cameras };
    write_rig_toml(&rig, &rec.join("rig.toml")).expect("write rig.toml");
    rig
}

/// Runs `bodyseg project` in `dir` on `rec/` and reads the cloud back.
fn project(dir: &Path, mode: &str, out: &str) -> LabeledCloud {
    let run = bodyseg(
        dir,
        &[
            "project",
            "--recording",
            "rec",
            "--frame",
            FRAME,
            "--mode",
            mode,
            "--out",
            out,
        ],
    );
    assert_ok(&run, "bodyseg project");
    let err = stderr(&run);
    assert!(
        err.lines()
            .any(|l| l.starts_with("project ") && l.contains(&format!("(mode {mode})"))),
        "{err}"
    );
    read_ply(&dir.join(out)).expect("the written cloud reads back")
}

/// Chebyshev distance (depth pixels) from (u, v) to the box's border.
fn distance_to_box_edge(u: u32, v: u32) -> u32 {
    let du = (i64::from(u) - i64::from(BOX_U.start))
        .abs()
        .min((i64::from(u) - i64::from(BOX_U.end - 1)).abs());
    let dv = (i64::from(v) - i64::from(BOX_V.start))
        .abs()
        .min((i64::from(v) - i64::from(BOX_V.end - 1)).abs());
    let inside_u = BOX_U.contains(&u);
    let inside_v = BOX_V.contains(&v);
    let d = match (inside_u, inside_v) {
        (true, true) => du.min(dv),
        (true, false) => dv,
        (false, true) => du,
        (false, false) => du.max(dv),
    };
    d as u32
}

#[test]
fn naive_and_dsa_label_every_depth_point_and_dsa_drops_the_occluded_ones() {
    let dir = tempdir();
    let d = dir.path();
    let rig = write_recording(d, &["cam0", "cam1"]);
    let width = rig.cameras[0].depth.width;
    // Every measured depth pixel, row-major: the points of one camera, in order.
    let pixels: Vec<u32> = (0..width * rig.cameras[0].depth.height)
        .filter(|&p| truth_depth_m(p % width, p / width).is_some())
        .collect();
    let n = pixels.len();
    assert_eq!(n, WALL_U.len() * WALL_V.len());

    let naive = project(d, "naive", "naive.ply");
    let dsa = project(d, "dsa", "dsa.ply");
    assert!(d.join("dsa.config.resolved.toml").exists());
    let mut wrong = [0usize; 2];
    for (k, cloud) in [&naive, &dsa].into_iter().enumerate() {
        assert_eq!(cloud.len(), 2 * n);
        for (i, o) in cloud.origins.iter().enumerate() {
            assert_eq!(
                (usize::from(o.camera), o.pixel),
                (i / n, pixels[i % n]),
                "origin of point {i}"
            );
        }
        // Same images, camera 1 is CAM1_X_M along world x: the same points shifted
        // (f32 positions of a few metres: 1e-5 m covers their rounding).
        for i in 0..n {
            let (a, b) = (cloud.positions_m[i], cloud.positions_m[n + i]);
            let shift = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            assert!(
                (shift[0] - CAM1_X_M as f32).abs() < 1e-5
                    && shift[1].abs() < 1e-5
                    && shift[2].abs() < 1e-5,
                "point {i}: {shift:?}"
            );
            // Depth along the optical axis = world z here (identity rotation); the raw
            // depth is rounded to whole millimetres, so within 0.5 mm (+ f32 rounding).
            let z_want = truth_depth_m(pixels[i] % width, pixels[i] / width).expect("measured");
            assert!(
                (f64::from(a[2]) - z_want).abs() < 5.1e-4,
                "point {i}: z {}",
                a[2]
            );
        }
        wrong[k] = cloud
            .labels
            .iter()
            .zip(&cloud.origins)
            .filter(|(l, o)| !l.is_unknown() && **l != truth_label(width, o.pixel))
            .count();
    }

    // Naive labels every point (all project into the colour image) but gives the box's
    // label to wall points hidden from the colour camera behind the box.
    assert_eq!(naive.labels.iter().filter(|l| l.is_unknown()).count(), 0);
    assert!(wrong[0] > 0, "naive has no wrong label");
    // DSA leaves some points unknown, all near the box's edge (the occluded strip is
    // ~6 depth pixels wide: 365 px · 0.052 m · (1/1.2 − 1/2) m⁻¹; 12 px of slack), and
    // labels fewer points wrongly.
    let unknown: Vec<u32> = dsa
        .labels
        .iter()
        .zip(&dsa.origins)
        .filter(|(l, _)| l.is_unknown())
        .map(|(_, o)| o.pixel)
        .collect();
    assert!(!unknown.is_empty(), "dsa left no point unknown");
    for &p in &unknown {
        let (u, v) = (p % width, p / width);
        assert!(
            distance_to_box_edge(u, v) <= 12,
            "unknown point far from the box: ({u}, {v})"
        );
    }
    assert!(
        unknown.len() < 2 * n / 20,
        "{} of {} unknown",
        unknown.len(),
        2 * n
    );
    assert!(
        wrong[1] < wrong[0],
        "wrong labels: dsa {} vs naive {}",
        wrong[1],
        wrong[0]
    );
}

/// Runs `bodyseg project` on `rec/` expecting exit 1, one `error:` line holding every
/// needle, and no file written.
fn assert_project_fails(d: &Path, needles: &[&str]) {
    let args = [
        "project",
        "--recording",
        "rec",
        "--frame",
        FRAME,
        "--out",
        "cloud.ply",
    ];
    fails_in(d, &args, needles);
}

#[test]
fn depth_image_of_the_wrong_size_is_named_with_both_sizes() {
    let dir = tempdir();
    let d = dir.path();
    write_recording(d, &["cam0"]);
    let small = DepthImage {
        width: 256,
        height: 212,
        depth_mm: vec![2000; 256 * 212],
    };
    write_depth_png(&d.join("rec/cam0/depth/000000.png"), &small).expect("write depth");
    assert_project_fails(
        d,
        &[
            "rec/cam0/depth/000000.png",
            "depth image is 256x212, rig.toml says 512x424",
        ],
    );
}

#[test]
fn eight_bit_depth_png_is_refused_naming_the_file() {
    let dir = tempdir();
    let d = dir.path();
    write_recording(d, &["cam0"]);
    let eight_bit = LabelImage::filled(512, 424, Label::BACKGROUND);
    write_label_png(&d.join("rec/cam0/depth/000000.png"), &eight_bit).expect("write");
    assert_project_fails(
        d,
        &["rec/cam0/depth/000000.png: depth PNG is 8-bit, expected 16-bit millimetres"],
    );
}

#[test]
fn missing_camera_folder_is_named() {
    let dir = tempdir();
    let d = dir.path();
    write_recording(d, &["cam0", "cam1"]);
    std::fs::remove_dir_all(d.join("rec/cam1")).expect("remove camera folder");
    assert_project_fails(d, &["camera cam1", "rec/cam1: camera folder is missing"]);
}
