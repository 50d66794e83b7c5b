//! [`ParsingConfig`]: the `[parsing]` section of the pipeline configuration.

use crate::blazepose_segmenter::{BlazePoseOptions, BlazePoseVariant};
use serde::{Deserialize, Serialize};

/// Which 2D parser runs on colour images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SegmenterKind {
    /// BlazePose's landmark model on the people found from depth, its landmarks and mask
    /// turned into the 7 classes ([`crate::blazepose`]): the default, for real images on a
    /// CPU.
    #[default]
    Blazepose,
    /// A network following the SCHP contract (ALGORITHM.md §2) in ONNX: `parsing.model`,
    /// else the bundled synthetic-trained `models/bodyseg_parser_small.onnx`
    /// ([`crate::OnnxSegmenter`]).
    Onnx,
}

/// Where `segmenter = "blazepose"` takes the body parts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyParts {
    /// BlazePose's landmarks: each pixel of its person mask takes the class of the nearest
    /// bone ([`crate::blazepose`]).
    Landmarks,
    /// BodyPix 2.0 (`models/bodypix_mobilenet_v1_075_quant.onnx`) on the same regions: the
    /// person is BlazePose's mask ∪ BodyPix's, the part BodyPix's, except BlazePose's legs
    /// ([`crate::bodypix::fuse`]); BlazePose's rim where BodyPix is sure of background and
    /// pieces held by no landmark or BlazePose pixel are taken off
    /// ([`crate::BlazePoseOptions::bodypix_background_below`],
    /// [`crate::BlazePoseOptions::drop_detached`]). About one more model run per person.
    /// The default (real photographs, tune + test: body-part mIoU 0.554 against 0.462,
    /// docs/results.md).
    #[default]
    Bodypix,
}

impl BodyParts {
    /// `landmarks` or `bodypix`.
    pub fn name(self) -> &'static str {
        match self {
            BodyParts::Landmarks => "landmarks",
            BodyParts::Bodypix => "bodypix",
        }
    }
}

/// How 2D parsing runs (`[parsing]` in the pipeline configuration).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ParsingConfig {
    /// Which parser runs on colour images: `blazepose` (default) or `onnx`.
    pub segmenter: SegmenterKind,
    /// BlazePose landmark model (`segmenter = "blazepose"`): `lite`, `full` (default) or
    /// `heavy` (`models/blazepose_<variant>.onnx`; heavy is made by
    /// `scripts/convert_blazepose.py`).
    pub blazepose_variant: BlazePoseVariant,
    /// Where `segmenter = "blazepose"` takes the body parts from: `bodypix` (default:
    /// BodyPix's parts inside BlazePose's and BodyPix's person, BlazePose's legs;
    /// `models/bodypix_mobilenet_v1_075_quant.onnx`) or `landmarks` (BlazePose's rule alone).
    pub body_parts: BodyParts,
    /// ONNX model file (`segmenter = "onnx"`); its sidecar is the same path with `.json`.
    /// Empty (default) = the bundled model, `models/bodyseg_parser_small.onnx`.
    pub model: String,
    /// ONNX Runtime shared library (`libonnxruntime.so.1.x`). Empty (default) = the
    /// `ORT_DYLIB_PATH` environment variable, else the project-local copy that
    /// `scripts/setup_onnxruntime.sh` writes (`.deps/onnxruntime/libonnxruntime.so`).
    pub runtime_library: String,
    /// Threads for the parser. `onnx`: ONNX Runtime's intra-op threads. `blazepose`: the
    /// intra-op threads of a view with one person region, the regions run at once (one
    /// single-threaded session each) of a view with several. 0 = ONNX Runtime's default.
    /// Default 2.
    pub threads: u32,
}

impl Default for ParsingConfig {
    fn default() -> Self {
        ParsingConfig {
            segmenter: SegmenterKind::Blazepose,
            blazepose_variant: BlazePoseVariant::Full,
            body_parts: BodyParts::Bodypix,
            model: String::new(),
            runtime_library: String::new(),
            threads: 2,
        }
    }
}

impl ParsingConfig {
    /// The [`crate::OnnxOptions`] of these values: the pipeline keeps only the winning
    /// label's probability (all 7 class probabilities are an option of the ONNX segmenter
    /// alone, for tests and studies).
    pub fn onnx_options(&self) -> crate::OnnxOptions {
        crate::OnnxOptions {
            threads: self.threads as usize,
            keep_class_probs: false,
        }
    }

    /// The [`BlazePoseOptions`] of these values (the rule's tuned defaults).
    pub fn blazepose_options(&self) -> BlazePoseOptions {
        BlazePoseOptions {
            threads: self.threads as usize,
            ..BlazePoseOptions::default()
        }
    }
}
