//! [`ParsingError`]: everything that can go wrong in 2D parsing.

use std::path::PathBuf;

/// Why a model cannot be loaded or a frame cannot be parsed. Messages read as one line;
/// those about a file start with its path.
#[derive(Debug, thiserror::Error)]
pub enum ParsingError {
    /// The ONNX Runtime shared library cannot be loaded (missing, wrong file, too old).
    #[error(
        "{}: cannot load the ONNX Runtime library: {cause} (run scripts/setup_onnxruntime.sh, \
         or set ORT_DYLIB_PATH or parsing.runtime_library to a libonnxruntime.so of version \
         >= 1.17)",
        .path.display()
    )]
    RuntimeLibrary {
        /// What the loader said.
        cause: String,
        /// The library file that was tried.
        path: PathBuf,
    },
    /// The model's sidecar JSON is not valid JSON or misses a key.
    #[error("{}: bad model sidecar: {cause}", .path.display())]
    SidecarSyntax {
        /// What the JSON parser said.
        cause: String,
        /// The sidecar file.
        path: PathBuf,
    },
    /// A sidecar value is out of range or disagrees with the contract or the model.
    #[error("{}: {field} {reason}", .path.display())]
    Sidecar {
        /// The key at fault (`input_size`, `class_names`).
        field: &'static str,
        /// What is wrong with it.
        reason: String,
        /// The sidecar file.
        path: PathBuf,
    },
    /// ONNX Runtime refuses the model file (not ONNX, unsupported IR version or operator).
    #[error("{}: ONNX Runtime cannot load the model: {cause}", .path.display())]
    ModelLoad {
        /// What ONNX Runtime said.
        cause: String,
        /// The model file.
        path: PathBuf,
    },
    /// The model's inputs or outputs do not follow the contract (ALGORITHM.md §2: one input
    /// `[N,3,H,W]` float32, logits `[N,7,h,w]`).
    #[error("{}: model does not follow the parsing contract: {reason}", .path.display())]
    ModelContract {
        /// What is wrong.
        reason: String,
        /// The model file.
        path: PathBuf,
    },
    /// A model given as BlazePose's landmark model is not one (other inputs or outputs).
    #[error(
        "{}: not a BlazePose landmark model: {reason} (expected the conversion of \
         scripts/convert_blazepose.py: input input_1 [1,256,256,3], outputs Identity [1,195], \
         Identity_1 [1,1], Identity_2 [1,256,256,1], Identity_3 [1,64,64,39])",
        .path.display()
    )]
    NotBlazePose {
        /// What differs.
        reason: String,
        /// The model file.
        path: PathBuf,
    },
    /// A model given as BodyPix is not one (other inputs or outputs).
    #[error(
        "{}: not a BodyPix model: {reason} (expected the conversion of \
         scripts/convert_bodypix.sh: input sub_2 uint8 [1,h,w,3], outputs float_segments \
         uint8 [1,h',w',1] and float_part_heatmaps uint8 [1,h',w',24])",
        .path.display()
    )]
    NotBodyPix {
        /// What differs.
        reason: String,
        /// The model file.
        path: PathBuf,
    },
    /// The model's output has a number of channels other than 7 (one per class).
    #[error(
        "{}: model output has {got} channels, expected 7 (one logit per class: background, \
         head, torso, upper_arms, lower_arms, upper_legs, lower_legs)",
        .path.display()
    )]
    OutputChannels {
        /// Channels of the output.
        got: i64,
        /// The model file.
        path: PathBuf,
    },
    /// Running the model failed.
    #[error("{}: inference failed: {cause}", .path.display())]
    Inference {
        /// What ONNX Runtime said.
        cause: String,
        /// The model file.
        path: PathBuf,
    },
    /// An input image is unusable (empty, or its buffer does not match its size).
    #[error("view {view}: {reason}")]
    BadImage {
        /// Index of the view in the frame.
        view: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A recorded label image could not be had or does not fit its view.
    #[error("view {view}: {reason}")]
    Recorded {
        /// Index of the view in the frame.
        view: usize,
        /// What went wrong (naming the camera and, for a file the caller read, the file).
        reason: String,
    },
}
