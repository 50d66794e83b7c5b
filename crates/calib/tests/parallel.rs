//! Parallel back-projection (rayon across chunks of rows, and across a rig's cameras)
//! gives exactly the sequential output: same points bit for bit, same origins, same order.

use bodyseg_calib::{
    BackProjectOptions, BackProjected, CalibError, CloudFrame, DepthBackProjector, Pose,
    RgbdCamera, Rig, RigBackProjector, back_project_rig,
};

fn kinect() -> RgbdCamera {
    bodyseg_calib::testing::kinect_v2_test_camera().unwrap_or_else(|e| {
        panic!("test data (the shared/ folder must sit beside the repository): {e}")
    })
}

/// A camera 2.2 m up, turned by `yaw` about world z and looking 35° down.
fn placed(mut cam: RgbdCamera, name: &str, yaw_deg: f64) -> RgbdCamera {
    let (s, c) = 35f64.to_radians().sin_cos();
    let (sy, cy) = yaw_deg.to_radians().sin_cos();
    let tilt = [[1.0, 0.0, 0.0], [0.0, -s, c], [0.0, -c, -s]];
    let rotation = std::array::from_fn(|r| {
        let yawed = |k: usize| match r {
            0 => cy * tilt[0][k] - sy * tilt[1][k],
            1 => sy * tilt[0][k] + cy * tilt[1][k],
            _ => tilt[2][k],
        };
        [yawed(0), yawed(1), yawed(2)]
    });
    cam.name = name.to_string();
    cam.world_from_depth =
        Pose::from_rotation_translation(rotation, [0.5 * cy, 0.5 * sy, 2.2]).expect("a rotation");
    cam
}

/// A Kinect-like depth image (mm): slanted plane, a box, ~15% holes (0), a few raw values
/// below the file's −13.35 mm depth shift (non-positive after it) and a few above 8 m.
fn depth_image(cam: &RgbdCamera, seed: u64) -> Vec<u16> {
    let mut rng = bodyseg_core::rng::XorShift64Star::new(seed);
    let mut unit = move || rng.unit_f64();
    let (w, h) = (cam.depth.width, cam.depth.height);
    let mut out = Vec::with_capacity(cam.depth.num_pixels());
    for v in 0..h {
        for u in 0..w {
            let r = unit();
            let z = if r < 0.15 {
                0.0
            } else if r < 0.16 {
                (unit() * 14.0).floor()
            } else if r < 0.17 {
                8000.0 + unit() * 2000.0
            } else if (150..340).contains(&u) && (120..330).contains(&v) {
                1800.0 + f64::from(u) + unit() * 10.0
            } else {
                4300.0 - 5.5 * f64::from(v) + unit() * 20.0
            };
            out.push(z as u16);
        }
    }
    out
}

fn assert_bit_identical(got: &BackProjected, want: &BackProjected, what: &str) {
    assert_eq!(got.origins, want.origins, "{what}: origins");
    assert_eq!(
        got.points_m.len(),
        want.points_m.len(),
        "{what}: point count"
    );
    for (i, (g, w)) in got.points_m.iter().zip(&want.points_m).enumerate() {
        assert_eq!(
            g.map(f32::to_bits),
            w.map(f32::to_bits),
            "{what}: point {i}: {g:?} vs {w:?}"
        );
    }
}

#[test]
fn parallel_equals_sequential_bit_for_bit_on_a_kinect_image_with_holes() {
    let cam = placed(kinect(), "k", 20.0);
    let image = depth_image(&cam, 0x5EED_0001);
    let projector = DepthBackProjector::new(&cam, 3).expect("valid camera");
    let holes = image.iter().filter(|&&d| d == 0).count();
    assert!(holes > image.len() / 10, "the image has holes");
    for frame in [CloudFrame::World, CloudFrame::Depth] {
        for stride in [1, 2, 3, 7, 423, 1000] {
            for (min, max) in [(0.0, f64::INFINITY), (0.5, 4.5)] {
                let opts = BackProjectOptions {
                    depth_min_m: min,
                    depth_max_m: max,
                    stride,
                    frame,
                };
                let par = projector.back_project(&image, &opts).expect("ok");
                let seq = projector
                    .back_project_sequential(&image, &opts)
                    .expect("ok");
                let what = format!("{frame:?} stride {stride} range [{min}, {max}]");
                if stride == 1 && min == 0.0 {
                    // Holes, sub-shift raw values give no point; everything else does.
                    assert!(seq.points_m.len() > image.len() * 3 / 4, "{what}");
                    assert!(seq.points_m.len() < image.len() - holes, "{what}");
                }
                assert!(seq.origins.iter().all(|o| o.camera == 3), "{what}");
                assert_bit_identical(&par, &seq, &what);
            }
        }
    }
    // Same on more threads than rows per chunk and on a single thread.
    let opts = BackProjectOptions::default();
    let seq = projector
        .back_project_sequential(&image, &opts)
        .expect("ok");
    for threads in [1, 3, 16] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let par = pool.install(|| projector.back_project(&image, &opts).expect("ok"));
        assert_bit_identical(&par, &seq, &format!("{threads} threads"));
    }
}

fn three_camera_rig() -> Rig {
    let base = kinect();
    Rig {
        cameras: vec![
            placed(base.clone(), "a", 0.0),
            placed(base.clone(), "b", 120.0),
            placed(base, "c", 240.0),
        ],
    }
}

#[test]
fn rig_cloud_is_the_cameras_clouds_in_rig_order() {
    let rig = three_camera_rig();
    let images: Vec<Vec<u16>> = (0..3)
        .map(|i| depth_image(&rig.cameras[i], 100 + i as u64))
        .collect();
    let depths: Vec<&[u16]> = images.iter().map(Vec::as_slice).collect();
    let opts = BackProjectOptions::default();
    let cloud = back_project_rig(&depths, &rig, &opts).expect("ok");

    let mut want = BackProjected::default();
    for (i, (cam, img)) in rig.cameras.iter().zip(&images).enumerate() {
        let one = DepthBackProjector::new(cam, i as u8)
            .expect("valid")
            .back_project_sequential(img, &opts)
            .expect("ok");
        assert!(!one.points_m.is_empty());
        want.points_m.extend(one.points_m);
        want.origins.extend(one.origins);
    }
    assert_bit_identical(&cloud, &want, "rig");
    // Rig order: camera indices never decrease.
    assert!(cloud.origins.windows(2).all(|w| w[0].camera <= w[1].camera));
    assert_eq!(cloud.origins.last().map(|o| o.camera), Some(2));

    let projector = RigBackProjector::new(&rig).expect("valid rig");
    let each = projector
        .back_project_each(
            &depths,
            &BackProjectOptions {
                frame: CloudFrame::Depth,
                ..opts
            },
        )
        .expect("ok");
    assert_eq!(each.len(), 3);
    for (i, part) in each.iter().enumerate() {
        let seq = projector.projectors()[i]
            .back_project_sequential(
                depths[i],
                &BackProjectOptions {
                    frame: CloudFrame::Depth,
                    ..opts
                },
            )
            .expect("ok");
        assert_bit_identical(part, &seq, &format!("camera {i}, depth frame"));
    }
}

#[test]
fn rig_errors_are_clear() {
    let rig = three_camera_rig();
    let projector = RigBackProjector::new(&rig).expect("valid rig");
    let image = depth_image(&rig.cameras[0], 1);
    let opts = BackProjectOptions::default();

    let err = projector
        .back_project(&[&image, &image], &opts)
        .expect_err("two images for three cameras");
    assert!(err.to_string().contains("3 cameras, got 2 images"), "{err}");

    let err = projector
        .back_project(
            &[&image, &image, &image],
            &BackProjectOptions {
                frame: CloudFrame::Depth,
                ..opts
            },
        )
        .expect_err("a joint cloud in depth frames");
    assert!(err.to_string().starts_with("frame"), "{err}");

    let err = projector
        .back_project(&[&image, &image[..100], &image], &opts)
        .expect_err("a short image");
    assert!(
        matches!(&err, CalibError::DepthSize { camera, .. } if camera == "b"),
        "{err}"
    );

    let mut dup = rig.clone();
    dup.cameras[2].name = "a".to_string();
    assert!(RigBackProjector::new(&dup).is_err(), "duplicate names");
}
