//! Guards the back-projection half of the per-frame budget (issue 4: back-projection +
//! DSA projection of one 3-camera Kinect v2 frame ≤ 10 ms on 2 cores): three 512×424 depth
//! images with the real iai_kinect2 intrinsics (`shared/data/iai_kinect2/196605135147`,
//! distortion included), a synthetic scene of a floor plane and a box with ~15% holes,
//! back-projected into one world-frame cloud with origins by [`RigBackProjector`]. Measured
//! on a 2-thread rayon pool (the budget's machine), on rayon's default pool, and
//! sequentially (one camera after another, one thread) for the parallel speed-up.
//! Elements = depth pixels (3 × 512 × 424).

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use std::hint::black_box;

use bodyseg_calib::{BackProjectOptions, RigBackProjector, testing};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    let rig = testing::bench_ring_rig();
    let projector = RigBackProjector::new(&rig).expect("a valid rig");
    let images = testing::bench_depth_images(&rig);
    let depths: Vec<&[u16]> = images.iter().map(Vec::as_slice).collect();
    let opts = BackProjectOptions::default();
    let pixels: usize = rig.cameras.iter().map(|c| c.depth.num_pixels()).sum();
    let valid = images.iter().flatten().filter(|&&d| d != 0).count();
    eprintln!(
        "back_project bench: {pixels} depth pixels, {:.1}% valid",
        100.0 * valid as f64 / pixels as f64
    );
    let size = testing::bench_frame_size(&rig);

    let mut group = c.benchmark_group("back_project_rig_world");
    group.throughput(Throughput::Elements(pixels as u64));
    let two = testing::two_thread_pool();
    group.bench_with_input(
        BenchmarkId::new("rayon_2_threads", &size),
        &depths,
        |b, d| {
            b.iter(|| two.install(|| projector.back_project(black_box(d), &opts).expect("ok")));
        },
    );
    group.bench_with_input(BenchmarkId::new("rayon_default", &size), &depths, |b, d| {
        b.iter(|| projector.back_project(black_box(d), &opts).expect("ok"));
    });
    group.bench_with_input(BenchmarkId::new("sequential", &size), &depths, |b, d| {
        b.iter(|| {
            projector
                .projectors()
                .iter()
                .zip(black_box(d))
                .map(|(p, img)| p.back_project_sequential(img, &opts).expect("ok"))
                .collect::<Vec<_>>()
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
