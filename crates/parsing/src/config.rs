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
}

impl Default for ParsingConfig {
    fn default() -> Self {
        ParsingConfig {
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
}
