//! The 3DPeople reader on the fixtures of `scripts/gen_3dpeople_fixture.py`
//! (`tests/fixtures/3dpeople`, `tests/fixtures/3dpeople_errors`): listing order, one point
//! per valid depth pixel, palette → class, pinhole back-projection, and an error naming
//! the file for each way a view can be bad.
//!
//! The expected values come from the script's `expected.json` (its own palette table and
//! validity rule, written independently of the reader).

use bodyseg_core::{Class, Label, LabeledCloud};
use bodyseg_io::{read_rgb_image, write_rgb_png};
use bodyseg_pipeline::{
    ThreeDPeopleCamera, ThreeDPeopleView, list_3dpeople_views, read_3dpeople_view,
};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Position tolerance, metres: f32 rounding of coordinates of a few metres (~3e-7 m),
/// with margin.
const TOL_M: f32 = 1e-5;

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures")
}

fn good_root() -> PathBuf {
    fixtures().join("3dpeople")
}

fn expected() -> Value {
    let text = std::fs::read_to_string(good_root().join("expected.json")).expect("expected.json");
    serde_json::from_str(&text).expect("expected.json is JSON")
}

/// The fixture's intrinsics (the dataset's, scaled to 64x48), as expected.json states them.
fn fixture_camera() -> ThreeDPeopleCamera {
    let k = &expected()["intrinsics"];
    let f = |key: &str| k[key].as_f64().expect("number");
    let camera = ThreeDPeopleCamera::pinhole(
        f("width") as u32,
        f("height") as u32,
        f("fx"),
        f("fy"),
        f("cx"),
        f("cy"),
    );
    assert_eq!(
        (camera.intrinsics.width, camera.intrinsics.height),
        (64, 48)
    );
    camera
}

fn view_named(root: &Path, stem: &str) -> ThreeDPeopleView {
    let views = list_3dpeople_views(root).expect("listing");
    views
        .into_iter()
        .find(|v| v.stem() == stem)
        .unwrap_or_else(|| panic!("no view {stem}"))
}

fn read_err(view: &ThreeDPeopleView, camera: &ThreeDPeopleCamera) -> String {
    match read_3dpeople_view(view, camera) {
        Ok(cloud) => panic!("{} read fine ({} points)", view.stem(), cloud.len()),
        Err(e) => format!("{e:#}"),
    }
}

fn assert_names(message: &str, path: &Path, what: &str) {
    assert!(
        message.contains(&path.display().to_string()),
        "error does not name {}: {message}",
        path.display()
    );
    assert!(
        message.contains(what),
        "error does not say '{what}': {message}"
    );
    assert!(!message.contains('\n'), "error is not one line: {message}");
}

#[test]
fn default_camera_is_the_datasets() {
    let c = ThreeDPeopleCamera::default();
    let k = c.intrinsics;
    assert_eq!((k.width, k.height), (640, 480));
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (700.0, 700.0, 320.0, 240.0));
    assert_eq!(k.distortion, bodyseg_calib::Distortion::NONE);
    assert_eq!(c.depth_scale_m, 1.0);
    assert!(!c.depth_is_ray_distance);
    c.validate().expect("defaults are valid");
}

#[test]
fn views_are_listed_sorted_with_their_files() {
    let root = good_root();
    let views = list_3dpeople_views(&root).expect("listing");
    let stems: Vec<String> = views.iter().map(ThreeDPeopleView::stem).collect();
    assert_eq!(
        stems,
        [
            "man01/01_01_walk/camera01/0001",
            "woman01/02_04_jump/camera01/0001",
            "woman01/02_04_jump/camera01/0002",
            "woman01/02_04_jump/camera02/0001",
            "woman01/02_04_jump/camera02/0002",
        ]
    );
    let mut sorted = stems.clone();
    sorted.sort();
    assert_eq!(stems, sorted, "stems sort in listing order");

    let v = &views[2];
    assert_eq!(
        (&*v.subject, &*v.sequence, &*v.camera, &*v.frame),
        ("woman01", "02_04_jump", "camera01", "0002")
    );
    // The real layout: colour images in an outfit folder inside the camera folder.
    assert_eq!(
        v.rgb_path,
        root.join("rgb/woman01/02_04_jump/camera01/wpskin01_bottom01_top01_background01/0002.jpg")
    );
    assert_eq!(
        v.depth_path,
        root.join("depth_mat/woman01/02_04_jump/camera01/depth.mat")
    );
    assert_eq!(
        v.segmentation_path,
        root.join("segmentation_body/woman01/02_04_jump/camera01/0002.png")
    );
    // Images directly in the camera folder are found too.
    assert_eq!(
        views[3].rgb_path,
        root.join("rgb/woman01/02_04_jump/camera02/0001.jpg")
    );
    // The view without depth is still listed; reading it is the error.
    assert!(!views[0].depth_path.exists());
}

/// Checks one cloud against expected.json's entry and the pinhole model.
fn check_view(
    view: &ThreeDPeopleView,
    cloud: &LabeledCloud,
    want: &Value,
    camera: &ThreeDPeopleCamera,
) {
    let stem = view.stem();
    cloud.validate().expect("consistent cloud");
    assert_eq!(
        cloud.len() as u64,
        want["valid_points"].as_u64().expect("count"),
        "{stem}: one point per valid depth pixel"
    );
    for (id, count) in want["label_counts"].as_object().expect("counts") {
        let id: u8 = id.parse().expect("label id");
        let got = cloud.labels.iter().filter(|l| l.id() == id).count() as u64;
        assert_eq!(got, count.as_u64().expect("count"), "{stem}: label {id}");
    }
    // Row-major pixel order, camera 0.
    assert!(cloud.origins.iter().all(|o| o.camera == 0));
    assert!(cloud.origins.windows(2).all(|w| w[0].pixel < w[1].pixel));
    // Colours are the colour image's pixels.
    let color = read_rgb_image(&view.rgb_path).expect("colour image");
    let colors = cloud.colors.as_ref().expect("colours");
    for (origin, c) in cloud.origins.iter().zip(colors) {
        let i = 3 * origin.pixel as usize;
        assert_eq!(
            *c,
            [color.rgb[i], color.rgb[i + 1], color.rgb[i + 2]],
            "{stem}"
        );
    }
    let samples = want["samples"].as_array().expect("samples");
    assert!(samples.len() >= 10, "{stem}: samples cover the parts");
    for s in samples {
        let (u, v) = (s["u"].as_u64().expect("u"), s["v"].as_u64().expect("v"));
        let z = s["depth_m"].as_f64().expect("depth");
        let pixel = (v * u64::from(camera.intrinsics.width) + u) as u32;
        let i = cloud
            .origins
            .iter()
            .position(|o| o.pixel == pixel)
            .unwrap_or_else(|| panic!("{stem}: no point at pixel ({u}, {v})"));
        assert_eq!(
            cloud.labels[i].id() as u64,
            s["label"].as_u64().expect("label"),
            "{stem}: label at ({u}, {v})"
        );
        // Pinhole, camera (x right, y down, z forward) → world (x, z, -y).
        let x = (u as f64 - camera.intrinsics.cx) / camera.intrinsics.fx * z;
        let y = (v as f64 - camera.intrinsics.cy) / camera.intrinsics.fy * z;
        let want_p = [x as f32, z as f32, -y as f32];
        let got = cloud.positions_m[i];
        for a in 0..3 {
            assert!(
                (got[a] - want_p[a]).abs() < TOL_M,
                "{stem}: pixel ({u}, {v}) at {got:?}, expected {want_p:?}"
            );
        }
    }
}

#[test]
fn good_views_match_the_expected_points_labels_and_positions() {
    let camera = fixture_camera();
    let expected = expected();
    let views = expected["views"].as_object().expect("views");
    assert_eq!(views.len(), 4);
    for (stem, want) in views {
        let view = view_named(&good_root(), stem);
        let cloud = read_3dpeople_view(&view, &camera).unwrap_or_else(|e| panic!("{e:#}"));
        check_view(&view, &cloud, want, &camera);
    }
}

#[test]
fn every_palette_class_and_the_edge_labels_occur() {
    let camera = fixture_camera();
    let view = view_named(&good_root(), "woman01/02_04_jump/camera01/0001");
    let cloud = read_3dpeople_view(&view, &camera).expect("reads");
    for class in Class::ALL {
        assert!(
            cloud.labels.contains(&Label::from(class)),
            "no {class} point"
        );
    }
    // The 50/50 head/torso blend at (31, 8) is unknown; the torso pixel 5/4/3 levels off
    // at (30, 12) is torso.
    let label_at = |u: u32, v: u32| {
        let i = cloud
            .origins
            .iter()
            .position(|o| o.pixel == v * camera.intrinsics.width + u)
            .expect("a point there");
        cloud.labels[i]
    };
    assert_eq!(label_at(31, 8), Label::UNKNOWN);
    assert_eq!(label_at(30, 12), Label::from(Class::Torso));
    // With no tolerance the off-palette torso pixel is unknown too.
    let strict = ThreeDPeopleCamera {
        palette_tolerance: 0,
        ..camera
    };
    let strict_cloud = read_3dpeople_view(&view, &strict).expect("reads");
    let unknown = |c: &LabeledCloud| c.labels.iter().filter(|l| l.is_unknown()).count();
    assert_eq!(unknown(&strict_cloud), unknown(&cloud) + 1);
}

#[test]
fn ray_distance_depth_puts_points_at_that_distance() {
    let camera = ThreeDPeopleCamera {
        depth_is_ray_distance: true,
        ..fixture_camera()
    };
    let expected = expected();
    let stem = "woman01/02_04_jump/camera02/0001";
    let view = view_named(&good_root(), stem);
    let cloud = read_3dpeople_view(&view, &camera).expect("reads");
    for s in expected["views"][stem]["samples"]
        .as_array()
        .expect("samples")
    {
        let pixel = (s["v"].as_u64().expect("v") * 64 + s["u"].as_u64().expect("u")) as u32;
        let i = cloud
            .origins
            .iter()
            .position(|o| o.pixel == pixel)
            .expect("point");
        let p = cloud.positions_m[i];
        let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let want = s["depth_m"].as_f64().expect("depth") as f32;
        assert!((norm - want).abs() < TOL_M, "{norm} vs {want}");
    }
}

#[test]
fn the_broken_view_of_the_good_set_names_its_missing_depth_file() {
    let view = view_named(&good_root(), "man01/01_01_walk/camera01/0001");
    let message = read_err(&view, &fixture_camera());
    assert_names(&message, &view.depth_path, "cannot read");
}

#[test]
fn bad_depth_contents_name_the_file_and_what_is_wrong() {
    let root = fixtures().join("3dpeople_errors");
    let camera = fixture_camera();
    let nan = view_named(&root, "woman02/03_01_run/camera01/0001");
    assert_names(
        &read_err(&nan, &camera),
        &nan.depth_path,
        "depth_0001 pixel (u 30, v 10) is NaN",
    );
    let missing = view_named(&root, "woman02/03_01_run/camera01/0002");
    let message = read_err(&missing, &camera);
    assert_names(
        &message,
        &missing.depth_path,
        "no depth variable for frame 0002",
    );
    assert!(message.contains("depth_0001, depth_0003"), "{message}");
    let small = view_named(&root, "woman02/03_01_run/camera02/0001");
    assert_names(
        &read_err(&small, &camera),
        &small.depth_path,
        "depth_0001 is 32x24, the camera is 64x48",
    );
}

/// A copy of the good camera02 frame 0001 view in a temporary folder, to break.
fn scratch_view(dir: &Path) -> ThreeDPeopleView {
    let good = view_named(&good_root(), "woman01/02_04_jump/camera02/0001");
    let view = ThreeDPeopleView {
        rgb_path: dir.join("0001.jpg"),
        depth_path: dir.join("depth.mat"),
        segmentation_path: dir.join("0001.png"),
        ..good.clone()
    };
    for (from, to) in [
        (&good.rgb_path, &view.rgb_path),
        (&good.depth_path, &view.depth_path),
        (&good.segmentation_path, &view.segmentation_path),
    ] {
        std::fs::copy(from, to).expect("copy");
    }
    view
}

#[test]
fn broken_files_name_the_file() {
    let camera = fixture_camera();
    let dir = tempfile::tempdir().expect("temp dir");
    let view = scratch_view(dir.path());
    read_3dpeople_view(&view, &camera).expect("the copy reads");

    std::fs::remove_file(&view.segmentation_path).expect("remove");
    assert_names(
        &read_err(&view, &camera),
        &view.segmentation_path,
        "cannot read",
    );

    write_rgb_png(&view.segmentation_path, 10, 10, &[153; 300]).expect("write");
    assert_names(
        &read_err(&view, &camera),
        &view.segmentation_path,
        "segmentation is 10x10, the camera is 64x48",
    );

    let view = scratch_view(dir.path());
    std::fs::write(&view.rgb_path, b"not a jpeg").expect("write");
    assert_names(&read_err(&view, &camera), &view.rgb_path, "cannot decode");

    let view = scratch_view(dir.path());
    std::fs::write(&view.depth_path, [7u8; 300]).expect("write");
    assert_names(&read_err(&view, &camera), &view.depth_path, "MAT file");

    // A MAT v7.3 (HDF5) file is named as such.
    let mut v73 = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".to_vec();
    v73.resize(512, b' ');
    std::fs::write(&view.depth_path, &v73).expect("write");
    assert_names(&read_err(&view, &camera), &view.depth_path, "v7.3");

    // A truncated compressed file.
    let good = view_named(&good_root(), "woman01/02_04_jump/camera01/0001");
    let bytes = std::fs::read(&good.depth_path).expect("read");
    std::fs::write(&view.depth_path, &bytes[..bytes.len() / 2]).expect("write");
    let cut = ThreeDPeopleView {
        depth_path: view.depth_path.clone(),
        ..good
    };
    assert_names(&read_err(&cut, &camera), &view.depth_path, "MAT file");

    // Images of the wrong size for the camera.
    let wrong = ThreeDPeopleCamera::default();
    let view = scratch_view(dir.path());
    assert_names(
        &read_err(&view, &wrong),
        &view.depth_path,
        "is 64x48, the camera is 640x480",
    );
}

#[test]
fn listing_errors_name_the_folder() {
    let dir = tempfile::tempdir().expect("temp dir");
    let message = format!(
        "{:#}",
        list_3dpeople_views(dir.path()).expect_err("no rgb/")
    );
    assert_names(&message, &dir.path().join("rgb"), "folder is missing");

    // Two outfit folders holding the same frame.
    let camera_dir = dir.path().join("rgb/woman01/seq/camera01");
    for outfit in ["a", "b"] {
        std::fs::create_dir_all(camera_dir.join(outfit)).expect("mkdir");
        std::fs::write(camera_dir.join(outfit).join("0001.jpg"), b"x").expect("write");
    }
    let message = format!(
        "{:#}",
        list_3dpeople_views(dir.path()).expect_err("duplicate")
    );
    assert_names(&message, &camera_dir, "two colour images of frame 0001");
}
