//! Guards the parsing issue's figure: 2D parsing of one 960×540 colour view with the
//! bundled model (`models/bodyseg_parser_small.onnx`) on 2 ONNX Runtime threads, whole
//! chain (SCHP pre-processing, inference, logits upsampling, warp back, softmax/argmax).
//! Also 3 views in one batch (a frame of the default 3-camera rig), and SCHP's pre-processing
//! of one view alone (warp into the 512×512 input, rounded to whole grey levels, and
//! normalisation), which an SCHP export runs before its ~1 s network. Input: frame 0 of the
//! `robot_cell` synth preset, seed 1 (three people, table, robot arm).
//!
//! Needs `scripts/setup_onnxruntime.sh` (or ORT_DYLIB_PATH) and the bundled model.

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_core::RgbImage;
use bodyseg_parsing::transform::{InputTransform, normalize_to_chw, warp_to_input};
use bodyseg_parsing::{ModelSpec, OnnxOptions, OnnxSegmenter, Segmenter, ViewInput};
use bodyseg_synth::{Synth, preset};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;

#[path = "../tests/common/runtime.rs"]
mod runtime;
use runtime::{root, runtime_library};

fn segmenter() -> OnnxSegmenter {
    let library = runtime_library();
    let model = root().join("models/bodyseg_parser_small.onnx");
    let bytes = std::fs::read(&model).expect("bundled model (scripts/train_parser.py)");
    let text = std::fs::read_to_string(model.with_extension("json")).expect("its sidecar");
    let spec = ModelSpec::from_json(&text, &model.with_extension("json")).expect("valid sidecar");
    let options = OnnxOptions {
        threads: 2,
        keep_class_probs: false,
    };
    OnnxSegmenter::new(&library, &bytes, &model, spec, &options)
        .expect("ONNX Runtime (scripts/setup_onnxruntime.sh) and the bundled model")
}

/// The colour views of frame 0 of `robot_cell`, seed 1 (960 wide).
fn views() -> Vec<RgbImage> {
    let config = preset("robot_cell").expect("preset");
    let frame = Synth::new(config, 1).expect("synth").frame(0);
    frame
        .cameras
        .iter()
        .map(|cam| {
            let w = 960;
            let h = (cam.color.len() / 3 / w) as u32;
            RgbImage::new(w as u32, h, cam.color.clone()).expect("960 wide RGB")
        })
        .collect()
}

fn preprocess(c: &mut Criterion) {
    let image = views().swap_remove(0);
    // SCHP's sidecar as scripts/export_schp_onnx.py writes it.
    let sidecar = r#"{"input_size": [512, 512], "channel_order": "BGR",
        "mean": [0.406, 0.456, 0.485], "std": [0.225, 0.224, 0.229],
        "class_names": ["background", "head", "torso", "upper_arms", "lower_arms",
                        "upper_legs", "lower_legs"],
        "output_stride": 4, "align_corners": true}"#;
    let spec = ModelSpec::from_json(sidecar, Path::new("schp.json")).expect("SCHP sidecar");
    let t = InputTransform::new(image.width, image.height, spec.input_side());
    let mut group = c.benchmark_group("preprocess_960x540_to_512");
    group.throughput(Throughput::Elements(1));
    group.bench_function(BenchmarkId::new("views", 1), |b| {
        b.iter(|| {
            let mut input = Vec::with_capacity(3 * 512 * 512);
            normalize_to_chw(&warp_to_input(black_box(&image), &t), &spec, &mut input);
            black_box(input)
        })
    });
    group.finish();
}

fn inference(c: &mut Criterion) {
    let images = views();
    let mut seg = segmenter();
    let mut group = c.benchmark_group("parse_960x540_2threads");
    group.sample_size(10);
    for views in [1usize, 3] {
        let inputs: Vec<ViewInput<'_>> = images
            .iter()
            .take(views)
            .map(|image| ViewInput {
                camera: "cam",
                frame: "000000",
                image: Some(image),
                recorded: None,
                regions: None,
            })
            .collect();
        group.throughput(Throughput::Elements(views as u64));
        group.bench_with_input(BenchmarkId::new("views", views), &inputs, |b, inputs| {
            b.iter(|| black_box(seg.segment(inputs).expect("segment")))
        });
    }
    group.finish();
}

criterion_group!(benches, preprocess, inference);
criterion_main!(benches);
