//! The multi-view consistency vote (`FrameProjector::vote_labels`) on a scene built
//! analytically: three parallel cameras 0.3 m apart see a wall 2 m away (torso) and a
//! small plate 1 m away (head). Camera 1's parser mislabels a patch of the wall as head;
//! the plate hides part of that patch from camera 2.

use bodyseg_calib::{BackProjectOptions, Intrinsics, Pose, RgbdCamera, Rig};
use bodyseg_core::{Class, Label, LabelImage, LabeledCloud};
use bodyseg_project::{CameraImages, FrameProjector, ProjectConfig, ProjectError};

const WALL_Z_M: f64 = 2.0;
const PLATE_Z_M: f64 = 1.0;
/// The plate: x in [0.05, 0.15], |y| <= 0.1 at z = 1 (world). From camera 2 (x = 0.3) it
/// hides the wall x in [-0.2, 0], |y| <= 0.2.
const PLATE_X_M: [f64; 2] = [0.05, 0.15];
const PLATE_HALF_H_M: f64 = 0.1;
/// Camera 1's mislabelled patch of wall: |x| <= 0.2, |y| <= 0.4.
const PATCH_HALF_W_M: f64 = 0.2;
const PATCH_HALF_H_M: f64 = 0.4;
const CAMERA_X_M: [f64; 3] = [-0.3, 0.0, 0.3];

/// One sensor model for depth and colour (64×48, no distortion) and `color_from_depth` =
/// identity: the projection adds no error of its own, so every wrong label is the parser's.
fn camera(index: usize) -> RgbdCamera {
    let intrinsics = Intrinsics::pinhole(64, 48, 40.0, 40.0, 31.5, 23.5);
    let mut cam = RgbdCamera::new(format!("cam{index}"), intrinsics, intrinsics);
    cam.world_from_depth = Pose::from_rotation_translation(
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [CAMERA_X_M[index], 0.0, 0.0],
    )
    .expect("identity rotation");
    cam
}

/// The first surface along the ray from camera `index` through its pixel (u, v): world
/// position and what the parser of that camera says there.
fn hit(index: usize, u: u32, v: u32) -> ([f64; 3], Class) {
    let cam = camera(index);
    let ray = cam
        .depth
        .unproject(f64::from(u), f64::from(v))
        .expect("no distortion");
    let at = |z: f64| [CAMERA_X_M[index] + ray[0] * z, ray[1] * z, z];
    let p = at(PLATE_Z_M);
    if (PLATE_X_M[0]..=PLATE_X_M[1]).contains(&p[0]) && p[1].abs() <= PLATE_HALF_H_M {
        return (p, Class::Head);
    }
    let p = at(WALL_Z_M);
    let in_patch = p[0].abs() <= PATCH_HALF_W_M && p[1].abs() <= PATCH_HALF_H_M;
    (
        p,
        if index == 1 && in_patch {
            Class::Head
        } else {
            Class::Torso
        },
    )
}

struct Frame {
    rig: Rig,
    depth: Vec<Vec<u16>>,
    labels: Vec<LabelImage>,
}

fn frame() -> Frame {
    let cameras: Vec<RgbdCamera> = (0..3).map(camera).collect();
    let mut depth = Vec::new();
    let mut labels = Vec::new();
    for (c, cam) in cameras.iter().enumerate() {
        let (w, h) = (cam.depth.width, cam.depth.height);
        let mut d = Vec::new();
        let mut l = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let (p, class) = hit(c, u, v);
                d.push((p[2] * cam.depth_scale).round() as u16);
                l.push(Label::from(class));
            }
        }
        depth.push(d);
        labels.push(LabelImage::new(w, h, l).expect("one label per pixel"));
    }
    Frame {
        rig: Rig { cameras },
        depth,
        labels,
    }
}

impl Frame {
    fn images(&self) -> Vec<CameraImages<'_>> {
        self.depth
            .iter()
            .zip(&self.labels)
            .map(|(d, l)| CameraImages {
                depth_raw: d,
                labels: l,
            })
            .collect()
    }
}

/// Project (naive: the labels are the parser's, nothing left unknown) and vote.
fn project_and_vote(
    f: &Frame,
    opts: &BackProjectOptions,
    cfg: &ProjectConfig,
) -> (LabeledCloud, Vec<Label>) {
    let projector = FrameProjector::new(&f.rig).expect("valid rig");
    let images = f.images();
    let cloud = projector
        .project_frame(&images, opts, cfg)
        .expect("valid frame");
    let mut voted = vec![Label::BACKGROUND; 3];
    projector
        .vote_labels(&images, opts, cfg, &cloud, &mut voted)
        .expect("the projector's own cloud");
    assert_eq!(voted.len(), cloud.len());
    (cloud, voted)
}

/// Indices of camera `c`'s wall points (z ≈ 2 m) whose world (x, y) lie in the boxes
/// `x0..x1`, `y0..y1`.
fn wall_points(cloud: &LabeledCloud, c: u8, x: [f32; 2], y: [f32; 2]) -> Vec<usize> {
    (0..cloud.len())
        .filter(|&i| {
            let p = cloud.positions_m[i];
            cloud.origins[i].camera == c
                && (p[2] - WALL_Z_M as f32).abs() < 0.01
                && (x[0]..=x[1]).contains(&p[0])
                && (y[0]..=y[1]).contains(&p[1])
        })
        .collect()
}

#[test]
fn vote_repairs_one_cameras_mislabelled_patch_and_ignores_a_camera_that_cannot_see() {
    let f = frame();
    let cfg = ProjectConfig::naive();
    let (cloud, voted) = project_and_vote(&f, &BackProjectOptions::default(), &cfg);
    let head = Label::from(Class::Head);
    let torso = Label::from(Class::Torso);

    // Camera 1's points in the patch, away from the plate's shadow in camera 2 (|y| > 0.2)
    // and from the patch's edge: projected head, seen as torso by cameras 0 and 2. Two
    // views against one: torso.
    let fixed = wall_points(&cloud, 1, [-0.17, 0.17], [0.23, 0.37]);
    assert!(fixed.len() >= 10, "{} points", fixed.len());
    for &i in &fixed {
        assert_eq!(cloud.labels[i], head, "point {i}: the parser's error");
        assert_eq!(voted[i], torso, "point {i} at {:?}", cloud.positions_m[i]);
    }

    // Camera 0's wall points that the plate hides from camera 2 (x in [-0.2, 0], |y| <=
    // 0.2), inside camera 1's patch: own torso, camera 1 head, camera 2 sees the plate
    // (head) 1 m in front. Camera 2 must not vote: a tie, own label kept. Had it voted,
    // head would win two to one.
    let shadow = wall_points(&cloud, 0, [-0.17, -0.03], [-0.17, 0.17]);
    assert!(shadow.len() >= 10, "{} points", shadow.len());
    for &i in &shadow {
        assert_eq!(cloud.labels[i], torso);
        assert_eq!(voted[i], torso, "point {i} at {:?}", cloud.positions_m[i]);
    }
    // Camera 1's points there: own head, camera 0 torso, camera 2 hidden: a tie, own kept
    // (the vote cannot tell who is right).
    let tie = wall_points(&cloud, 1, [-0.17, -0.03], [-0.17, 0.17]);
    assert!(!tie.is_empty());
    assert!(tie.iter().all(|&i| voted[i] == head));

    // The plate is head in every view and stays head; the wall outside the patch stays
    // torso: where the views agree, nothing changes.
    let plate: Vec<usize> = (0..cloud.len())
        .filter(|&i| (cloud.positions_m[i][2] - PLATE_Z_M as f32).abs() < 0.01)
        .collect();
    assert!(plate.len() >= 10);
    assert!(plate.iter().all(|&i| voted[i] == head));
    let outside = wall_points(&cloud, 0, [0.3, 1.0], [-1.0, 1.0]);
    assert!(!outside.is_empty());
    assert!(outside.iter().all(|&i| voted[i] == torso));
    // Every change is a repair of camera 1's patch.
    let changed: Vec<usize> = (0..cloud.len())
        .filter(|&i| voted[i] != cloud.labels[i])
        .collect();
    assert!(changed.iter().all(|&i| {
        cloud.origins[i].camera == 1 && cloud.labels[i] == head && voted[i] == torso
    }));
    assert!(changed.len() >= fixed.len());

    // With every other view "too far" to count (a slack of 0 and a camera 2 mm off), no
    // view votes and the vote is the projection.
    let mut shifted = frame();
    for d in &mut shifted.depth[2] {
        *d += 2;
    }
    for d in &mut shifted.depth[0] {
        *d += 2;
    }
    let strict = ProjectConfig {
        occlusion_tol_m: 0.0,
        occlusion_tol_ratio: 0.0,
        ..cfg.clone()
    };
    let (cloud, voted) = project_and_vote(&shifted, &BackProjectOptions::default(), &strict);
    let fixed = wall_points(&cloud, 1, [-0.17, 0.17], [0.23, 0.37]);
    assert!(!fixed.is_empty());
    assert!(fixed.iter().all(|&i| voted[i] == head));
}

#[test]
fn vote_with_a_stride_reads_the_other_cameras_grid_points() {
    let f = frame();
    let opts = BackProjectOptions {
        stride: 2,
        ..Default::default()
    };
    let (cloud, voted) = project_and_vote(&f, &opts, &ProjectConfig::naive());
    assert!(cloud.origins.iter().all(|o| o.pixel % 2 == 0));
    let fixed = wall_points(&cloud, 1, [-0.17, 0.17], [0.23, 0.37]);
    assert!(fixed.len() >= 3, "{} points", fixed.len());
    assert!(fixed.iter().all(|&i| voted[i] == Label::from(Class::Torso)));
}

#[test]
fn vote_rejects_a_cloud_from_another_rig() {
    let f = frame();
    let (mut cloud, _) =
        project_and_vote(&f, &BackProjectOptions::default(), &ProjectConfig::naive());
    let projector = FrameProjector::new(&f.rig).expect("valid rig");
    let images = f.images();
    let mut out = Vec::new();
    cloud.origins[5].camera = 7;
    let mut vote = |images: &[CameraImages<'_>], cloud: &LabeledCloud, why: &str| {
        projector
            .vote_labels(
                images,
                &BackProjectOptions::default(),
                &ProjectConfig::naive(),
                cloud,
                &mut out,
            )
            .expect_err(why)
    };
    let err = vote(&images, &cloud, "camera 7 of 3");
    assert!(
        matches!(err, ProjectError::CameraCount { want: 3, .. }),
        "{err}"
    );
    let err = vote(&images[..2], &cloud, "two images for three cameras");
    assert!(
        matches!(err, ProjectError::CameraCount { got: 2, want: 3 }),
        "{err}"
    );
}
