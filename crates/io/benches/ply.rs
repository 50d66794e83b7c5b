//! Guards the speed of the labelled-PLY reader and writer on a 300k-point cloud (a
//! 3-camera Kinect frame holds about that many points): parsing should stay within a few
//! times the cost of copying the same bytes. `cargo bench -p bodyseg-io`.
#![allow(missing_docs)] // criterion_group! generates undocumented items.

use bodyseg_io::{PlyWriteOptions, parse_ply, ply_bytes};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;

fn bench_ply(c: &mut Criterion) {
    let cloud = bodyseg_testkit::human_cloud(300_000, 1).cloud;
    let path = Path::new("bench.ply");
    let opts = PlyWriteOptions::default();
    let bytes = ply_bytes(&cloud, &opts, path).expect("a valid cloud encodes");
    let mut g = c.benchmark_group("ply");
    g.sample_size(20);
    g.throughput(Throughput::Elements(cloud.len() as u64));
    g.bench_with_input(
        BenchmarkId::new("parse_binary", cloud.len()),
        &bytes,
        |b, bytes| b.iter(|| parse_ply(black_box(bytes), path)),
    );
    g.bench_with_input(
        BenchmarkId::new("encode_binary", cloud.len()),
        &cloud,
        |b, cloud| b.iter(|| ply_bytes(black_box(cloud), &opts, path)),
    );
    g.bench_with_input(
        BenchmarkId::new("copy_bytes_reference", cloud.len()),
        &bytes,
        |b, bytes| b.iter(|| black_box(bytes).to_vec()),
    );
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench_ply
}
criterion_main!(benches);
