//! [`ParsingConfig`]: the `[parsing]` section of the pipeline configuration.

use serde::{Deserialize, Serialize};

/// How 2D parsing runs (`[parsing]` in the pipeline configuration).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ParsingConfig {
    /// ONNX model file; its sidecar is the same path with `.json`. Empty (default) = the
    /// bundled model, `models/bodyseg_parser_small.onnx`.
    pub model: String,
    /// ONNX Runtime shared library (`libonnxruntime.so.1.x`). Empty (default) = the
    /// `ORT_DYLIB_PATH` environment variable, else the project-local copy that
    /// `scripts/setup_onnxruntime.sh` writes (`.deps/onnxruntime/libonnxruntime.so`).
    pub runtime_library: String,
    /// ONNX Runtime intra-op threads; 0 = one per core. Default 2.
    pub threads: u32,
    /// Keep all 7 class probabilities per pixel, not only the winner's (7× the memory of
    /// the label maps). Default false.
    pub keep_class_probs: bool,
}

impl Default for ParsingConfig {
    fn default() -> Self {
        ParsingConfig {
            model: String::new(),
            runtime_library: String::new(),
            threads: 2,
            keep_class_probs: false,
        }
    }
}

impl ParsingConfig {
    /// The [`crate::OnnxOptions`] of these values.
    pub fn onnx_options(&self) -> crate::OnnxOptions {
        crate::OnnxOptions {
            threads: self.threads as usize,
            keep_class_probs: self.keep_class_probs,
        }
    }
}
