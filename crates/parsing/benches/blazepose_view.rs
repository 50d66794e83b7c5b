//! Guards issue 29's time budget: one 960×540 view with 2 people through
//! [`BlazePoseSegmenter`] (`models/blazepose_full.onnx`, default options: the two regions
//! at once, each on its own single-threaded session): per person the crop, the landmark
//! model (the first ROI and the refinement pass), decoding, the landmarks + mask → classes
//! rule, and merging the people; target ≤ 80 ms. Input: frame 0 of the `robot_cell` synth
//! preset, seed 1, camera 0, the regions of its two largest people (their pixels' bounding
//! boxes in synth's per-pixel person ids, as a box found from depth would give).
//! `blazepose_rule` measures the labelling alone on two 500 px people.
//!
//! Needs `scripts/setup_onnxruntime.sh` (or ORT_DYLIB_PATH) and the committed model.

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_parsing::{BlazePoseOptions, BlazePoseSegmenter, BlazePoseVariant};
use bodyseg_parsing::{Segmenter, ViewInput};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

#[path = "../tests/common/runtime.rs"]
mod runtime;
use runtime::{root, runtime_library};
#[path = "../tests/common/two_people.rs"]
mod two_people;
use two_people::view;

fn segmenter(variant: BlazePoseVariant) -> BlazePoseSegmenter {
    let library = runtime_library();
    let model = root().join(format!("models/blazepose_{}.onnx", variant.name()));
    let bytes = std::fs::read(&model).expect("committed BlazePose model");
    BlazePoseSegmenter::new(&library, &bytes, &model, &BlazePoseOptions::default())
        .expect("ONNX Runtime (scripts/setup_onnxruntime.sh) and the model")
}

fn blazepose(c: &mut Criterion) {
    let (image, regions) = view();
    assert_eq!(regions.len(), 2, "two people in view");
    let mut group = c.benchmark_group("blazepose_view_960x540");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);
    for variant in [BlazePoseVariant::Full, BlazePoseVariant::Lite] {
        let mut seg = segmenter(variant);
        group.bench_function(BenchmarkId::new("two_people", variant.name()), |b| {
            b.iter(|| {
                let input = ViewInput {
                    camera: "cam0",
                    frame: "000000",
                    image: Some(&image),
                    recorded: None,
                    regions: Some(&regions),
                };
                black_box(seg.segment(black_box(&[input])).expect("segment"))
            })
        });
        let runs = seg.runs();
        eprintln!("{}: {runs} landmark-model runs in all", variant.name());
    }
    group.finish();
}

criterion_group!(benches, blazepose);
criterion_main!(benches);
