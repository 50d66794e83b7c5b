//! [`BlazePoseSegmenter`] with the committed `models/blazepose_full.onnx`: a model that is
//! not BlazePose's is refused naming the file, a view with nobody in it is all background
//! (not an error), and regions outside the image or malformed do not fail.
//!
//! Needs the ONNX Runtime library: `scripts/setup_onnxruntime.sh` (scripts/test.sh runs it)
//! or `ORT_DYLIB_PATH`.

use bodyseg_core::{Label, RgbImage};
use bodyseg_parsing::{BlazePoseOptions, BlazePoseSegmenter};
use bodyseg_parsing::{ParsingError, PersonRegion, PixelBox, Segmenter, ViewInput};
use std::path::Path;

#[path = "common/runtime.rs"]
mod runtime;
#[path = "common/two_people.rs"]
mod two_people;
use runtime::{root, runtime_library};

fn load(model: &Path) -> Result<BlazePoseSegmenter, ParsingError> {
    load_with(model, 1)
}

/// The model with `threads` sessions (regions run at once).
fn load_with(model: &Path, threads: usize) -> Result<BlazePoseSegmenter, ParsingError> {
    let bytes = std::fs::read(model).expect("committed model");
    BlazePoseSegmenter::new(
        &runtime_library(),
        &bytes,
        model,
        &BlazePoseOptions {
            threads,
            ..BlazePoseOptions::default()
        },
    )
}

fn full() -> BlazePoseSegmenter {
    load(&root().join("models/blazepose_full.onnx")).expect("the committed full model loads")
}

/// A grey image with a smooth pattern (no person).
fn image(w: u32, h: u32) -> RgbImage {
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for v in 0..h {
        for u in 0..w {
            let g = 100 + ((u / 40 + v / 40) % 2) as u8 * 30;
            rgb.extend_from_slice(&[g, g, g]);
        }
    }
    RgbImage::new(w, h, rgb).expect("w*h*3 bytes")
}

fn view<'a>(image: &'a RgbImage, regions: Option<&'a [PersonRegion]>) -> ViewInput<'a> {
    ViewInput {
        camera: "cam0",
        frame: "000000",
        image: Some(image),
        recorded: None,
        regions,
    }
}

#[test]
fn a_model_that_is_not_blazepose_is_refused_naming_the_file() {
    let tiny = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny.onnx");
    let e = load(&tiny).expect_err("the SCHP-contract test model is not BlazePose");
    assert!(matches!(e, ParsingError::NotBlazePose { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("tiny.onnx") && text.contains("not a BlazePose"),
        "{text}"
    );
}

#[test]
fn nobody_gives_an_all_background_view_and_odd_regions_do_not_fail() {
    let mut seg = full();
    assert!(seg.needs_regions() && seg.needs_images());
    let img = image(320, 240);
    let out = seg
        .segment(&[view(&img, Some(&[]))])
        .expect("nobody is no error");
    assert_eq!(out.len(), 1);
    let labels = &out[0].labels;
    assert_eq!((labels.width, labels.height), (320, 240));
    assert!(labels.labels.iter().all(|&l| l == Label::BACKGROUND));
    assert!(
        labels
            .probs
            .as_ref()
            .expect("probabilities")
            .iter()
            .all(|&p| p == 1.0)
    );
    assert_eq!(seg.runs(), 0, "no region, no inference");

    // A region wholly outside the image and a malformed one: no error, right size.
    let regions = [
        PersonRegion {
            bounds: PixelBox {
                x0: 1000.0,
                y0: 1000.0,
                x1: 1100.0,
                y1: 1300.0,
            },
            depth_m: 3.0,
        },
        PersonRegion {
            bounds: PixelBox {
                x0: f64::NAN,
                y0: 0.0,
                x1: 10.0,
                y1: 10.0,
            },
            depth_m: 3.0,
        },
    ];
    let out = seg
        .segment(&[view(&img, Some(&regions))])
        .expect("odd regions are no error");
    assert_eq!((out[0].labels.width, out[0].labels.height), (320, 240));
    let probs = out[0].labels.probs.as_ref().expect("probabilities");
    assert!(probs.iter().all(|p| (0.0..=1.0).contains(p)));

    // No colour image: an error naming the camera.
    let none = ViewInput {
        image: None,
        ..view(&img, None)
    };
    let e = seg.segment(&[none]).expect_err("no image");
    assert!(e.to_string().contains("cam0"), "{e}");
}

/// Regions run at once on several sessions give the labels of one session running them in
/// turn (people merged in region order), on a view with two people; and those labels hold
/// both people's parts.
#[test]
fn regions_at_once_label_as_one_session_does() {
    let (image, regions) = two_people::view();
    assert_eq!(regions.len(), 2, "two people in view");
    let model = root().join("models/blazepose_full.onnx");
    let label = |threads: usize| {
        let mut seg = load_with(&model, threads).expect("the committed full model loads");
        let labels = seg.segment_image(&image, Some(&regions)).expect("segments");
        (labels, seg.runs())
    };
    let (one, runs_one) = label(1);
    let body = one
        .labels
        .iter()
        .filter(|l| **l != Label::BACKGROUND)
        .count();
    assert!(body > 1000, "two people give body pixels, got {body}");
    for threads in [2, 3] {
        let (many, runs) = label(threads);
        assert_eq!(runs, runs_one, "{threads} sessions run the model as often");
        assert!(
            many.labels == one.labels,
            "{threads} sessions: labels differ"
        );
        assert!(
            many.probs == one.probs,
            "{threads} sessions: probabilities differ"
        );
    }
}

/// `mirror_average` runs the model once more per person found (on the mirrored crop) and
/// changes the mask only: on the two-person view the labels stay nearly the same (the mean
/// of two estimates of the same people), probabilities stay in [0, 1], and both people keep
/// their parts.
#[test]
fn a_mirrored_run_per_person_only_smooths_the_mask() {
    let (image, regions) = two_people::view();
    let model = root().join("models/blazepose_full.onnx");
    let bytes = std::fs::read(&model).expect("committed model");
    let label = |mirror_average: bool| {
        let options = BlazePoseOptions {
            mirror_average,
            ..BlazePoseOptions::default()
        };
        let mut seg = BlazePoseSegmenter::new(&runtime_library(), &bytes, &model, &options)
            .expect("the committed full model loads");
        let labels = seg.segment_image(&image, Some(&regions)).expect("segments");
        (labels, seg.runs())
    };
    let (plain, runs_plain) = label(false);
    let (mirrored, runs_mirrored) = label(true);
    assert_eq!(runs_mirrored, runs_plain + 2, "one more run per person");
    let probs = mirrored.probs.as_ref().expect("probabilities");
    assert!(probs.iter().all(|p| (0.0..=1.0).contains(p)));
    let body = |l: &[Label]| l.iter().filter(|l| **l != Label::BACKGROUND).count();
    let (a, b) = (body(&plain.labels), body(&mirrored.labels));
    // The same people: their body pixels agree within a tenth (a border a pixel or two
    // wide moves), and most pixels keep their class.
    assert!(a.abs_diff(b) * 10 <= a, "body pixels {a} → {b}");
    let same = plain
        .labels
        .iter()
        .zip(&mirrored.labels)
        .filter(|(p, q)| p == q)
        .count();
    assert!(
        same * 100 >= plain.labels.len() * 99,
        "{same} of {} pixels kept their class",
        plain.labels.len()
    );
    assert_ne!(plain.labels, mirrored.labels, "the mask changed somewhere");
}
