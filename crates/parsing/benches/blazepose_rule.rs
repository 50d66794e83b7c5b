//! Guards the labelling half of issue 29's time budget (≤ 80 ms per 960×540 view with 2
//! people, 2 threads, `full` model): `blazepose::label_person` + `merge_people` for two
//! people whose ROIs are 500 px squares in a 960×540 view (one thread, no model: the
//! model's two or four inferences per view are measured by
//! `scripts/blazepose_prototype.py --bench`). Input: an upright figure scaled ×3.2
//! (≈ 450 px tall), a graded mask, two copies side by side.

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_parsing::blazepose::{
    DecodedPose, INPUT, NUM_LANDMARKS, Roi, RuleConfig, label_person, landmark, merge_people,
};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

#[path = "../src/blazepose/figure.rs"]
mod figure;

const W: usize = 960;
const H: usize = 540;

/// The figure of the unit tests (image px, 100×160 frame), scaled by `k` and moved by
/// `shift`, with a graded mask on a ROI of side `side`.
fn person(k: f64, shift: [f64; 2], side: f64) -> DecodedPose {
    let mut xy = figure::upright_figure_xy();
    for p in &mut xy {
        *p = [p[0] * k + shift[0], p[1] * k + shift[1]];
    }
    let mut mask = vec![0.0f32; INPUT * INPUT];
    for j in 0..INPUT {
        for i in 0..INPUT {
            let m = 1.2 - ((i as f64 + 0.5 - 128.0) / 70.0).hypot((j as f64 + 0.5 - 128.0) / 120.0);
            mask[j * INPUT + i] = m.clamp(0.0, 1.0) as f32;
        }
    }
    figure::sure_pose(xy, [50.0 * k + shift[0], 80.0 * k + shift[1]], side, mask)
}

fn rule(c: &mut Criterion) {
    let people = [
        person(3.2, [100.0, 10.0], 500.0),
        person(3.2, [520.0, 10.0], 500.0),
    ];
    let cfg = RuleConfig::default();
    let mut group = c.benchmark_group("blazepose_rule");
    group.throughput(Throughput::Elements((W * H) as u64));
    group.bench_function(BenchmarkId::new("label_two_people", "960x540"), |b| {
        b.iter(|| {
            let labelled: Vec<_> = people
                .iter()
                .filter_map(|p| label_person(black_box(p), &cfg, W, H))
                .collect();
            black_box(merge_people(W, H, &labelled))
        })
    });
    group.finish();
}

criterion_group!(benches, rule);
criterion_main!(benches);
