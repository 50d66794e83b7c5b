//! bodyseg-parsing: 2D human parsing (ALGORITHM.md §2).
//!
//! Place in the pipeline: the first stage. Colour images of one frame
//! ([`RgbImage`](bodyseg_core::RgbImage), one per camera) → one
//! [`LabelImage`](bodyseg_core::LabelImage) per view (class per pixel with the
//! probability of that class), the input of label projection (bodyseg-project).
//!
//! - [`Segmenter`]: the trait every parser implements.
//! - [`OnnxSegmenter`]: SCHP-compatible networks in ONNX, run by ONNX Runtime, which is
//!   loaded at run time from a shared library ([`load_runtime`]); the model's sidecar JSON
//!   is a [`ModelSpec`]. Pre- and post-processing are SCHP's ([`transform`]).
//! - [`RecordedSegmenter`]: label images computed earlier (a recording's `parsing/`,
//!   read by the caller and handed over in [`ViewInput::recorded`]).
//! - [`blazepose`]: BlazePose landmarks + mask → the 7 classes (issue 29), pure functions;
//!   [`BlazePoseSegmenter`] runs it on person regions.
//! - [`bodypix`]: BodyPix 2.0's body parts on person regions, fused with BlazePose's.
//!
//! This crate does no file I/O: model bytes, sidecar text and images come from the
//! caller (bodyseg-pipeline reads them with bodyseg-io). `ort` and `ndarray` types do not
//! appear in its API.
//!
//! # Conventions
//! - Pixels: (u, v) = (column, row), integer coordinates are pixel centres, arrays are
//!   row-major (`v * width + u`). The network input is a square of side S (the sidecar's
//!   `input_size`) with the same convention.
//! - Classes: the 7 of ALGORITHM.md §0 in id order; a model's output channel `c` is the
//!   logit of class id `c`.
//! - Colour: [`RgbImage`](bodyseg_core::RgbImage) bytes are R, G, B; the sidecar's
//!   `channel_order`, `mean` and `std` (on pixels / 255) say what the network wants.
//! - Probabilities are softmax values in `[0, 1]`.

pub mod blazepose;
mod blazepose_segmenter;
pub mod bodypix;
mod config;
mod error;
mod onnx;
mod segmenter;
mod spec;
pub mod transform;

pub use blazepose_segmenter::{BlazePoseOptions, BlazePoseSegmenter, BlazePoseVariant};
pub use bodypix::{BodyPix, BodyPixOptions};
pub use config::{BodyParts, ParsingConfig, SegmenterKind};
pub use error::ParsingError;
pub use onnx::{OnnxOptions, OnnxSegmenter, load_runtime};
pub use segmenter::{ParsedView, PersonRegion, PixelBox, RecordedSegmenter, Segmenter, ViewInput};
pub use spec::{ChannelOrder, MAX_INPUT_SIZE, ModelSpec, sidecar_path};
