//! [`BodyPix`] with the committed `models/bodypix_mobilenet_v1_075_quant.onnx`: its labels on
//! the synthetic two-person view equal the Python reference's (`scripts/bodypix_golden.py`,
//! i.e. `scripts/bodypix_probe.py`'s crop and sampling with ONNX Runtime in Python) on
//! ≥ 99.5 % of the pixels; a model that is not BodyPix is refused naming the file; bad
//! regions give nothing, not an error.
//!
//! Needs the ONNX Runtime library: `scripts/setup_onnxruntime.sh` (scripts/test.sh runs it)
//! or `ORT_DYLIB_PATH`. `BODYSEG_BODYPIX_INPUT=DIR` writes the view and its regions for the
//! reference (`two_people.png`, `two_people.json`).

use bodyseg_core::Label;
use bodyseg_parsing::bodypix::{merge_part_maps, part_labels};
use bodyseg_parsing::{
    BlazePoseOptions, BlazePoseSegmenter, BodyPix, BodyPixOptions, ParsingError, PixelBox,
};
use std::path::PathBuf;

#[path = "common/runtime.rs"]
mod runtime;
#[path = "common/two_people.rs"]
mod two_people;
use runtime::{root, runtime_library};

fn model() -> PathBuf {
    root().join("models/bodypix_mobilenet_v1_075_quant.onnx")
}

fn bodypix() -> BodyPix {
    let bytes = std::fs::read(model()).expect("committed model");
    BodyPix::new(&runtime_library(), &bytes, &model(), 1).expect("the committed model loads")
}

#[test]
fn labels_equal_the_python_reference() {
    let (image, regions) = two_people::view();
    assert_eq!(regions.len(), 2);
    if let Some(dir) = std::env::var_os("BODYSEG_BODYPIX_INPUT") {
        let dir = PathBuf::from(dir);
        std::fs::create_dir_all(&dir).expect("input dir");
        // The `image` crate, not bodyseg-io: a stage crate's tests use only core, synth
        // and testkit among bodyseg's crates (scripts/check_boundaries.py).
        image::save_buffer(
            dir.join("two_people.png"),
            &image.rgb,
            image.width,
            image.height,
            image::ExtendedColorType::Rgb8,
        )
        .expect("write the view");
        let boxes: Vec<[f64; 4]> = regions
            .iter()
            .map(|r| [r.bounds.x0, r.bounds.y0, r.bounds.x1, r.bounds.y1])
            .collect();
        std::fs::write(
            dir.join("two_people.json"),
            format!("{{\"person_boxes\": {boxes:?}}}"),
        )
        .expect("write the regions");
    }
    let mut bp = bodypix();
    // The reference's size: longer side 513 -> 512.
    let options = BodyPixOptions {
        long_side: 512,
        ..BodyPixOptions::default()
    };
    let maps: Vec<_> = regions
        .iter()
        .map(|r| bp.run_region(&image, &r.bounds, &options).expect("runs"))
        .collect::<Option<Vec<_>>>()
        .expect("both regions are in the image");
    let (w, h) = (image.width as usize, image.height as usize);
    let got = part_labels(&merge_part_maps(w, h, &maps), options.threshold);
    let golden = root().join("crates/parsing/tests/data/bodypix_two_people_labels.png");
    let want = image::open(&golden).expect("golden labels").into_luma8();
    assert_eq!(want.dimensions(), (image.width, image.height));
    let want = want.into_raw(); // class ids 0-6, one byte per pixel
    let same = got.iter().zip(&want).filter(|(g, w)| g == w).count();
    let people = want
        .iter()
        .filter(|&&w| w != Label::BACKGROUND.id())
        .count();
    let share = same as f64 / got.len() as f64;
    eprintln!("BodyPix vs Python: {share:.5} of pixels equal; {people} person pixels");
    assert!(people > 5_000, "the reference finds the two people");
    assert!(share >= 0.995, "{share}");
    // Per class, so that a swap of two parts cannot hide in the background's share.
    for class in 1..7u8 {
        let n_want = want.iter().filter(|&&w| w == class).count();
        let n_got = got.iter().filter(|&&g| g == class).count();
        assert!(
            n_got.abs_diff(n_want) <= n_want / 20 + 50,
            "class {class}: {n_got} pixels, reference {n_want}"
        );
    }
}

#[test]
fn another_model_is_refused_naming_the_file() {
    let path = root().join("models/blazepose_lite.onnx");
    let bytes = std::fs::read(&path).expect("committed model");
    let err = BodyPix::new(&runtime_library(), &bytes, &path, 1).expect_err("not BodyPix");
    assert!(matches!(err, ParsingError::NotBodyPix { .. }), "{err:?}");
    let text = err.to_string();
    assert!(text.contains("blazepose_lite.onnx"), "{text}");
    assert!(text.contains("not a BodyPix model"), "{text}");
}

#[test]
fn bad_regions_give_nothing() {
    let (image, _) = two_people::view();
    let mut bp = bodypix();
    let options = BodyPixOptions::default();
    let bad = [
        PixelBox {
            x0: f64::NAN,
            y0: 0.0,
            x1: 10.0,
            y1: 10.0,
        },
        PixelBox {
            x0: 50.0,
            y0: 0.0,
            x1: 10.0,
            y1: 10.0,
        },
        PixelBox {
            x0: 5000.0,
            y0: 5000.0,
            x1: 6000.0,
            y1: 6000.0,
        },
    ];
    for b in &bad {
        assert!(
            bp.run_region(&image, b, &options)
                .expect("no error")
                .is_none()
        );
    }
    // A one-pixel region at the corner and a huge one run.
    for b in [
        PixelBox {
            x0: 0.0,
            y0: 0.0,
            x1: 0.0,
            y1: 0.0,
        },
        PixelBox {
            x0: -1e6,
            y0: -1e6,
            x1: 1e6,
            y1: 1e6,
        },
    ] {
        let map = bp.run_region(&image, &b, &options).expect("runs");
        assert!(map.is_some());
    }
}

fn fused(threads: usize) -> BlazePoseSegmenter {
    let path = root().join("models/blazepose_full.onnx");
    let bytes = std::fs::read(&path).expect("committed model");
    let options = BlazePoseOptions {
        threads,
        ..BlazePoseOptions::default()
    };
    let segmenter = BlazePoseSegmenter::new(&runtime_library(), &bytes, &path, &options)
        .expect("BlazePose loads");
    let bytes = std::fs::read(model()).expect("committed model");
    segmenter
        .with_bodypix(&runtime_library(), &bytes, &model())
        .expect("BodyPix loads")
}

/// BlazePose with BodyPix's parts: a view with nobody (no region) is all background; the
/// two-person view has every body class, with probabilities in (0, 1], and the same labels
/// with one session as with regions at once.
#[test]
fn fused_segmenter_labels_people_and_nobody() {
    let (image, regions) = two_people::view();
    let mut seg = fused(2);
    assert!(seg.uses_bodypix());
    let empty = seg.segment_image(&image, Some(&[])).expect("runs");
    assert!(empty.labels.iter().all(|l| *l == Label::BACKGROUND));
    let labels = seg.segment_image(&image, Some(&regions)).expect("runs");
    let probs = labels.probs.as_ref().expect("probabilities");
    for class in 1..7u8 {
        let n = labels.labels.iter().filter(|l| l.id() == class).count();
        assert!(n > 100, "class {class}: {n} pixels");
    }
    for (l, p) in labels.labels.iter().zip(probs) {
        assert!((0.0..=1.0).contains(p), "{p}");
        if *l != Label::BACKGROUND {
            assert!(*p > 0.0);
        }
    }
    let one = fused(1)
        .segment_image(&image, Some(&regions))
        .expect("runs");
    assert_eq!(one.labels, labels.labels);
}

#[test]
fn fused_segmenter_refuses_a_landmark_model_as_bodypix() {
    let path = root().join("models/blazepose_full.onnx");
    let bytes = std::fs::read(&path).expect("committed model");
    let segmenter = BlazePoseSegmenter::new(
        &runtime_library(),
        &bytes,
        &path,
        &BlazePoseOptions::default(),
    )
    .expect("BlazePose loads");
    let err = segmenter
        .with_bodypix(&runtime_library(), &bytes, &path)
        .expect_err("not BodyPix");
    assert!(err.to_string().contains("blazepose_full.onnx"), "{err}");
    assert!(matches!(err, ParsingError::NotBodyPix { .. }), "{err:?}");
}
