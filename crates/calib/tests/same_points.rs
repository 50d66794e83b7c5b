//! Issue 4's check "a rig in each format yields the same points for the same depth image":
//! the real iai_kinect2 camera, placed in a world, is written through every format (or
//! combination of formats) that can hold what back-projection uses — depth intrinsics,
//! `depth_scale`, `depth_shift_mm`, `world_from_depth` — read back, and back-projects one
//! depth image; the points are compared with those of the original camera.
//!
//! | source of the camera                           | what it holds                 | points      |
//! |------------------------------------------------|-------------------------------|-------------|
//! | `rig.toml`                                     | everything                    | bit-exact   |
//! | iai_kinect2 folder                             | all but `world_from_depth`    | bit-exact (depth frame) |
//! | iai_kinect2 folder + OpenPTrack `camera_poses` | everything                    | ≤ 1e-6 m    |
//! | Azure Kinect JSON + OpenPTrack `camera_poses`  | all but the depth shift       | ≤ 1e-6 m    |
//! | ROS `camera_info` (depth, colour) + OpenPTrack | all but shift and colour pose | ≤ 1e-6 m    |
//!
//! Neither Azure Kinect JSON nor ROS `camera_info` has a depth shift (their drivers publish
//! corrected depth): the shift is carried over from the source camera. ROS `camera_info`
//! has no depth→colour pose (that is TF's job); back-projection does not use it.
//!
//! Tolerance of the non-exact paths: OpenPTrack stores the rotation as a quaternion
//! (matrix → quaternion → matrix changes entries by a few ulps, < 1e-14) and Azure Kinect
//! normalises the intrinsics by the sensor size (`fx / W · W`, `(cx + 0.5) / W · W − 0.5`:
//! a few ulps, < 1e-9 px). At ≤ 10 m that moves an f64 point by < 1e-10 m, but points are
//! stored as f32 (ulp 9.5e-7 m between 8 and 16 m, 4.8e-7 m between 4 and 8 m), so an f64
//! difference that straddles a rounding boundary shows as one f32 ulp. Bound: one f32 ulp
//! of the coordinate, and at most 1e-6 m; origins (which pixels give points) must match
//! exactly.

use std::path::Path;

use bodyseg_calib::{
    AzureKinectMode, BackProjectOptions, BackProjected, CloudFrame, DepthBackProjector, Pose,
    RgbdCamera, Rig, read_azure_kinect_json, read_iai_kinect2, read_openptrack_poses,
    read_rig_toml, read_ros_camera_info, write_azure_kinect_json, write_iai_kinect2,
    write_openptrack_poses, write_rig_toml, write_ros_camera_info,
};

/// The real camera, 2.2 m up, yawed 30° and looking 35° down.
fn source_camera() -> RgbdCamera {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/iai_kinect2/196605135147");
    let mut cam = read_iai_kinect2(&dir).unwrap_or_else(|e| {
        panic!("test data (the shared/ folder must sit beside the repository): {e}")
    });
    assert_ne!(cam.depth_shift_mm, 0.0, "the real file has a depth shift");
    let (s, c) = 35f64.to_radians().sin_cos();
    let (sy, cy) = 30f64.to_radians().sin_cos();
    let tilt = [[1.0, 0.0, 0.0], [0.0, -s, c], [0.0, -c, -s]];
    let yaw = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
    let rotation = std::array::from_fn(|r| {
        std::array::from_fn(|k| (0..3).map(|j| yaw[r][j] * tilt[j][k]).sum())
    });
    cam.world_from_depth =
        Pose::from_rotation_translation(rotation, [1.25, -3.5, 2.2]).expect("a rotation");
    cam
}

/// Floor, a box and ~15% holes, raw millimetres.
fn depth_image(cam: &RgbdCamera) -> Vec<u16> {
    let mut rng = bodyseg_core::rng::XorShift64Star::new(0x5A3E_9017);
    let (w, h) = (cam.depth.width, cam.depth.height);
    let mut out = Vec::with_capacity(cam.depth.num_pixels());
    for v in 0..h {
        for u in 0..w {
            let r = rng.unit_f64();
            let z = if r < 0.15 {
                0.0
            } else if (160..330).contains(&u) && (130..320).contains(&v) {
                1900.0 + 0.7 * f64::from(u)
            } else {
                4400.0 - 5.8 * f64::from(v) + 37.0 * r
            };
            out.push(z as u16);
        }
    }
    out
}

fn points(cam: &RgbdCamera, image: &[u16], frame: CloudFrame) -> BackProjected {
    DepthBackProjector::new(cam, 0)
        .expect("valid camera")
        .back_project(
            image,
            &BackProjectOptions {
                frame,
                ..Default::default()
            },
        )
        .expect("right size")
}

fn assert_bit_exact(got: &BackProjected, want: &BackProjected, what: &str) {
    assert_eq!(got.origins, want.origins, "{what}: origins");
    let bits = |p: &BackProjected| {
        p.points_m
            .iter()
            .map(|q| q.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert!(bits(got) == bits(want), "{what}: points differ");
}

/// Largest coordinate difference, metres, after checking the tolerance of the module doc.
fn assert_close(got: &BackProjected, want: &BackProjected, what: &str) -> f32 {
    assert_eq!(got.origins, want.origins, "{what}: origins");
    let mut worst = 0f32;
    for (i, (g, w)) in got.points_m.iter().zip(&want.points_m).enumerate() {
        for k in 0..3 {
            let d = (g[k] - w[k]).abs();
            let one_ulp = w[k].abs().max(f32::MIN_POSITIVE) * f32::EPSILON;
            assert!(
                d <= one_ulp && d <= 1e-6,
                "{what}: point {i}[{k}]: {} vs {} (diff {d:e} m)",
                g[k],
                w[k]
            );
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn a_rig_in_each_format_yields_the_same_points() {
    let src = source_camera();
    let image = depth_image(&src);
    let want_world = points(&src, &image, CloudFrame::World);
    let want_depth = points(&src, &image, CloudFrame::Depth);
    assert!(want_world.points_m.len() > image.len() * 4 / 5);
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let name = src.name.clone();

    // rig.toml: everything, bit-exact.
    let rig_path = d.join("rig.toml");
    write_rig_toml(
        &Rig {
            cameras: vec![src.clone()],
        },
        &rig_path,
    )
    .expect("writes rig.toml");
    let from_toml = read_rig_toml(&rig_path).expect("reads rig.toml").cameras[0].clone();
    assert_eq!(from_toml, src, "rig.toml holds the camera exactly");
    assert_bit_exact(
        &points(&from_toml, &image, CloudFrame::World),
        &want_world,
        "rig.toml",
    );

    // iai_kinect2 folder: all but the world pose; depth-frame points bit-exact.
    let iai_dir = d.join(&name);
    write_iai_kinect2(&iai_dir, &src).expect("writes the folder");
    let from_iai = read_iai_kinect2(&iai_dir).expect("reads the folder");
    assert_bit_exact(
        &points(&from_iai, &image, CloudFrame::Depth),
        &want_depth,
        "iai_kinect2",
    );

    // OpenPTrack camera_poses.yaml supplies the world pose to the formats without one.
    let poses_path = d.join("camera_poses.yaml");
    write_openptrack_poses(&poses_path, &[(name.clone(), src.world_from_depth)])
        .expect("writes camera_poses.yaml");
    let poses = read_openptrack_poses(&poses_path).expect("reads camera_poses.yaml");
    assert_eq!(poses[0].0, name);
    let world_from_depth = poses[0].1;

    let mut iai_opt = from_iai.clone();
    iai_opt.world_from_depth = world_from_depth;
    let worst_iai = assert_close(
        &points(&iai_opt, &image, CloudFrame::World),
        &want_world,
        "iai_kinect2 + OpenPTrack",
    );

    // Azure Kinect JSON: intrinsics and depth→colour; no shift (carried over), no world.
    let azure_path = d.join("calibration.json");
    let mut no_shift = src.clone();
    no_shift.depth_shift_mm = 0.0;
    write_azure_kinect_json(&azure_path, &no_shift).expect("writes the JSON");
    let cal = read_azure_kinect_json(&azure_path, &name, AzureKinectMode::default())
        .expect("reads the JSON");
    assert!(cal.notes.is_empty(), "{:?}", cal.notes);
    let mut azure = cal.camera;
    azure.depth_shift_mm = src.depth_shift_mm;
    azure.world_from_depth = world_from_depth;
    assert_eq!(azure.color_from_depth, src.color_from_depth, "Rt is exact");
    let worst_azure = assert_close(
        &points(&azure, &image, CloudFrame::World),
        &want_world,
        "Azure Kinect + OpenPTrack",
    );

    // ROS camera_info for each sensor's intrinsics (exact) + OpenPTrack for the world pose.
    let ir_path = d.join("depth_camera_info.yaml");
    let rgb_path = d.join("rgb_camera_info.yaml");
    write_ros_camera_info(&ir_path, &format!("{name}_ir"), &src.depth).expect("writes");
    write_ros_camera_info(&rgb_path, &format!("{name}_rgb"), &src.color).expect("writes");
    let ir = read_ros_camera_info(&ir_path).expect("reads");
    let rgb = read_ros_camera_info(&rgb_path).expect("reads");
    assert_eq!(
        (ir.intrinsics, rgb.intrinsics),
        (src.depth, src.color),
        "exact"
    );
    let mut ros = RgbdCamera::new(name.clone(), ir.intrinsics, rgb.intrinsics);
    ros.depth_shift_mm = src.depth_shift_mm;
    ros.world_from_depth = world_from_depth;
    assert_bit_exact(
        &points(&ros, &image, CloudFrame::Depth),
        &want_depth,
        "ROS camera_info",
    );
    let worst_ros = assert_close(
        &points(&ros, &image, CloudFrame::World),
        &want_world,
        "ROS camera_info + OpenPTrack",
    );
    eprintln!(
        "largest coordinate differences (m): iai+OpenPTrack {worst_iai:e}, \
         Azure+OpenPTrack {worst_azure:e}, ROS+OpenPTrack {worst_ros:e}"
    );
}
