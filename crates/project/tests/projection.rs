//! Label projection on small scenes built analytically (no synth yet): a fronto-parallel
//! foreground rectangle in front of a far background plane, seen by a camera whose colour
//! sensor sits 5 cm to the side of its depth sensor. The label image is the exact
//! projection of the truth, so every wrong label is a DSA error of the projection itself.

use bodyseg_calib::{
    BackProjectOptions, CloudFrame, Intrinsics, Pose, RgbdCamera, Rig, back_project,
};
use bodyseg_core::{Class, Label, LabelImage, LabeledCloud, PointOrigin};
use bodyseg_project::{
    CameraImages, FrameProjector, Hits, ProjectConfig, ProjectError, ProjectMode, project_frame,
    project_labels,
};

const FG: Class = Class::Torso;
const BG: Class = Class::Background;

/// A scene of planes z = const in the depth sensor frame: a foreground rectangle
/// (`|x| ≤ half_w_m`, `|y| ≤ half_h_m` at `z_fg_m`) in front of an infinite background
/// plane at `z_bg_m`.
#[derive(Clone, Copy)]
struct Scene {
    z_fg_m: f64,
    z_bg_m: f64,
    half_w_m: f64,
    half_h_m: f64,
}

impl Scene {
    /// First surface hit by the ray `origin + t·dir` (depth frame): (depth z, class).
    fn hit(&self, origin: [f64; 3], dir: [f64; 3]) -> (f64, Class) {
        let t = (self.z_fg_m - origin[2]) / dir[2];
        let x = origin[0] + t * dir[0];
        let y = origin[1] + t * dir[1];
        if t > 0.0 && x.abs() <= self.half_w_m && y.abs() <= self.half_h_m {
            (self.z_fg_m, FG)
        } else {
            (self.z_bg_m, BG)
        }
    }
}

/// The ray (z = 1, sensor frame) of every pixel centre of `intr`, row-major.
fn pixel_rays(intr: &Intrinsics) -> impl Iterator<Item = [f64; 3]> + '_ {
    (0..intr.height).flat_map(move |v| {
        (0..intr.width).map(move |u| {
            intr.unproject(f64::from(u), f64::from(v))
                .expect("fixture intrinsics undistort everywhere")
        })
    })
}

/// Depth image (raw, with the camera's scale and shift) and the truth per depth pixel.
fn render_depth(camera: &RgbdCamera, scene: &Scene) -> (Vec<u16>, Vec<Class>) {
    let d = &camera.depth;
    let mut raw = Vec::with_capacity(d.num_pixels());
    let mut truth = Vec::with_capacity(d.num_pixels());
    for ray in pixel_rays(d) {
        let (z, class) = scene.hit([0.0; 3], ray);
        let mm = z * camera.depth_scale - camera.depth_shift_mm;
        raw.push(mm.round() as u16);
        truth.push(class);
    }
    (raw, truth)
}

/// The exact label image: what each colour pixel centre's ray sees.
fn render_labels(camera: &RgbdCamera, scene: &Scene) -> LabelImage {
    let c = &camera.color;
    let depth_from_color = camera.color_from_depth.inverse();
    let origin = depth_from_color.transform_point([0.0; 3]);
    let r = depth_from_color.rotation();
    let mut labels = Vec::with_capacity(c.num_pixels());
    for d in pixel_rays(c) {
        let dir = [0, 1, 2].map(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2]);
        labels.push(Label::from(scene.hit(origin, dir).1));
    }
    LabelImage::new(c.width, c.height, labels).expect("one label per colour pixel")
}

/// 64×48 depth, 128×96 colour (twice the focal length: the colour image is denser, as on
/// a Kinect), no distortion, colour sensor 5 cm to the depth sensor's +x.
fn simple_camera() -> RgbdCamera {
    let depth = Intrinsics::pinhole(64, 48, 60.0, 60.0, 31.5, 23.5);
    let color = Intrinsics::pinhole(128, 96, 120.0, 120.0, 63.5, 47.5);
    let mut cam = RgbdCamera::new("simple", depth, color);
    cam.color_from_depth = Pose::from_rotation_translation(
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [-0.05, 0.0, 0.0],
    )
    .expect("identity rotation");
    cam
}

const SIMPLE_SCENE: Scene = Scene {
    z_fg_m: 0.8,
    z_bg_m: 2.5,
    half_w_m: 0.1,
    half_h_m: 0.08,
};

/// One camera's fixture: points (depth frame), origins, raw depth, truth per point,
/// label image.
struct Fixture {
    camera: RgbdCamera,
    points: Vec<[f32; 3]>,
    origins: Vec<PointOrigin>,
    depth_raw: Vec<u16>,
    truth: Vec<Class>,
    labels: LabelImage,
}

impl Fixture {
    /// Its raw depth and label image, as a frame's camera images.
    fn images(&self) -> CameraImages<'_> {
        CameraImages {
            depth_raw: &self.depth_raw,
            labels: &self.labels,
        }
    }
}

fn fixture(camera: RgbdCamera, scene: &Scene) -> Fixture {
    let (depth_raw, truth_px) = render_depth(&camera, scene);
    let labels = render_labels(&camera, scene);
    let opts = BackProjectOptions {
        frame: CloudFrame::Depth,
        ..Default::default()
    };
    let cloud = back_project(&depth_raw, &camera, 0, &opts).expect("valid fixture camera");
    let truth = cloud
        .origins
        .iter()
        .map(|o| truth_px[o.pixel as usize])
        .collect();
    Fixture {
        camera,
        points: cloud.points_m,
        origins: cloud.origins,
        depth_raw,
        truth,
        labels,
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Score {
    points: usize,
    wrong: usize,
    unknown: usize,
    /// Background points labelled foreground (the parallax strip hidden from colour).
    bg_as_fg: usize,
}

impl Score {
    fn wrong_frac(&self) -> f64 {
        self.wrong as f64 / self.points as f64
    }
    fn unknown_frac(&self) -> f64 {
        self.unknown as f64 / self.points as f64
    }
    /// Fraction right among the points given a label.
    fn precision(&self) -> f64 {
        let labelled = self.points - self.unknown;
        (labelled - self.wrong) as f64 / labelled as f64
    }
}

fn run(f: &Fixture, labels: &LabelImage, cfg: &ProjectConfig) -> (Vec<Label>, Score) {
    let out = project_labels(&f.camera, &f.points, &f.origins, &f.depth_raw, labels, cfg)
        .expect("valid inputs");
    assert_eq!(out.len(), f.points.len());
    let mut s = Score {
        points: out.len(),
        wrong: 0,
        unknown: 0,
        bg_as_fg: 0,
    };
    for (l, &t) in out.iter().zip(&f.truth) {
        match l.class() {
            None => s.unknown += 1,
            Some(c) if c != t => {
                s.wrong += 1;
                if t == BG && c == FG {
                    s.bg_as_fg += 1;
                }
            }
            Some(_) => {}
        }
    }
    (out, s)
}

fn check_dsa_beats_naive(name: &str, f: &Fixture) {
    let (_, naive) = run(f, &f.labels, &ProjectConfig::naive());
    let (_, dsa) = run(f, &f.labels, &ProjectConfig::default());
    println!(
        "{name}: {} points, {} outside the colour image; naive wrong {:.4} ({}), bg→fg {}; dsa wrong {:.4} ({}), unknown {:.4} ({}), precision {:.5}",
        naive.points,
        naive.unknown,
        naive.wrong_frac(),
        naive.wrong,
        naive.bg_as_fg,
        dsa.wrong_frac(),
        dsa.wrong,
        dsa.unknown_frac(),
        dsa.unknown,
        dsa.precision()
    );
    // The parallax hides a strip of background behind the foreground's edge from the
    // colour camera; naive gives it the foreground's label.
    assert!(naive.bg_as_fg > 0, "{naive:?}");
    // Naive leaves unknown only what falls outside the colour image; DSA adds to that.
    assert!(naive.unknown <= dsa.unknown);
    assert!(dsa.wrong < naive.wrong, "naive {naive:?} dsa {dsa:?}");
    assert!(dsa.precision() >= 0.995, "{dsa:?}");
    // DSA pays with unknown points, but only near edges, not half the cloud.
    assert!(dsa.unknown_frac() < 0.2, "{dsa:?}");
}

#[test]
fn dsa_beats_naive_on_parallax_fixture() {
    check_dsa_beats_naive("simple 64x48", &fixture(simple_camera(), &SIMPLE_SCENE));
}

/// The fixture with the real Kinect v2 calibration in `../shared/data`: a 0.6 × 0.8 m
/// rectangle at 1.2 m before a wall at 3 m.
fn kinect_fixture() -> Fixture {
    let camera = bodyseg_calib::testing::kinect_v2_test_camera()
        .expect("the example iai_kinect2 folder reads");
    let scene = Scene {
        z_fg_m: 1.2,
        z_bg_m: 3.0,
        half_w_m: 0.3,
        half_h_m: 0.4,
    };
    fixture(camera, &scene)
}

#[test]
fn dsa_beats_naive_with_real_kinect_calibration() {
    check_dsa_beats_naive("kinect 512x424", &kinect_fixture());
}

#[test]
fn each_check_switched_off_changes_the_result() {
    let f = fixture(simple_camera(), &SIMPLE_SCENE);
    let (full_labels, full) = run(&f, &f.labels, &ProjectConfig::default());

    // Occlusion off: the hidden background strip is no longer unknown; the part of it wider
    // than the depth-edge band comes back with the foreground's label unless the vote of
    // its background neighbours repairs it (with the vote off too, it stays wrong).
    let no_occ = ProjectConfig {
        occlusion: false,
        ..Default::default()
    };
    let (_, s) = run(&f, &f.labels, &no_occ);
    assert!(s.unknown < full.unknown, "{s:?} vs {full:?}");
    assert!(s.wrong >= full.wrong);
    let no_vote = ProjectConfig {
        label_boundary: false,
        ..Default::default()
    };
    let (_, s_vote_off) = run(&f, &f.labels, &no_vote);
    let (_, s_both_off) = run(
        &f,
        &f.labels,
        &ProjectConfig {
            occlusion: false,
            ..no_vote.clone()
        },
    );
    println!("occlusion off: {s:?}; vote off: {s_vote_off:?}; both off: {s_both_off:?}");
    assert!(
        s_both_off.bg_as_fg > s_vote_off.bg_as_fg,
        "{s_both_off:?} vs {s_vote_off:?}"
    );
    assert!(s_both_off.wrong > s_vote_off.wrong);

    // Depth edge off: points next to the depth jump get labels again.
    let no_edge = ProjectConfig {
        depth_edge: false,
        ..Default::default()
    };
    let (_, s) = run(&f, &f.labels, &no_edge);
    assert!(s.unknown < full.unknown, "{s:?} vs {full:?}");
    // With it on, every point with a neighbour across the jump is unknown.
    let w = f.camera.depth.width as usize;
    for (i, o) in f.origins.iter().enumerate() {
        let (u, v) = (o.pixel as usize % w, o.pixel as usize / w);
        let me = f.depth_raw[o.pixel as usize];
        let across = [
            (u + 1, v),
            (u.wrapping_sub(1), v),
            (u, v + 1),
            (u, v.wrapping_sub(1)),
        ]
        .into_iter()
        .filter(|&(un, vn)| un < w && vn < f.camera.depth.height as usize)
        .any(|(un, vn)| f.depth_raw[vn * w + un] != me);
        if across {
            assert!(full_labels[i].is_unknown(), "point {i} at ({u}, {v})");
        }
    }

    // Naive mode ignores every check.
    let naive_all_off = ProjectConfig {
        mode: ProjectMode::Naive,
        occlusion: false,
        depth_edge: false,
        label_boundary: false,
        ..Default::default()
    };
    let dsa_all_off = ProjectConfig {
        mode: ProjectMode::Dsa,
        ..naive_all_off.clone()
    };
    assert_eq!(
        run(&f, &f.labels, &naive_all_off).0,
        run(&f, &f.labels, &dsa_all_off).0,
        "dsa with every check off is naive"
    );
    assert_eq!(
        run(&f, &f.labels, &naive_all_off).0,
        run(&f, &f.labels, &ProjectConfig::naive()).0
    );
}

/// One plane, left half head and right half torso; the parser bleeds head 2 colour pixels
/// into the torso on a thin band of rows. The vote of depth neighbours repairs it.
#[test]
fn label_boundary_vote_repairs_bleeding() {
    let camera = simple_camera();
    let z_m = 1.5;
    let boundary_x_m = 0.013; // off any pixel centre, so no rounding ties
    let head = Label::from(Class::Head);
    let torso = Label::from(Class::Torso);
    let depth_raw = vec![(z_m * 1000.0) as u16; camera.depth.num_pixels()];
    let opts = BackProjectOptions {
        frame: CloudFrame::Depth,
        ..Default::default()
    };
    let cloud = back_project(&depth_raw, &camera, 0, &opts).expect("valid camera");
    let truth_of = |x_m: f32| {
        if f64::from(x_m) < boundary_x_m {
            head
        } else {
            torso
        }
    };
    let truth: Vec<Label> = cloud.points_m.iter().map(|p| truth_of(p[0])).collect();
    let c = &camera.color;
    let mut labels = Vec::new();
    for v in 0..c.height {
        for u in 0..c.width {
            // Colour ray hits the plane at x_color; depth frame x = x_color + 0.05.
            let x_depth = (f64::from(u) - c.cx) / c.fx * z_m + 0.05;
            let x_boundary_px = (boundary_x_m - 0.05) / z_m * c.fx + c.cx;
            let bleed =
                v % 8 < 2 && f64::from(u) > x_boundary_px && f64::from(u) < x_boundary_px + 2.5;
            labels.push(if x_depth < boundary_x_m || bleed {
                head
            } else {
                torso
            });
        }
    }
    let labels = LabelImage::new(c.width, c.height, labels).expect("sized");
    let wrong = |cfg: &ProjectConfig| {
        let out = project_labels(
            &camera,
            &cloud.points_m,
            &cloud.origins,
            &depth_raw,
            &labels,
            cfg,
        )
        .expect("valid inputs");
        out.iter()
            .zip(&truth)
            .filter(|(l, t)| !l.is_unknown() && l != t)
            .count()
    };
    let naive = wrong(&ProjectConfig::naive());
    let no_vote = wrong(&ProjectConfig {
        label_boundary: false,
        ..Default::default()
    });
    let vote = wrong(&ProjectConfig::default());
    println!("bleeding: naive wrong {naive}, dsa without vote {no_vote}, dsa {vote}");
    assert!(naive > 0);
    assert_eq!(no_vote, naive, "no depth edge or occlusion on one plane");
    assert!(vote < no_vote);

    // The same labels whatever the points' order: with origins not increasing, the
    // labels per depth pixel that the vote reads are gathered another way.
    let cfg = ProjectConfig::default();
    let forward = project_labels(
        &camera,
        &cloud.points_m,
        &cloud.origins,
        &depth_raw,
        &labels,
        &cfg,
    )
    .expect("valid inputs");
    let points_rev: Vec<_> = cloud.points_m.iter().rev().copied().collect();
    let origins_rev: Vec<_> = cloud.origins.iter().rev().copied().collect();
    let mut backward = project_labels(
        &camera,
        &points_rev,
        &origins_rev,
        &depth_raw,
        &labels,
        &cfg,
    )
    .expect("valid inputs");
    backward.reverse();
    assert_eq!(backward, forward);
}

/// `labels` with probabilities: 0.3 on the left half of the image, 0.9 on the right.
fn left_half_unsure(labels: &LabelImage) -> LabelImage {
    let w = labels.width as usize;
    LabelImage {
        probs: Some(
            (0..labels.num_pixels())
                .map(|i| if i % w < w / 2 { 0.3 } else { 0.9 })
                .collect(),
        ),
        ..labels.clone()
    }
}

#[test]
fn low_probability_labels_become_unknown() {
    let f = fixture(simple_camera(), &SIMPLE_SCENE);
    let labels = left_half_unsure(&f.labels);
    let w = labels.width as usize;
    let base = ProjectConfig {
        occlusion: false,
        depth_edge: false,
        label_boundary: false,
        ..Default::default()
    };
    let (off, s_off) = run(&f, &labels, &base);
    let (plain, _) = run(&f, &f.labels, &base);
    assert_eq!(off, plain, "min_probability 0 is off");
    let on = ProjectConfig {
        min_probability: 0.5,
        ..base
    };
    let (out, s_on) = run(&f, &labels, &on);
    assert!(s_on.unknown > s_off.unknown);
    for (i, p) in f.points.iter().enumerate() {
        if off[i].is_unknown() {
            // Outside the colour image.
            assert!(out[i].is_unknown());
            continue;
        }
        let uv = f
            .camera
            .color
            .project([f64::from(p[0]) - 0.05, f64::from(p[1]), f64::from(p[2])])
            .expect("in front");
        let left = (uv[0].round() as usize) < w / 2;
        assert_eq!(out[i].is_unknown(), left, "point {i} at u_c {}", uv[0]);
        if !left {
            assert_eq!(out[i], off[i]);
        }
    }
}

#[test]
fn points_outside_the_color_image_are_unknown() {
    let mut camera = simple_camera();
    // Keep the principal point but cut the colour image to its left half.
    camera.color.width = 64;
    let f = fixture(camera, &SIMPLE_SCENE);
    for cfg in [ProjectConfig::naive(), ProjectConfig::default()] {
        let (out, _) = run(&f, &f.labels, &cfg);
        let mut outside = 0;
        for (i, p) in f.points.iter().enumerate() {
            let u = 63.5 + 120.0 * (f64::from(p[0]) - 0.05) / f64::from(p[2]);
            if u >= 63.5 {
                outside += 1;
                assert!(out[i].is_unknown(), "{:?}: point {i} at u_c {u}", cfg.mode);
            }
        }
        assert!(
            outside > 500,
            "the fixture has points beyond the image: {outside}"
        );
    }
    // A point behind the colour camera.
    let out = project_labels(
        &f.camera,
        &[[0.0, 0.0, -1.0]],
        &[PointOrigin {
            camera: 0,
            pixel: 0,
        }],
        &f.depth_raw,
        &f.labels,
        &ProjectConfig::naive(),
    )
    .expect("valid inputs");
    assert_eq!(out, [Label::UNKNOWN]);
}

#[test]
fn config_validation_names_the_field() {
    // The default config with one field set out of its range: the error opens with it.
    let rejects = |edit: fn(&mut ProjectConfig), field: &str| {
        let mut cfg = ProjectConfig::default();
        edit(&mut cfg);
        let msg = cfg.validate().expect_err(field).to_string();
        assert!(msg.starts_with(field), "{msg}");
    };
    rejects(|c| c.occlusion_tol_m = -0.01, "project.occlusion_tol_m");
    rejects(|c| c.edge_jump_ratio = f64::NAN, "project.edge_jump_ratio");
    rejects(|c| c.edge_radius_px = 0, "project.edge_radius_px");
    rejects(|c| c.boundary_radius_px = 99, "project.boundary_radius_px");
    rejects(|c| c.min_probability = 1.5, "project.min_probability");
    assert!(ProjectConfig::default().validate().is_ok());
    // project_labels validates too.
    let f = fixture(simple_camera(), &SIMPLE_SCENE);
    let bad = ProjectConfig {
        splat_radius_px: 0,
        ..Default::default()
    };
    let err = project_labels(
        &f.camera,
        &f.points,
        &f.origins,
        &f.depth_raw,
        &f.labels,
        &bad,
    )
    .expect_err("invalid config");
    assert!(err.to_string().contains("project.splat_radius_px"), "{err}");
}

#[test]
fn config_reads_from_toml_with_defaults_and_rejects_unknown_keys() {
    let cfg: ProjectConfig = toml::from_str("").expect("empty is all defaults");
    assert_eq!(cfg, ProjectConfig::default());
    let cfg: ProjectConfig =
        toml::from_str("mode = \"naive\"\nocclusion_tol_m = 0.05").expect("valid");
    assert_eq!(cfg.mode, ProjectMode::Naive);
    assert_eq!(cfg.occlusion_tol_m, 0.05);
    let err = toml::from_str::<ProjectConfig>("occlusion_tol = 0.05").expect_err("unknown key");
    assert!(err.to_string().contains("occlusion_tol"), "{err}");
}

#[test]
fn bad_inputs_are_errors_naming_the_camera() {
    let f = fixture(simple_camera(), &SIMPLE_SCENE);
    let cfg = ProjectConfig::default();
    let small = LabelImage::filled(10, 10, Label::BACKGROUND);
    let err = project_labels(&f.camera, &f.points, &f.origins, &f.depth_raw, &small, &cfg)
        .expect_err("label image size");
    assert!(matches!(err, ProjectError::LabelImageSize { .. }));
    assert_eq!(
        err.to_string(),
        "camera simple: label image is 10x10, calibration says 128x96"
    );
    let err = project_labels(
        &f.camera,
        &f.points,
        &f.origins,
        &f.depth_raw[1..],
        &f.labels,
        &cfg,
    )
    .expect_err("depth size");
    assert!(err.to_string().contains("depth image"), "{err}");
    let err = project_labels(
        &f.camera,
        &f.points,
        &f.origins[1..],
        &f.depth_raw,
        &f.labels,
        &cfg,
    )
    .expect_err("origins");
    assert!(err.to_string().contains("origins"), "{err}");
    let mut origins = f.origins.clone();
    origins[3].pixel = 1_000_000;
    let err = project_labels(
        &f.camera,
        &f.points,
        &origins,
        &f.depth_raw,
        &f.labels,
        &cfg,
    )
    .expect_err("origin outside");
    assert!(
        matches!(err, ProjectError::OriginOutside { index: 3, .. }),
        "{err}"
    );
}

#[test]
fn project_frame_concatenates_cameras_in_world_frame() {
    let cam0 = simple_camera();
    let mut cam1 = simple_camera();
    cam1.name = "second".into();
    cam1.world_from_depth = Pose::from_rotation_translation(
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        [1.0, 2.0, 0.5],
    )
    .expect("rotation about z");
    let rig = Rig {
        cameras: vec![cam0.clone(), cam1.clone()],
    };
    let f0 = fixture(cam0, &SIMPLE_SCENE);
    let far = Scene {
        z_fg_m: 1.0,
        ..SIMPLE_SCENE
    };
    let f1 = fixture(cam1, &far);
    let images = [f0.images(), f1.images()];
    let cfg = ProjectConfig::default();
    let cloud =
        project_frame(&rig, &images, &BackProjectOptions::default(), &cfg).expect("valid frame");
    cloud.validate().expect("consistent cloud");
    let n0 = f0.points.len();
    assert_eq!(cloud.len(), n0 + f1.points.len());
    assert!(cloud.origins[..n0].iter().all(|o| o.camera == 0));
    assert!(cloud.origins[n0..].iter().all(|o| o.camera == 1));
    let (l0, _) = run(&f0, &f0.labels, &cfg);
    let (l1, _) = run(&f1, &f1.labels, &cfg);
    assert_eq!(cloud.labels[..n0], l0[..]);
    assert_eq!(cloud.labels[n0..], l1[..]);
    // Camera 1's points went through world_from_depth: (x, y, z) → (1 - y, 2 + x, 0.5 + z).
    for (p_world, p_depth) in cloud.positions_m[n0..].iter().zip(&f1.points) {
        let want = [1.0 - p_depth[1], 2.0 + p_depth[0], 0.5 + p_depth[2]];
        for a in 0..3 {
            // f32 rounding of a few metres: ~1e-6 m.
            assert!(
                (p_world[a] - want[a]).abs() < 1e-5,
                "{p_world:?} vs {want:?}"
            );
        }
    }
    let err = project_frame(&rig, &images[..1], &BackProjectOptions::default(), &cfg)
        .expect_err("one image for two cameras");
    assert!(matches!(err, ProjectError::CameraCount { got: 1, want: 2 }));
}

/// The fused back-projection + projection of `project_frame` against its definition
/// (`back_project` into the depth frame, `project_labels`, `world_from_depth` on the f32
/// depth points), bit for bit, with a stride, depth limits and a negative depth shift
/// (raw values that give no depth), in both modes.
#[test]
fn project_frame_equals_back_project_then_project_labels() {
    let mut cam = simple_camera();
    cam.depth_shift_mm = -700.0;
    cam.world_from_depth = Pose::from_rotation_translation(
        [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]],
        [0.3, -1.2, 2.2],
    )
    .expect("a rotation");
    let f = fixture(cam.clone(), &SIMPLE_SCENE);
    // Some raw values at and below the shift: no depth.
    let mut depth_raw = f.depth_raw.clone();
    for (i, d) in depth_raw.iter_mut().enumerate() {
        if i % 7 == 0 {
            *d = (i % 3) as u16 * 350;
        }
    }
    let rig = Rig {
        cameras: vec![cam.clone()],
    };
    let images = [CameraImages {
        depth_raw: &depth_raw,
        labels: &f.labels,
    }];
    for (stride, depth_min_m, depth_max_m) in
        [(1, 0.0, f64::INFINITY), (2, 0.5, 1.9), (3, 0.1, 0.9)]
    {
        for cfg in [ProjectConfig::naive(), ProjectConfig::default()] {
            let opts = BackProjectOptions {
                depth_min_m,
                depth_max_m,
                stride,
                frame: CloudFrame::World,
            };
            let got = project_frame(&rig, &images, &opts, &cfg).expect("valid frame");
            let depth_opts = BackProjectOptions {
                frame: CloudFrame::Depth,
                ..opts
            };
            let want = back_project(&depth_raw, &cam, 0, &depth_opts).expect("valid");
            assert!(!want.points_m.is_empty());
            assert_eq!(got.origins, want.origins, "stride {stride}");
            let labels = project_labels(
                &cam,
                &want.points_m,
                &want.origins,
                &depth_raw,
                &f.labels,
                &cfg,
            )
            .expect("valid inputs");
            assert_eq!(got.labels, labels, "stride {stride}, {:?}", cfg.mode);
            for (g, p) in got.positions_m.iter().zip(&want.points_m) {
                let w = cam
                    .world_from_depth
                    .transform_point(p.map(f64::from))
                    .map(|c| c as f32);
                assert_eq!(g.map(f32::to_bits), w.map(f32::to_bits));
            }
        }
    }
    // A depth image of the wrong size: the back-projection's error, as before fusing.
    let short = [CameraImages {
        depth_raw: &depth_raw[1..],
        labels: &f.labels,
    }];
    let err = project_frame(
        &rig,
        &short,
        &BackProjectOptions::default(),
        &ProjectConfig::naive(),
    )
    .expect_err("wrong depth size");
    assert!(
        matches!(
            err,
            ProjectError::Calib(bodyseg_calib::CalibError::DepthSize { .. })
        ),
        "{err}"
    );
}

/// Two cameras of [`simple_camera`]'s model at the same place (the second named "second"),
/// each with its own fixture of [`SIMPLE_SCENE`]: `(camera 0, rig, fixture 0, fixture 1)`.
fn two_cameras() -> (RgbdCamera, Rig, Fixture, Fixture) {
    let cam0 = simple_camera();
    let mut cam1 = simple_camera();
    cam1.name = "second".into();
    let rig = Rig {
        cameras: vec![cam0.clone(), cam1.clone()],
    };
    let f0 = fixture(cam0.clone(), &SIMPLE_SCENE);
    let f1 = fixture(cam1, &SIMPLE_SCENE);
    (cam0, rig, f0, f1)
}

/// Projects `images` naively, keeping where the points land.
fn project_naive_keeping_hits(rig: &Rig, images: &[CameraImages<'_>]) -> (LabeledCloud, Hits) {
    let projector = FrameProjector::new(rig).expect("valid rig");
    let (mut cloud, mut hits) = Default::default();
    projector
        .project_frame_keeping_hits(
            images,
            &BackProjectOptions::default(),
            &ProjectConfig::naive(),
            &mut cloud,
            &mut hits,
        )
        .expect("valid frame");
    (cloud, hits)
}

/// `Hits::label_probs_into`: each labelled point reads the probability at its own colour
/// pixel (here: left half of camera 0's image unsure, camera 1's image without
/// probabilities); 1 where that says nothing.
#[test]
fn label_probabilities_follow_each_point_to_its_color_pixel() {
    let (cam0, rig, f0, f1) = two_cameras();
    let labels0 = left_half_unsure(&f0.labels);
    let w = labels0.width as usize;
    let images = [
        CameraImages {
            depth_raw: &f0.depth_raw,
            labels: &labels0,
        },
        CameraImages {
            depth_raw: &f1.depth_raw,
            labels: &f1.labels,
        },
    ];
    // Naive: every point's label is its pixel's, so the probability always applies.
    let (cloud, hits) = project_naive_keeping_hits(&rig, &images);
    let mut probs = Vec::new();
    hits.label_probs_into(&cloud, &images, &mut probs);
    assert_eq!(probs.len(), cloud.len());
    let n0 = f0.points.len();
    let (mut unsure, mut sure) = (0, 0);
    for (i, p) in f0.points.iter().enumerate() {
        if cloud.labels[i].is_unknown() {
            assert_eq!(probs[i], 1.0, "unknown point {i}");
            continue;
        }
        let uv = cam0
            .color
            .project([f64::from(p[0]) - 0.05, f64::from(p[1]), f64::from(p[2])])
            .expect("in front");
        let left = (uv[0].round() as usize) < w / 2;
        assert_eq!(probs[i], if left { 0.3 } else { 0.9 }, "point {i}");
        if left { unsure += 1 } else { sure += 1 }
    }
    assert!(unsure > 100 && sure > 100, "{unsure} unsure, {sure} sure");
    assert!(probs[n0..].iter().all(|&p| p == 1.0), "no probabilities: 1");
}

/// `Hits::colors_of`: each point takes the colour of its own colour pixel in its own
/// camera's image (here: camera 0's left half red, right half green; camera 1's blue).
#[test]
fn point_colors_are_read_at_each_points_color_pixel() {
    let (cam0, rig, f0, f1) = two_cameras();
    let images = [f0.images(), f1.images()];
    let (w, h) = (f0.labels.width, f0.labels.height);
    let (red, green, blue) = ([200, 10, 10], [10, 200, 10], [10, 10, 200]);
    let rgb0: Vec<u8> = (0..h)
        .flat_map(|_| (0..w).flat_map(|u| if u < w / 2 { red } else { green }))
        .collect();
    let color0 = bodyseg_core::RgbImage::new(w, h, rgb0).expect("size");
    let color1 = bodyseg_core::RgbImage::new(w, h, blue.repeat((w * h) as usize)).expect("size");
    let (cloud, hits) = project_naive_keeping_hits(&rig, &images);
    let colors = hits.colors_of(&cloud, &[&color0, &color1]);
    assert_eq!(colors.len(), cloud.len());
    let n0 = f0.points.len();
    let (mut left, mut right) = (0, 0);
    for (i, p) in f0.points.iter().enumerate() {
        if cloud.labels[i].is_unknown() {
            continue; // no hit, or a hit on an unlabelled pixel
        }
        let uv = cam0
            .color
            .project([f64::from(p[0]) - 0.05, f64::from(p[1]), f64::from(p[2])])
            .expect("in front");
        let is_left = (uv[0].round() as u32) < w / 2;
        assert_eq!(colors[i], if is_left { red } else { green }, "point {i}");
        if is_left { left += 1 } else { right += 1 }
    }
    assert!(left > 100 && right > 100, "{left} left, {right} right");
    assert!(
        (n0..cloud.len()).all(|i| cloud.labels[i].is_unknown() || colors[i] == blue),
        "camera 1's points: its image's blue"
    );
    // A camera without an image: black.
    assert!(
        hits.colors_of(&cloud, &[&color0])[n0..]
            .iter()
            .all(|&c| c == [0; 3])
    );
}

/// FNV-1a over the little-endian bytes of a word.
fn fnv(h: &mut u64, word: u64) {
    for b in word.to_le_bytes() {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x0100_0000_01b3);
    }
}

/// Issue 28 gave the camera model a second distortion model; for Brown-Conrady cameras
/// every step must give the bits it gave before. The real Kinect fixture (f64
/// undistortion of every depth and colour pixel, back-projection, f32 colour look-up in
/// naive and DSA mode, f64 projection) hashed to this value on main at 4d8781f
/// (before the change): the same test run there.
#[test]
fn kinect_projection_bits_are_those_of_main() {
    let f = kinect_fixture();
    let mut h = 0xcbf2_9ce4_8422_2325_u64;
    for p in &f.points {
        for c in p {
            fnv(&mut h, u64::from(c.to_bits()));
        }
    }
    for &d in &f.depth_raw {
        fnv(&mut h, u64::from(d));
    }
    for l in &f.labels.labels {
        fnv(&mut h, u64::from(l.id()));
    }
    for cfg in [ProjectConfig::naive(), ProjectConfig::default()] {
        let (labels, _) = run(&f, &f.labels, &cfg);
        for l in labels {
            fnv(&mut h, u64::from(l.id()));
        }
    }
    for p in &f.points {
        let p_color = f.camera.color_from_depth.transform_point(p.map(f64::from));
        let uv = f.camera.color.project(p_color).expect("in front");
        fnv(&mut h, uv[0].to_bits());
        fnv(&mut h, uv[1].to_bits());
    }
    println!(
        "kinect projection hash {h:#018x} over {} points",
        f.points.len()
    );
    assert_eq!(h, KINECT_PROJECTION_HASH_MAIN, "{h:#018x}");
}

/// The hash [`kinect_projection_bits_are_those_of_main`] printed on main at 4d8781f.
const KINECT_PROJECTION_HASH_MAIN: u64 = 0x71d9_5be7_4dbf_38e9;
