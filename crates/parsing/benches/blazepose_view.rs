//! Guards issue 29's time budget: one 960×540 view with 2 people through
//! [`BlazePoseSegmenter`] (`models/blazepose_full.onnx`, 2 ONNX Runtime threads): per
//! person the crop, the landmark model (the first ROI and the refinement pass), decoding,
//! the landmarks + mask → classes rule, and merging the people; target ≤ 80 ms. Input:
//! frame 0 of the `robot_cell` synth preset, seed 1, camera 0, the regions of its two
//! largest people (their pixels' bounding boxes in synth's per-pixel person ids, as a box
//! found from depth would give). `blazepose_rule` measures the labelling alone on two
//! 500 px people.
//!
//! Needs `scripts/setup_onnxruntime.sh` (or ORT_DYLIB_PATH) and the committed model.

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_core::RgbImage;
use bodyseg_parsing::{BlazePoseOptions, BlazePoseSegmenter, BlazePoseVariant};
use bodyseg_parsing::{PersonRegion, PixelBox, Segmenter, ViewInput};
use bodyseg_synth::{Synth, preset};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn segmenter(variant: BlazePoseVariant) -> BlazePoseSegmenter {
    let library = std::env::var_os("ORT_DYLIB_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".deps/onnxruntime/libonnxruntime.so"));
    let model = root().join(format!("models/blazepose_{}.onnx", variant.name()));
    let bytes = std::fs::read(&model).expect("committed BlazePose model");
    BlazePoseSegmenter::new(&library, &bytes, &model, &BlazePoseOptions::default())
        .expect("ONNX Runtime (scripts/setup_onnxruntime.sh) and the model")
}

/// Camera 0 of frame 0 of `robot_cell`, seed 1 (960 wide), and the regions of its two
/// largest people.
fn view() -> (RgbImage, Vec<PersonRegion>) {
    let config = preset("robot_cell").expect("preset");
    let frame = Synth::new(config, 1).expect("synth").frame(0);
    let cam = &frame.cameras[0];
    let w = 960usize;
    let h = cam.color.len() / 3 / w;
    let image = RgbImage::new(w as u32, h as u32, cam.color.clone()).expect("960 wide RGB");
    // Bounding box and pixel count per person id (0 = nobody).
    let mut boxes: Vec<(usize, [usize; 4])> = vec![(0, [usize::MAX, usize::MAX, 0, 0]); 256];
    for (k, &id) in cam.color_person.iter().enumerate() {
        if id == 0 {
            continue;
        }
        let (u, v) = (k % w, k / w);
        let b = &mut boxes[usize::from(id)];
        b.0 += 1;
        b.1 = [b.1[0].min(u), b.1[1].min(v), b.1[2].max(u), b.1[3].max(v)];
    }
    boxes.sort_by_key(|b| std::cmp::Reverse(b.0));
    let regions = boxes
        .iter()
        .take(2)
        .filter(|b| b.0 > 0)
        .enumerate()
        .map(|(i, (_, b))| PersonRegion {
            bounds: PixelBox {
                x0: b[0] as f64,
                y0: b[1] as f64,
                x1: b[2] as f64,
                y1: b[3] as f64,
            },
            depth_m: 3.0 + i as f64,
        })
        .collect();
    (image, regions)
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
