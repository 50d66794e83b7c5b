//! Guards issue 6's budget: labels-mode box finding takes ≤ 5 ms per frame of three
//! Kinect v2 cameras with two people (the handover preset: every depth pixel of the three
//! cameras back-projected, ≈ 0.5 M points, labelled with the per-pixel truth). Geometry
//! mode is measured beside it, on positions only and with colours (`geometry_colours`:
//! made-up colours per class, as the crate may not sample camera images; the colour split
//! runs a second Dijkstra over each cluster with something nobody's beside its people).
//!
//! `cargo bench -p bodyseg-people --bench boxes`

#![allow(missing_docs)] // criterion_group! generates undocumented items.

use bodyseg_core::LabeledCloud;
use bodyseg_people::{BoxMode, BoxesConfig, find_boxes};
use bodyseg_synth::{Synth, preset};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

/// Frame `index` of the handover preset (seed 7): every depth pixel of the three cameras
/// back-projected into the world frame, labelled with the frame's per-depth-pixel truth
/// (this crate may not use the projection; the point count is the projected cloud's).
fn handover_cloud(index: usize) -> LabeledCloud {
    let synth = Synth::new(preset("handover").expect("preset"), 7).expect("synth");
    synth.truth_cloud(&synth.frame(index)).expect("truth cloud")
}

fn bench(c: &mut Criterion) {
    let cloud = handover_cloud(10);
    let mut group = c.benchmark_group("find_boxes");
    group.throughput(Throughput::Elements(cloud.len() as u64));
    for mode in [BoxMode::Labels, BoxMode::Geometry] {
        let cfg = BoxesConfig {
            mode,
            ..BoxesConfig::default()
        };
        let found = find_boxes(&cloud, &cfg).expect("boxes");
        eprintln!(
            "{}: {} points, {} boxes",
            mode.name(),
            cloud.len(),
            found.boxes.len()
        );
        group.bench_with_input(
            BenchmarkId::new(mode.name(), cloud.len()),
            &cloud,
            |b, cloud| b.iter(|| find_boxes(black_box(cloud), &cfg)),
        );
    }
    // Skin on heads and arms, a shirt, trousers; the background grey, orange where x > 0.5.
    let mut colored = cloud.clone();
    colored.colors = Some(
        cloud
            .labels
            .iter()
            .zip(&cloud.positions_m)
            .map(|(l, p)| match l.id() {
                1 | 4 => [200, 150, 120],
                2 | 3 => [40, 60, 160],
                5 | 6 => [60, 50, 40],
                _ if p[0] > 0.5 => [215, 115, 15],
                _ => [120, 120, 120],
            })
            .collect(),
    );
    let cfg = BoxesConfig {
        mode: BoxMode::Geometry,
        ..BoxesConfig::default()
    };
    group.bench_with_input(
        BenchmarkId::new("geometry_colours", colored.len()),
        &colored,
        |b, cloud| b.iter(|| find_boxes(black_box(cloud), &cfg)),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
