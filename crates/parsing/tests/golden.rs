//! bodyseg-parsing against values computed in Python (scripts/gen_parsing_test_model.py,
//! which uses scripts/parsing_common.py and Python onnxruntime): SCHP pre-processing of
//! 640x480 and 1920x1080 images, the logits of a tiny committed model, and the whole
//! pre-processing → inference → post-processing chain.
//!
//! Needs the ONNX Runtime library: `scripts/setup_onnxruntime.sh` (scripts/test.sh runs it)
//! or `ORT_DYLIB_PATH`.

use bodyseg_core::RgbImage;
use bodyseg_parsing::transform::{InputTransform, warp_to_input};
use bodyseg_parsing::{ModelSpec, OnnxOptions, OnnxSegmenter, ParsingError, Segmenter, ViewInput};
use serde_json::Value;
use std::path::{Path, PathBuf};

#[path = "common/runtime.rs"]
mod runtime;
use runtime::runtime_library;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn json(name: &str) -> Value {
    let text = std::fs::read_to_string(data(name)).expect("committed test data");
    serde_json::from_str(&text).expect("valid JSON")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The image scripts/gen_parsing_test_model.py's `pattern_rgb` builds.
fn pattern_rgb(w: u32, h: u32) -> RgbImage {
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for v in 0..i64::from(h) {
        for u in 0..i64::from(w) {
            rgb.push(((u * 7 + v * 3) % 256) as u8);
            rgb.push(((u * v) % 251) as u8);
            rgb.push(((u ^ v) & 255) as u8);
        }
    }
    RgbImage::new(w, h, rgb).expect("w*h*3 bytes")
}

fn tiny(path: &str, spec_text: Option<&str>) -> Result<OnnxSegmenter, ParsingError> {
    let model = data(path);
    let bytes = std::fs::read(&model).expect("committed model");
    let sidecar = spec_text
        .map(String::from)
        .unwrap_or_else(|| std::fs::read_to_string(data("tiny.json")).expect("sidecar"));
    let spec = ModelSpec::from_json(&sidecar, &data("tiny.json"))?;
    OnnxSegmenter::new(
        &runtime_library(),
        &bytes,
        &model,
        spec,
        &OnnxOptions {
            threads: 1,
            keep_class_probs: true,
        },
    )
}

#[test]
fn preprocessing_matches_schp_equations() {
    let golden = json("preprocess_golden.json");
    let s = golden["input_size"].as_u64().expect("S") as u32;
    for case in golden["cases"].as_array().expect("cases") {
        let (w, h) = (
            case["width"].as_u64().expect("w") as u32,
            case["height"].as_u64().expect("h") as u32,
        );
        let t = InputTransform::new(w, h, s);
        for (name, got) in [
            ("input_from_image", t.input_from_image()),
            ("image_from_input", t.image_from_input()),
        ] {
            let want: Vec<f64> = case[name]
                .as_array()
                .expect("rows")
                .iter()
                .flat_map(floats)
                .collect();
            let got: Vec<f64> = got.iter().flatten().copied().collect();
            for (g, w_) in got.iter().zip(&want) {
                // Same formulas in f64 on both sides: only rounding differs.
                assert!((g - w_).abs() < 1e-9, "{w}x{h} {name}: {got:?} vs {want:?}");
            }
        }
        let samples = warp_to_input(&pattern_rgb(w, h), &t);
        for row in case["samples"].as_array().expect("samples") {
            let r = floats(row);
            let (x, y) = (r[0] as usize, r[1] as usize);
            for c in 0..3 {
                let got = f64::from(samples[(y * s as usize + x) * 3 + c]);
                // The golden sample is numpy's bilinear value before SCHP's rounding to a
                // whole grey level. Rust blends in f32 (weights and values), numpy in f64:
                // the unrounded values agree to ~1e-4, so Rust's rounded sample is numpy's
                // rounded one, except within 1e-3 of a tie (x.5), where either neighbour is
                // right.
                let want = r[2 + c];
                let near_tie = ((want - want.floor()) - 0.5).abs() < 1e-3;
                assert!(
                    got == want.round_ties_even() || (near_tie && (got - want).abs() <= 0.5 + 1e-3),
                    "{w}x{h} input pixel ({x}, {y}) channel {c}: {got}, want {want} rounded"
                );
            }
        }
    }
}

#[test]
fn logits_equal_python_onnxruntime() {
    let golden = json("tiny_golden.json");
    let mut seg = tiny("tiny.onnx", None).expect("tiny model loads");
    let shape: Vec<usize> = floats(&golden["input_shape"])
        .iter()
        .map(|&d| d as usize)
        .collect();
    let (n, s) = (shape[0], shape[2]);
    let mut input = Vec::with_capacity(n * 3 * s * s);
    for b in 0..n {
        for c in 0..3 {
            for y in 0..s {
                for x in 0..s {
                    let a = 0.37 * x as f64 + 0.23 * y as f64 + 1.1 * c as f64 + 2.3 * b as f64;
                    input.push((a.sin() as f32) * 2.0);
                }
            }
        }
    }
    let (logits, h, w) = seg.run_batch(input, n).expect("inference");
    assert_eq!(
        vec![n, 7, h, w],
        floats(&golden["logits_shape"])
            .iter()
            .map(|&d| d as usize)
            .collect::<Vec<_>>()
    );
    let want = floats(&golden["logits"]);
    let max = logits
        .iter()
        .zip(&want)
        .map(|(g, w)| (f64::from(*g) - w).abs())
        .fold(0.0, f64::max);
    // The bar: the same runtime on the same model and input, max |diff| ≤ 1e-4.
    assert!(max <= 1e-4, "max abs logit difference {max}");
}

#[test]
fn whole_chain_matches_python_and_batches_views() {
    let golden = json("tiny_golden.json");
    let mut seg = tiny("tiny.onnx", None).expect("tiny model loads");
    let wh = floats(&golden["chain_image"]);
    let image = pattern_rgb(wh[0] as u32, wh[1] as u32);
    let other = pattern_rgb(17, 23);
    let view = |image| ViewInput {
        camera: "cam0",
        frame: "000000",
        image: Some(image),
        recorded: None,
        regions: None,
    };
    // Two views of different sizes in one batch: each comes back at its own size.
    let out = seg.segment(&[view(&image), view(&other)]).expect("segment");
    assert_eq!((out[1].labels.width, out[1].labels.height), (17, 23));
    let parsed = &out[0];
    parsed.labels.validate().expect("consistent label image");
    let ids = floats(&golden["chain_class_ids"]);
    let probs = floats(&golden["chain_probs"]);
    let probs_got = parsed.labels.probs.as_ref().expect("probabilities");
    let mut differ = 0;
    for i in 0..ids.len() {
        if f64::from(parsed.labels.labels[i].id()) != ids[i] {
            differ += 1;
        }
        // f32 in Rust vs f64 in numpy through bilinear blends and softmax.
        assert!(
            (f64::from(probs_got[i]) - probs[i]).abs() < 1e-4,
            "pixel {i}: prob {} vs {}",
            probs_got[i],
            probs[i]
        );
    }
    // Argmax may flip only where two classes tie to ~1e-6; none expected here.
    assert_eq!(
        differ, 0,
        "{differ} pixels with another class than Python's"
    );
    let all = parsed.class_probs.as_ref().expect("kept");
    let n = parsed.labels.num_pixels();
    let sum: f32 = (0..7).map(|c| all[c * n + 5]).sum();
    assert!((sum - 1.0).abs() < 1e-5, "{sum}");
    // The same view alone gives the same result as in the batch.
    let alone = seg.segment(&[view(&image)]).expect("segment");
    assert_eq!(alone[0].labels.labels, parsed.labels.labels);
}

#[test]
fn contract_violations_are_clear_errors() {
    let e = tiny("tiny_5ch.onnx", None)
        .expect_err("5 channels")
        .to_string();
    assert!(
        e.contains("tiny_5ch.onnx: model output has 5 channels, expected 7"),
        "{e}"
    );

    let sidecar = std::fs::read_to_string(data("tiny.json")).expect("sidecar");
    let wrong_size = sidecar.replace("[\n    32,\n    32\n  ]", "[64, 64]");
    assert_ne!(
        wrong_size, sidecar,
        "the sidecar's input_size layout changed"
    );
    let e = tiny("tiny.onnx", Some(&wrong_size))
        .expect_err("64 vs 32")
        .to_string();
    assert!(
        e.contains("tiny.json: input_size is [64, 64] but the model's input is 32x32"),
        "{e}"
    );
    let wrong_stride = sidecar.replace("\"output_stride\": 2", "\"output_stride\": 4");
    let e = tiny("tiny.onnx", Some(&wrong_stride))
        .expect_err("stride")
        .to_string();
    assert!(e.contains("tiny.json: output_stride is 4 but"), "{e}");

    let bytes = b"not an onnx model";
    let e = OnnxSegmenter::new(
        &runtime_library(),
        bytes,
        Path::new("junk.onnx"),
        ModelSpec::schp(),
        &OnnxOptions::default(),
    )
    .expect_err("junk")
    .to_string();
    assert!(
        e.starts_with("junk.onnx: ONNX Runtime cannot load the model: "),
        "{e}"
    );
}
