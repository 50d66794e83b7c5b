//! Guards the per-frame budget of issue 4: back-projection + DSA projection of one
//! 3-camera Kinect v2 frame ≤ 10 ms on 2 cores. Three 512×424 depth images with the real
//! iai_kinect2 intrinsics (`shared/data/iai_kinect2/196605135147`, distortion included) of
//! a floor plane and a box (~15% holes, as in `bodyseg-calib`'s `back_project` bench), and
//! 1920×1080 label images made by splatting the scene's truth (box = two body parts,
//! floor = background) into the colour image. Measures [`FrameProjector::project_frame`]
//! (back-projection included, world-frame output) in naive and DSA mode on a 2-thread
//! rayon pool (the budget's machine), and DSA on rayon's default pool; the `_reused`
//! cases measure [`FrameProjector::project_frame_into`] with the output cloud of the
//! previous frame reused, as a pipeline worker streaming frames does (no fresh ~12 MB
//! allocation and page faults per frame). `dsa_rational_rayon_2_threads_reused` is the
//! same frame with the colour sensors' distortion given as OpenCV's rational model (the
//! Brown-Conrady coefficients and a small k4): the cost of the radial denominator in the
//! colour look-up (Azure Kinect cameras).
//! Elements = depth pixels (3 × 512 × 424).

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use std::hint::black_box;

use bodyseg_calib::{BackProjectOptions, CloudFrame, Distortion, RgbdCamera, testing};
use bodyseg_core::{Label, LabelImage};
use bodyseg_project::{CameraImages, FrameProjector, ProjectConfig};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The box's depth pixels (u range, v range) in every camera's depth image.
const BOX_U: std::ops::Range<u32> = testing::TEST_BOX_U;
const BOX_V: std::ops::Range<u32> = testing::TEST_BOX_V;

/// The colour camera's label image of the truth: every depth point of the box splatted
/// (5×5 colour pixels, closing the gaps between depth samples) with its part (upper half
/// of the box class 1, lower half class 2), background elsewhere.
fn label_image(camera: &RgbdCamera, depth_raw: &[u16]) -> LabelImage {
    let opts = BackProjectOptions {
        frame: CloudFrame::Depth,
        ..Default::default()
    };
    let cloud = bodyseg_calib::back_project(depth_raw, camera, 0, &opts).expect("bench depth");
    let (w, h) = (camera.color.width as i64, camera.color.height as i64);
    let mut image = LabelImage::filled(camera.color.width, camera.color.height, Label::BACKGROUND);
    let depth_w = camera.depth.width;
    let split_v = (BOX_V.start + BOX_V.end) / 2;
    for (p, o) in cloud.points_m.iter().zip(&cloud.origins) {
        let (u, v) = (o.pixel % depth_w, o.pixel / depth_w);
        if !(BOX_U.contains(&u) && BOX_V.contains(&v)) {
            continue;
        }
        let part = Label::from_id(if v < split_v { 1 } else { 2 }).expect("a class id");
        let p_color = camera.color_from_depth.transform_point(p.map(f64::from));
        let Some(uv) = camera.color.project(p_color) else {
            continue;
        };
        let (uc, vc) = (uv[0].round() as i64, uv[1].round() as i64);
        for vn in (vc - 2).max(0)..=(vc + 2).min(h - 1) {
            for un in (uc - 2).max(0)..=(uc + 2).min(w - 1) {
                image.labels[(vn * w + un) as usize] = part;
            }
        }
    }
    image
}

fn bench(c: &mut Criterion) {
    let rig = testing::bench_ring_rig();
    let projector = FrameProjector::new(&rig).expect("a valid rig");
    let depths = testing::bench_depth_images(&rig);
    let labels: Vec<LabelImage> = rig
        .cameras
        .iter()
        .zip(&depths)
        .map(|(cam, d)| label_image(cam, d))
        .collect();
    let images: Vec<CameraImages<'_>> = depths
        .iter()
        .zip(&labels)
        .map(|(d, l)| CameraImages {
            depth_raw: d,
            labels: l,
        })
        .collect();
    let opts = BackProjectOptions::default();
    let naive = ProjectConfig::naive();
    let dsa = ProjectConfig::default();

    let pixels: usize = rig.cameras.iter().map(|c| c.depth.num_pixels()).sum();
    let valid = depths.iter().flatten().filter(|&&d| d != 0).count();
    let body = labels
        .iter()
        .flat_map(|l| &l.labels)
        .filter(|l| l.is_body())
        .count();
    let cloud = projector
        .project_frame(&images, &opts, &dsa)
        .expect("bench frame");
    let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
    eprintln!(
        "project bench: {pixels} depth pixels, {:.1}% valid; {:.1}% body colour pixels; \
         DSA: {} points, {:.1}% unknown",
        100.0 * valid as f64 / pixels as f64,
        100.0 * body as f64 / labels.iter().map(LabelImage::num_pixels).sum::<usize>() as f64,
        cloud.labels.len(),
        100.0 * unknown as f64 / cloud.labels.len() as f64,
    );
    let size = testing::bench_frame_size(&rig);

    let mut group = c.benchmark_group("project_frame");
    group.throughput(Throughput::Elements(pixels as u64));
    let two = testing::two_thread_pool();
    for (name, cfg) in [("naive", &naive), ("dsa", &dsa)] {
        group.bench_with_input(
            BenchmarkId::new(format!("{name}_rayon_2_threads"), &size),
            &images,
            |b, imgs| {
                b.iter(|| {
                    two.install(|| {
                        projector
                            .project_frame(black_box(imgs), &opts, cfg)
                            .expect("ok")
                    })
                });
            },
        );
    }
    for (name, cfg) in [("naive", &naive), ("dsa", &dsa)] {
        let mut cloud = bodyseg_core::LabeledCloud::default();
        group.bench_with_input(
            BenchmarkId::new(format!("{name}_rayon_2_threads_reused"), &size),
            &images,
            |b, imgs| {
                b.iter(|| {
                    two.install(|| {
                        projector
                            .project_frame_into(black_box(imgs), &opts, cfg, &mut cloud)
                            .expect("ok");
                    });
                    black_box(cloud.len())
                });
            },
        );
    }
    let mut rational_rig = rig.clone();
    for cam in &mut rational_rig.cameras {
        let mut k = cam.color.distortion.rational_coefficients();
        k[5] = 1e-3;
        cam.color.distortion = Distortion::Rational(k);
    }
    let rational = FrameProjector::new(&rational_rig).expect("a valid rig");
    let mut cloud = bodyseg_core::LabeledCloud::default();
    group.bench_with_input(
        BenchmarkId::new("dsa_rational_rayon_2_threads_reused", &size),
        &images,
        |b, imgs| {
            b.iter(|| {
                two.install(|| {
                    rational
                        .project_frame_into(black_box(imgs), &opts, &dsa, &mut cloud)
                        .expect("ok");
                });
                black_box(cloud.len())
            });
        },
    );
    group.bench_with_input(
        BenchmarkId::new("dsa_rayon_default", &size),
        &images,
        |b, imgs| {
            b.iter(|| {
                projector
                    .project_frame(black_box(imgs), &opts, &dsa)
                    .expect("ok")
            });
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
