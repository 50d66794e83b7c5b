//! OpenCV's rational distortion model (k1..k6, p1, p2) in projection and back-projection:
//! `project` against OpenCV's formula written out here (as `cv::projectPoints` computes
//! it), `project(unproject(p)) ≈ p` over whole images of a real Azure Kinect's sensors,
//! what happens outside the field of view, and rig.toml with 5 and 8 coefficients.

// The coefficients are typed digit for digit from the calibration file.
#![allow(clippy::excessive_precision)]

use std::path::Path;

use bodyseg_calib::{Distortion, Intrinsics, RgbdCamera, Rig, parse_rig_toml, rig_to_toml_string};

mod common;
use bodyseg_calib::testing::AZURE_COLOR_DISTORTION;
use common::{Rng, assert_round_trip, outer_corners, seed};

/// The depth sensor of Azure Kinect 001514394512 (`tests/fixtures/calib/azure_kinect/
/// pyk4a_calibration.json`) in NFOV unbinned mode, 640×576, as the SDK converts it:
/// `fx = fx_n · 1024`, `cx = cx_n · 1024 − 192 − 0.5`, likewise y with 180.
fn azure_depth_nfov() -> Intrinsics {
    Intrinsics::pinhole(
        640,
        576,
        0.4927808940410614 * 1024.0,
        0.49290284514427185 * 1024.0,
        0.5129697918891907 * 1024.0 - 192.0 - 0.5,
        0.5169235467910767 * 1024.0 - 180.0 - 0.5,
    )
    .with_distortion(bodyseg_calib::testing::AZURE_DEPTH_DISTORTION)
}

/// The same depth sensor in WFOV unbinned mode, 1024×1024: the 120° field of view.
fn azure_depth_wfov() -> Intrinsics {
    Intrinsics {
        width: 1024,
        height: 1024,
        cx: 0.5129697918891907 * 1024.0 - 0.5,
        cy: 0.5169235467910767 * 1024.0 - 0.5,
        ..azure_depth_nfov()
    }
}

/// The colour sensor of the same device at 3072P (4096×3072, the full sensor).
fn azure_color_3072p() -> Intrinsics {
    Intrinsics::pinhole(
        4096,
        3072,
        0.4779651165008545 * 4096.0,
        0.6374239325523376 * 3072.0,
        0.4998471438884735 * 4096.0 - 0.5,
        0.5066176056861877 * 3072.0 - 0.5,
    )
    .with_distortion(AZURE_COLOR_DISTORTION)
}

/// OpenCV's projection (`cvProjectPoints2Internal`, calib3d/src/calibration.cpp) of a
/// point with camera matrix `(fx, fy, cx, cy)` and distortion vector `k` of 8
/// (k1 k2 p1 p2 k3 k4 k5 k6), written out as OpenCV writes it.
fn opencv_project(i: &Intrinsics, k: &[f64; 8], p: [f64; 3]) -> [f64; 2] {
    let z = if p[2] != 0.0 { 1.0 / p[2] } else { 1.0 };
    let (x, y) = (p[0] * z, p[1] * z);
    let r2 = x * x + y * y;
    let r4 = r2 * r2;
    let r6 = r4 * r2;
    let a1 = 2.0 * x * y;
    let a2 = r2 + 2.0 * x * x;
    let a3 = r2 + 2.0 * y * y;
    let cdist = 1.0 + k[0] * r2 + k[1] * r4 + k[4] * r6;
    let icdist2 = 1.0 / (1.0 + k[5] * r2 + k[6] * r4 + k[7] * r6);
    let xd = x * cdist * icdist2 + k[2] * a1 + k[3] * a2;
    let yd = y * cdist * icdist2 + k[2] * a3 + k[3] * a1;
    [xd * i.fx + i.cx, yd * i.fy + i.cy]
}

#[test]
fn project_matches_opencv_formula_on_random_points() {
    let seed = seed();
    let mut rng = Rng::new(seed);
    for intr in [azure_depth_wfov(), azure_color_3072p()] {
        let Distortion::Rational(k) = intr.distortion else {
            panic!("rational fixtures");
        };
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            // Within ±60° of the axis (the WFOV depth sensor's field), 0.2–10 m.
            let z = rng.range_f64(0.2, 10.0);
            let p = [
                rng.range_f64(-1.7, 1.7) * z,
                rng.range_f64(-1.7, 1.7) * z,
                z,
            ];
            let ours = intr.project(p).expect("denominator > 0 within the field");
            let cv = opencv_project(&intr, &k, p);
            worst = worst
                .max((ours[0] - cv[0]).abs())
                .max((ours[1] - cv[1]).abs());
        }
        // Same formula, other operation order: a few ulps of coordinates up to ~1e4 px.
        assert!(
            worst < 1e-8,
            "{}x{}: {worst:e} px from OpenCV's formula (seed {seed}, BODYSEG_TEST_SEED to rerun)",
            intr.width,
            intr.height
        );
    }
}

#[test]
fn brown_conrady_as_rational_projects_bit_for_bit() {
    let bc = Intrinsics {
        distortion: Distortion::BrownConrady([0.0966, -0.283, 0.000159, -0.000508, 0.105]),
        ..azure_depth_nfov()
    };
    let rational = Intrinsics {
        distortion: Distortion::Rational(bc.distortion.rational_coefficients()),
        ..bc
    };
    let mut rng = Rng::new(seed());
    for _ in 0..1000 {
        let p = [
            rng.range_f64(-1.0, 1.0),
            rng.range_f64(-1.0, 1.0),
            rng.range_f64(0.5, 4.0),
        ];
        assert_eq!(bc.project(p), rational.project(p), "{p:?}");
    }
}

/// Largest |project(z · unproject(u, v)) − (u, v)| over every pixel centre and the outer
/// pixel borders, and the pixels within `max_radius` (normalised, undistorted: the
/// SDK's metric radius) that did not undistort. Pixels farther out must either undistort
/// exactly or give no ray.
fn worst_round_trip(intr: &Intrinsics, max_radius: f64) -> (f64, usize) {
    let border = outer_corners(intr);
    // Distorted radius of the metric radius (the distortion is radially monotonic there).
    let rim = intr
        .distort([max_radius, 0.0])
        .expect("the field of view maps")[0];
    let centres =
        (0..intr.height).flat_map(|v| (0..intr.width).map(move |u| [f64::from(u), f64::from(v)]));
    let (mut worst, mut failed) = (0.0f64, 0);
    for [u, v] in centres.chain(border) {
        let (xd, yd) = ((u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy);
        let Some(ray) = intr.unproject(u, v) else {
            if xd.hypot(yd) < rim {
                failed += 1;
            }
            continue;
        };
        let uv = intr.project(ray.map(|c| c * 2.5)).expect("in front");
        worst = worst.max((uv[0] - u).abs()).max((uv[1] - v).abs());
    }
    (worst, failed)
}

#[test]
fn round_trip_every_pixel_of_an_azure_kinect() {
    // The file's MetricRadius: 1.7399997711181641 for the depth sensor, 0 (the SDK then
    // uses 1.7) for the colour sensor. The WFOV image's corners lie beyond it, outside
    // the lens' image circle (the SDK marks them invalid): they give no ray here either.
    for (name, intr, metric_radius) in [
        ("depth NFOV 640x576", azure_depth_nfov(), 1.7399997711181641),
        (
            "depth WFOV 1024x1024",
            azure_depth_wfov(),
            1.7399997711181641,
        ),
        ("colour 4096x3072", azure_color_3072p(), 1.7),
    ] {
        let (worst, failed) = worst_round_trip(&intr, metric_radius);
        assert_eq!(
            failed, 0,
            "{name}: pixels without a ray inside the metric radius"
        );
        assert_round_trip(worst, name);
    }
}

#[test]
fn outside_the_field_of_view() {
    // The WFOV depth model keeps rising to r = 3 (71.6° off-axis, beyond the 120° field):
    // undistortion still inverts it there.
    let depth = azure_depth_wfov();
    for r in [1.8, 2.4, 3.0] {
        let p = [r * 0.6, r * 0.8, 1.0];
        let uv = depth.project(p).expect("denominator > 0");
        let ray = depth.unproject(uv[0], uv[1]).expect("monotonic model");
        assert!(
            (ray[0] - p[0]).abs() < 1e-9 && (ray[1] - p[1]).abs() < 1e-9,
            "r {r}: {ray:?}"
        );
    }
    // A rational model whose radial factor folds back, r_d = r (1 - 0.4 r²)/(1 + 0.1 r²):
    // beyond its peak no ray is returned (the pixel would have two), and where the
    // denominator is ≤ 0 neither direction maps.
    let folding = Intrinsics {
        distortion: Distortion::Rational([-0.4, 0.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0]),
        ..depth
    };
    let peak_r: f64 = (0..2000)
        .map(|i| f64::from(i) / 1000.0)
        .fold((0.0, 0.0), |(best_r, best_rd), r| {
            let rd = r * (1.0 - 0.4 * r * r) / (1.0 + 0.1 * r * r);
            if rd > best_rd {
                (r, rd)
            } else {
                (best_r, best_rd)
            }
        })
        .0;
    let beyond = [1.3 * peak_r, 0.0, 1.0];
    let uv = folding
        .project(beyond)
        .expect("maps, onto the falling branch");
    if let Some(ray) = folding.unproject(uv[0], uv[1]) {
        // Newton may only find the root on the rising branch, never the one given.
        assert!(ray[0] < peak_r, "{ray:?} beyond the fold at {peak_r}");
    }
    let pole = Intrinsics {
        distortion: Distortion::Rational([0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0]),
        ..depth
    };
    assert!(pole.project([1.2, 0.0, 1.0]).is_none(), "1 - r² < 0");
    assert!(pole.project([0.5, 0.0, 1.0]).is_some());
}

fn camera_with(depth: Intrinsics, color: Intrinsics) -> Rig {
    Rig {
        cameras: vec![RgbdCamera::new("k4a", depth, color)],
    }
}

#[test]
fn rig_toml_writes_5_or_8_coefficients_and_reads_both_back() {
    let bc = Intrinsics {
        distortion: Distortion::BrownConrady([0.1, -0.2, 1e-4, -2e-4, 0.05]),
        ..azure_depth_nfov()
    };
    let rig = camera_with(azure_depth_nfov(), bc);
    let text = rig_to_toml_string(&rig).expect("valid rig");
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("distortion = "))
        .collect();
    assert_eq!(lines.len(), 2, "{text}");
    let count = |l: &str| l.matches(',').count() + 1;
    assert_eq!(
        (count(lines[0]), count(lines[1])),
        (8, 5),
        "depth rational, colour Brown-Conrady:\n{text}"
    );
    let back = parse_rig_toml(&text, Path::new("rig.toml")).expect("reads back");
    assert_eq!(back, rig, "exact round trip, models kept");

    // Other lengths are refused, naming the camera, the field and the file.
    let six = text.replacen(
        lines[1],
        "distortion = [0.1, -0.2, 0.0001, -0.0002, 0.05, 0.0]",
        1,
    );
    let err = parse_rig_toml(&six, Path::new("calib/rig.toml")).expect_err("6 values");
    assert_eq!(
        err.to_string(),
        "camera k4a: color.distortion must have 5 numbers (k1 k2 p1 p2 k3) or 8 (rational \
         model: k1 k2 p1 p2 k3 k4 k5 k6), got 6 values: calib/rig.toml"
    );
    let text_value = text.replacen(lines[1], "distortion = \"none\"", 1);
    let err = parse_rig_toml(&text_value, Path::new("rig.toml")).expect_err("a string");
    assert!(
        err.to_string()
            .starts_with("camera k4a: color.distortion must be an array of 5 numbers"),
        "{err}"
    );
}
