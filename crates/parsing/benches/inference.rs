//! Guards the parsing issue's figure: 2D parsing of one 960×540 colour view with the
//! bundled model (`models/bodyseg_parser_small.onnx`) on 2 ONNX Runtime threads, whole
//! chain (SCHP pre-processing, inference, logits upsampling, warp back, softmax/argmax).
//! Also 3 views in one batch (a frame of the default 3-camera rig). Input: frame 0 of the
//! `robot_cell` synth preset, seed 1 (three people, table, robot arm).
//!
//! Needs `scripts/setup_onnxruntime.sh` (or ORT_DYLIB_PATH) and the bundled model.

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_core::RgbImage;
use bodyseg_parsing::{ModelSpec, OnnxOptions, OnnxSegmenter, Segmenter, ViewInput};
use bodyseg_synth::{Synth, preset};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn segmenter() -> OnnxSegmenter {
    let library = std::env::var_os("ORT_DYLIB_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".deps/onnxruntime/libonnxruntime.so"));
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

fn inference(c: &mut Criterion) {
    let config = preset("robot_cell").expect("preset");
    let frame = Synth::new(config, 1).expect("synth").frame(0);
    let images: Vec<RgbImage> = frame
        .cameras
        .iter()
        .map(|cam| {
            let w = 960;
            let h = (cam.color.len() / 3 / w) as u32;
            RgbImage::new(w as u32, h, cam.color.clone()).expect("960 wide RGB")
        })
        .collect();
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
            })
            .collect();
        group.throughput(Throughput::Elements(views as u64));
        group.bench_with_input(BenchmarkId::new("views", views), &inputs, |b, inputs| {
            b.iter(|| black_box(seg.segment(inputs).expect("segment")))
        });
    }
    group.finish();
}

criterion_group!(benches, inference);
criterion_main!(benches);
