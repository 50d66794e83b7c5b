//! Calibration through OpenCV (feature `opencv`): exact synthetic corners give back the
//! intrinsics and the stereo pose they were made with; a rendered board's corners are found
//! to sub-pixel accuracy in canonical order; FileStorage written by OpenCV is read by the
//! pure-Rust iai_kinect2 reader and the other way round.
#![cfg(feature = "opencv")]

mod common;

use bodyseg_calib::{
    Board, BoardZ, Distortion, GrayImage, Intrinsics, KINECT2_DEPTH_SIZE, Pose, RgbdCamera,
    board_pose, calibrate_intrinsics, calibrate_stereo, find_board_corners, read_iai_kinect2,
    read_opencv_intrinsics, write_iai_kinect2, write_opencv_intrinsics,
};

fn kinect_ir() -> Intrinsics {
    Intrinsics::pinhole(512, 424, 366.9, 364.8, 243.0, 207.7).with_distortion(
        Distortion::BrownConrady([0.0966, -0.283, 0.000159, -0.000508, 0.105]),
    )
}

fn color() -> Intrinsics {
    Intrinsics::pinhole(960, 540, 530.0, 527.0, 477.2, 261.6).with_distortion(
        Distortion::BrownConrady([0.056, -0.074, 0.0014, -0.0017, 0.024]),
    )
}

/// Rotation about x, then y, then z (radians).
fn rotation(ax: f64, ay: f64, az: f64) -> [[f64; 3]; 3] {
    let (sx, cx) = ax.sin_cos();
    let (sy, cy) = ay.sin_cos();
    let (sz, cz) = az.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        m
    };
    mul(mul(rx, ry), rz)
}

/// Board poses in front of the sensor, tilted every way.
fn board_poses() -> Vec<Pose> {
    let mut poses = Vec::new();
    for k in 0..12 {
        let a = f64::from(k) * 0.53;
        let r = rotation(0.5 * a.sin(), 0.5 * (1.7 * a).cos(), 0.2 * (0.7 * a).sin());
        let t = [
            -0.16 + 0.03 * a.cos(),
            -0.1 + 0.03 * a.sin(),
            0.9 + 0.05 * f64::from(k % 4),
        ];
        poses.push(Pose::from_rotation_translation(r, t).expect("pose"));
    }
    poses
}

fn project(board: &Board, intrinsics: &Intrinsics, sensor_from_board: &Pose) -> Vec<[f64; 2]> {
    board
        .object_points()
        .iter()
        .map(|p| {
            intrinsics
                .project(sensor_from_board.transform_point(*p))
                .expect("in front")
        })
        .collect()
}

#[test]
fn exact_corners_give_back_the_intrinsics_and_the_stereo_pose() {
    let board = Board::new([9, 6], 0.04).expect("board");
    let ir = kinect_ir();
    let views: Vec<Vec<[f64; 2]>> = board_poses()
        .iter()
        .map(|p| project(&board, &ir, p))
        .collect();
    let fit = calibrate_intrinsics(&board, &views, ir.width, ir.height).expect("fit");
    // Corners are exact up to f32 rounding (OpenCV's Point2f, ~1e-5 px): the fit lands
    // within 0.01 % and the residual is far below a hundredth of a pixel.
    for (got, want) in [
        (fit.intrinsics.fx, ir.fx),
        (fit.intrinsics.fy, ir.fy),
        (fit.intrinsics.cx, ir.cx),
        (fit.intrinsics.cy, ir.cy),
    ] {
        assert!((got - want).abs() / want < 1e-4, "{got} vs {want}");
    }
    assert!(fit.rms_px < 1e-3, "rms {}", fit.rms_px);
    assert_eq!(fit.view_rms_px.len(), views.len());

    let color_from_depth =
        Pose::from_rotation_translation(rotation(0.002, -0.01, 0.017), [-0.052, -0.0005, 0.0009])
            .expect("pose");
    let c = color();
    let pairs: Vec<_> = board_poses()
        .iter()
        .map(|p| {
            (
                project(&board, &ir, p),
                project(&board, &c, &color_from_depth.compose(p)),
            )
        })
        .collect();
    for refine in [false, true] {
        let stereo = calibrate_stereo(&board, &ir, &c, &pairs, refine).expect("stereo");
        let (g, w) = (
            stereo.second_from_first.translation_m(),
            color_from_depth.translation_m(),
        );
        for k in 0..3 {
            // Micrometres: f32 corners only.
            assert!(
                (g[k] - w[k]).abs() < 1e-5,
                "refine {refine}: {g:?} vs {w:?}"
            );
        }
        assert!(stereo.rms_px < 1e-3);
    }

    let (pose, rms) = board_pose(&board, &ir, &views[3]).expect("pnp");
    let (g, w) = (pose.translation_m(), board_poses()[3].translation_m());
    assert!((0..3).all(|k| (g[k] - w[k]).abs() < 1e-5), "{g:?} vs {w:?}");
    assert!(rms < 1e-3);
}

#[test]
fn too_few_views_or_wrong_corner_counts_are_errors() {
    let board = Board::new([9, 6], 0.04).expect("board");
    let ir = kinect_ir();
    let views: Vec<Vec<[f64; 2]>> = board_poses()[..2]
        .iter()
        .map(|p| project(&board, &ir, p))
        .collect();
    let e = calibrate_intrinsics(&board, &views, 512, 424).expect_err("2 views");
    assert!(e.to_string().contains("at least 3 views"), "{e}");
    let short = vec![views[0][..10].to_vec(); 3];
    let e = calibrate_intrinsics(&board, &short, 512, 424).expect_err("10 corners");
    assert!(e.to_string().contains("has 10 corners"), "{e}");
}

/// A fronto-parallel board, 4×4 supersampled: the corners come out where they are, in
/// canonical order, whatever the image is turned to.
#[test]
fn rendered_corners_are_found_to_sub_pixel_accuracy_in_canonical_order() {
    let board = Board::new([9, 6], 0.04).expect("board");
    let (w, h) = (320u32, 240u32);
    // Edges on the 1/4 px supersampling grid, so the rendered edges are exactly there.
    let px = 22.25;
    let origin = [61.75, 58.25];
    let render = |flip: bool| {
        let mut data = vec![0u8; (w * h) as usize];
        for v in 0..h {
            for u in 0..w {
                let mut acc = 0.0f64;
                for s in 0..16 {
                    let fu = f64::from(u) + (f64::from(s % 4) + 0.5) / 4.0 - 0.5;
                    let fv = f64::from(v) + (f64::from(s / 4) + 0.5) / 4.0 - 0.5;
                    // Turned by 180° about the image centre when `flip`.
                    let (fu, fv) = if flip {
                        (f64::from(w - 1) - fu, f64::from(h - 1) - fv)
                    } else {
                        (fu, fv)
                    };
                    let a = ((fu - origin[0]) / px).floor() as i64;
                    let b = ((fv - origin[1]) / px).floor() as i64;
                    let inside = (-1..9).contains(&a) && (-1..6).contains(&b);
                    acc += if inside && (a + b).rem_euclid(2) == 0 {
                        20.0
                    } else {
                        220.0
                    };
                }
                data[(v * w + u) as usize] = (acc / 16.0).round() as u8;
            }
        }
        GrayImage {
            width: w,
            height: h,
            data,
        }
    };
    for flip in [false, true] {
        let corners = find_board_corners(&render(flip), &board, BoardZ::AwayFromCamera)
            .expect("detect")
            .expect("found");
        for (k, c) in corners.iter().enumerate() {
            let (i, j) = ((k % 9) as f64, (k / 9) as f64);
            let mut want = [origin[0] + i * px, origin[1] + j * px];
            if flip {
                // The turned image shows corner (i, j) at the mirrored point, and the
                // canonical order turns the board back.
                want = [f64::from(w - 1) - want[0], f64::from(h - 1) - want[1]];
            }
            let err = (c[0] - want[0]).abs().max((c[1] - want[1]).abs());
            // Noise-free, supersampled edges: cornerSubPix lands within a tenth of a pixel per axis
            // (measured: ±0.075 px, varying with the edge's phase in the pixel, the known
            // pixel-locking of gradient-based refinement on sharp edges).
            assert!(err < 0.1, "flip {flip} corner {k}: {c:?} vs {want:?}");
        }
        // Turned by 180°, the canonical corner (0, 0) is the one that was (8, 5).
        let first = corners[0];
        assert_eq!(first[0] > f64::from(w) / 2.0, flip, "{first:?}");
    }
    let blank = GrayImage {
        width: 64,
        height: 48,
        data: vec![128; 64 * 48],
    };
    assert!(
        find_board_corners(&blank, &board, BoardZ::AwayFromCamera)
            .expect("runs")
            .is_none()
    );
}

#[test]
fn file_storage_written_by_opencv_reads_in_pure_rust_and_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ir = kinect_ir();
    for name in ["ir.yaml", "ir.yml", "ir.xml"] {
        let path = dir.path().join(name);
        write_opencv_intrinsics(&path, &ir, Some(0.05)).expect("write");
        let back = read_opencv_intrinsics(&path, None).expect("read");
        assert_eq!(back, ir, "{name}");
    }
    // iai_kinect2 folder: the pure-Rust writer's calib_ir.yaml reads through OpenCV (no
    // size in the file: the Kinect v2 one is given), and OpenCV's file reads in the
    // pure-Rust iai_kinect2 reader.
    let mut camera = RgbdCamera::new("k", ir, color());
    camera.color = Intrinsics {
        width: 1920,
        height: 1080,
        ..color()
    };
    let folder = dir.path().join("k");
    std::fs::create_dir(&folder).expect("mkdir");
    write_iai_kinect2(&folder, &camera).expect("write iai");
    let via_opencv =
        read_opencv_intrinsics(&folder.join("calib_ir.yaml"), Some(KINECT2_DEPTH_SIZE))
            .expect("read iai with OpenCV");
    assert_eq!(via_opencv, ir);
    write_opencv_intrinsics(&folder.join("calib_ir.yaml"), &ir, None).expect("overwrite");
    assert_eq!(read_iai_kinect2(&folder).expect("read iai").depth, ir);

    // Bad input names the file.
    let bad = dir.path().join("bad.yaml");
    std::fs::write(&bad, "%YAML:1.0\n---\nimage_width: 5\n").expect("write");
    let e = read_opencv_intrinsics(&bad, None)
        .expect_err("no matrix")
        .to_string();
    assert!(e.contains("cameraMatrix") && e.ends_with("bad.yaml"), "{e}");
    let e = write_opencv_intrinsics(&dir.path().join("x.json"), &ir, None)
        .expect_err("json")
        .to_string();
    assert!(e.contains(".yaml, .yml or .xml"), "{e}");
}

/// The colour sensor of a real Azure Kinect at 960×540 (its rational coefficients,
/// `tests/fixtures/calib/azure_kinect/pyk4a_calibration.json`).
fn azure_like() -> Intrinsics {
    Intrinsics {
        distortion: bodyseg_calib::testing::AZURE_COLOR_DISTORTION,
        ..color()
    }
}

#[test]
fn rational_model_is_opencvs() {
    // solvePnP fits the pose by minimising OpenCV's own projection (cv::projectPoints)
    // of the board: corners projected with our rational model are fitted exactly only if
    // both models agree.
    let board = Board::new([9, 6], 0.04).expect("board");
    let intrinsics = azure_like();
    for want in board_poses() {
        let corners = project(&board, &intrinsics, &want);
        let (got, rms_px) = board_pose(&board, &intrinsics, &corners).expect("solvePnP");
        // OpenCV takes the corners as Point2f (~1e-5 px rounding).
        assert!(rms_px < 1e-4, "RMS {rms_px:e} px");
        for (g, w) in got.translation_m().iter().zip(want.translation_m()) {
            assert!((g - w).abs() < 1e-5, "{got:?} vs {want:?}");
        }
    }
    // FileStorage with 8 coefficients: OpenCV writes them, OpenCV and the pure-Rust
    // reader read them back.
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["rgb.yaml", "rgb.xml"] {
        let path = dir.path().join(name);
        write_opencv_intrinsics(&path, &intrinsics, None).expect("write");
        assert_eq!(
            read_opencv_intrinsics(&path, None).expect("read"),
            intrinsics
        );
    }
    assert_eq!(
        bodyseg_calib::read_opencv_yaml_intrinsics(&dir.path().join("rgb.yaml"), None)
            .expect("pure Rust"),
        intrinsics
    );
}
