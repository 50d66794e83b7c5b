//! Guards issue 29's time budget: one 960×540 view with 2 people through
//! [`BlazePoseSegmenter`] (`models/blazepose_full.onnx`, default options: the two regions
//! at once, each on its own single-threaded session): per person the crop, the landmark
//! model (the first ROI on the model cut at its mask output, the refinement pass on the
//! full model), decoding, the landmarks + mask → classes
//! rule, and merging the people; target ≤ 80 ms. `full_bodypix` (the default,
//! `parsing.body_parts = "bodypix"`) adds BodyPix on each region (crop longer side 384;
//! `full_bodypix448`: 448) on the same worker and the fusion; `full` is `landmarks`. Input: frame 0 of the `robot_cell` synth
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

/// The segmenter of `variant`, with BodyPix's parts at crop side `bodypix` when given.
fn segmenter(variant: BlazePoseVariant, bodypix: Option<usize>) -> BlazePoseSegmenter {
    let library = runtime_library();
    let model = root().join(format!("models/blazepose_{}.onnx", variant.name()));
    let bytes = std::fs::read(&model).expect("committed BlazePose model");
    let mut options = BlazePoseOptions::default();
    options.bodypix.long_side = bodypix.unwrap_or(options.bodypix.long_side);
    let seg = BlazePoseSegmenter::new(&library, &bytes, &model, &options)
        .expect("ONNX Runtime (scripts/setup_onnxruntime.sh) and the model");
    if bodypix.is_none() {
        return seg;
    }
    let model = root().join("models/bodypix_mobilenet_v1_075_quant.onnx");
    let bytes = std::fs::read(&model).expect("committed BodyPix model");
    seg.with_bodypix(&library, &bytes, &model)
        .expect("the BodyPix model")
}

fn blazepose(c: &mut Criterion) {
    let (image, regions) = view();
    assert_eq!(regions.len(), 2, "two people in view");
    let mut group = c.benchmark_group("blazepose_view_960x540");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);
    let setups = [
        ("full_bodypix", BlazePoseVariant::Full, Some(384)),
        ("full_bodypix448", BlazePoseVariant::Full, Some(448)),
        ("full", BlazePoseVariant::Full, None),
        ("lite", BlazePoseVariant::Lite, None),
    ];
    for (name, variant, bodypix) in setups {
        let mut seg = segmenter(variant, bodypix);
        group.bench_function(BenchmarkId::new("two_people", name), |b| {
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
        eprintln!("{name}: {runs} landmark-model runs in all");
    }
    group.finish();
}

criterion_group!(benches, blazepose);
criterion_main!(benches);
