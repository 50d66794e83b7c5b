//! Guards the speed of label-aware DBSCAN and of the whole refinement on human-shaped
//! clouds of 30k, 100k and 300k points (eps 0.05 m, min_points 40, 7 labels), two kinds:
//! `*_synth`, sensor-like clouds of `bodyseg-synth` (one person seen by Kinect-v2-like
//! depth cameras, flying pixels on, the parser's label errors; `common/synth_cloud.rs`),
//! and the capsule clouds of `bodyseg-testkit` (groups without a suffix). Targets (issue
//! 30, single-threaded, synth cloud at 100k): the whole refinement (M-R-N) of one person
//! ≤ 12 ms; ratios against peers are printed by `scripts/bench_dbscan_peers.py`. Run
//! single-threaded with `RAYON_NUM_THREADS=1 taskset -c 0 cargo bench -p bodyseg-refine`;
//! `refine_synth_steps` splits the synth 100k refinement by steps (M, N, M-R-N). `refine_modes` prices
//! the modes beside the paper's (issue 8: contact graph, coverage tree, weighted noise,
//! and all three; probability noise and its wide vote for doubted labels with made-up
//! parser probabilities, doubted in strips) on the 100k cloud; `foreign_colors` the
//! foreign-color step alone on it; `smooth_labels` the 5 cm smoothing alone on it.

#![allow(missing_docs)] // criterion_group! generates undocumented items.

use bodyseg_core::{LabeledCloud, PersonBox};
use bodyseg_refine::Steps;
use bodyseg_refine::color::drop_foreign_arms;
use bodyseg_refine::{
    DbscanParams, GraphMode, NoiseMode, PointEvidence, RefineConfig, TreeMode, dbscan, refine,
    refine_variants_with, smooth_labels,
};
use bodyseg_testkit::human_cloud;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

/// The same allocator as the `bodyseg` binary.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[path = "common/synth_cloud.rs"]
mod synth_cloud;

#[path = "common/alloc.rs"]
mod alloc;

#[path = "common/evidence.rs"]
mod evidence;

const SIZES: [usize; 3] = [30_000, 100_000, 300_000];
const SEED: u64 = 1;

/// The synth cloud of `n` points (seed [`SEED`]).
fn synth(n: usize) -> synth_cloud::SynthPersonCloud {
    synth_cloud::synth_person_cloud(n, SEED).expect("the synth preset renders")
}

/// Label-aware DBSCAN as the paper runs it: eps 0.05 m, min_points 40, labels never mix.
const PARAMS: DbscanParams = DbscanParams {
    eps_m: 0.05,
    min_points: 40,
    label_penalty_m: f32::INFINITY,
};

/// Per cloud size, 20 samples, throughput in points: group `dbscan{suffix}` times
/// [`PARAMS`]' DBSCAN, then group `refine{suffix}` the default refinement of the one person
/// in `clouds` = (size asked, cloud, the person's box).
fn dbscan_and_refine(
    c: &mut Criterion,
    suffix: &str,
    clouds: &[(usize, &LabeledCloud, &PersonBox)],
) {
    let mut g = c.benchmark_group(format!("dbscan{suffix}"));
    g.sample_size(20);
    for &(n, cloud, _) in clouds {
        g.throughput(Throughput::Elements(cloud.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(n), cloud, |b, cloud| {
            b.iter(|| {
                dbscan(
                    black_box(&cloud.positions_m),
                    black_box(&cloud.labels),
                    &PARAMS,
                )
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group(format!("refine{suffix}"));
    g.sample_size(20);
    let cfg = RefineConfig::default();
    for &(n, cloud, person_box) in clouds {
        let boxes = [person_box.clone()];
        g.throughput(Throughput::Elements(cloud.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(n), cloud, |b, cloud| {
            b.iter(|| refine(black_box(cloud), &boxes, &cfg))
        });
    }
    g.finish();
}

fn bench_synth(c: &mut Criterion) {
    // As the binary: freed memory stays with the allocator (`targets` runs this first).
    alloc::keep_freed_memory();
    let clouds: Vec<_> = SIZES.iter().map(|&n| (n, synth(n))).collect();
    for (n, p) in &clouds {
        eprintln!(
            "synth cloud {n}: {} cameras, {} flying pixels, {} labels unlike the truth",
            p.cameras, p.flying, p.mislabelled
        );
    }
    let sized: Vec<_> = clouds
        .iter()
        .map(|(n, p)| (*n, &p.cloud, &p.person_box))
        .collect();
    dbscan_and_refine(c, "_synth", &sized);
    let mut g = c.benchmark_group("refine_synth_steps");
    g.sample_size(20);
    let (n, p) = &clouds[1];
    let boxes = [p.person_box.clone()];
    g.throughput(Throughput::Elements(*n as u64));
    for steps in ["M", "N", "M-R-N"] {
        let cfg = RefineConfig {
            steps: steps.parse::<Steps>().expect("a step name"),
            ..RefineConfig::default()
        };
        g.bench_with_input(BenchmarkId::new(steps, n), p, |b, p| {
            b.iter(|| refine(black_box(&p.cloud), &boxes, &cfg))
        });
    }
    g.finish();
}

/// The capsule clouds of `bodyseg-testkit`: groups `dbscan` and `refine`.
fn bench_testkit(c: &mut Criterion) {
    let clouds: Vec<_> = SIZES.iter().map(|&n| (n, human_cloud(n, SEED))).collect();
    let sized: Vec<_> = clouds
        .iter()
        .map(|(n, p)| (*n, &p.cloud, &p.person_box))
        .collect();
    dbscan_and_refine(c, "", &sized);
}

fn bench_refine_modes(c: &mut Criterion) {
    let mut g = c.benchmark_group("refine_modes");
    g.sample_size(20);
    let n = 100_000;
    let p = human_cloud(n, SEED);
    let boxes = [p.person_box.clone()];
    let paper = RefineConfig::default();
    let modes = [
        ("paper", paper.clone()),
        (
            "contact",
            RefineConfig {
                graph: GraphMode::Contact,
                ..paper.clone()
            },
        ),
        (
            "coverage",
            RefineConfig {
                tree: TreeMode::Coverage,
                ..paper.clone()
            },
        ),
        (
            "weighted",
            RefineConfig {
                noise: NoiseMode::Weighted,
                ..paper.clone()
            },
        ),
        (
            "all",
            RefineConfig {
                graph: GraphMode::Contact,
                tree: TreeMode::Coverage,
                noise: NoiseMode::Weighted,
                ..paper.clone()
            },
        ),
    ];
    g.throughput(Throughput::Elements(p.cloud.len() as u64));
    for (name, cfg) in &modes {
        g.bench_with_input(BenchmarkId::new(*name, n), &p, |b, p| {
            b.iter(|| refine(black_box(&p.cloud), &boxes, cfg))
        });
    }
    // Probability noise needs the parser's probabilities (made up, in strips).
    let probs = evidence::strip_probs(&p.cloud.positions_m);
    let evidence = PointEvidence {
        label_probs: Some(&probs),
        ..Default::default()
    };
    let probability = evidence::probability_config(&paper);
    let improved = RefineConfig {
        noise_doubt_radius_m: 0.15,
        remove_through_noise: true,
        ..probability.clone()
    };
    for (name, cfg) in [("probability", &probability), ("improved", &improved)] {
        g.bench_with_input(BenchmarkId::new(name, n), &p, |b, p| {
            b.iter(|| {
                refine_variants_with(
                    black_box(&p.cloud),
                    evidence,
                    &boxes,
                    cfg,
                    &[cfg.steps],
                    false,
                )
            })
        });
    }
    g.finish();
}

/// `foreign_color_density`'s step alone on the 100k cloud: head skin, torso shirt, arms in
/// shirt or skin with every tenth arm point orange (an object to drop).
fn bench_foreign_colors(c: &mut Criterion) {
    let mut g = c.benchmark_group("foreign_colors");
    let n = 100_000;
    let p = human_cloud(n, SEED);
    let colors: Vec<[u8; 3]> = p
        .cloud
        .labels
        .iter()
        .enumerate()
        .map(|(i, l)| match l.id() {
            1 => [200, 150, 120],
            3 | 4 if i % 10 == 0 => [215, 115, 15],
            3 | 4 if i % 2 == 0 => [200, 150, 120],
            _ => [40, 60, 160],
        })
        .collect();
    g.throughput(Throughput::Elements(n as u64));
    g.bench_with_input(BenchmarkId::new("drop_foreign_arms", n), &p, |b, p| {
        b.iter(|| {
            let mut labels = p.cloud.labels.clone();
            drop_foreign_arms(
                black_box(&mut labels),
                &colors,
                0.02,
                bodyseg_core::Label::BACKGROUND,
            );
            labels
        })
    });
    g.finish();
}

/// `smooth_radius_m`'s step alone (5 cm, as configs/benchmarks/improved.toml) on the 100k
/// cloud.
fn bench_smooth(c: &mut Criterion) {
    let mut g = c.benchmark_group("smooth_labels");
    g.sample_size(10);
    let n = 100_000;
    let p = human_cloud(n, SEED);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_with_input(BenchmarkId::from_parameter(n), &p, |b, p| {
        b.iter(|| smooth_labels(black_box(&p.cloud.positions_m), &p.cloud.labels, 0.05))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench_synth, bench_testkit, bench_refine_modes, bench_foreign_colors, bench_smooth
}
criterion_main!(benches);
