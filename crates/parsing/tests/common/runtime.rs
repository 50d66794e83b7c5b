//! Where the parsing tests and benches find the repository and ONNX Runtime (included with
//! `#[path]`: one copy for all).

use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The ONNX Runtime library to load: ORT_DYLIB_PATH, else the project-local copy.
pub fn runtime_library() -> PathBuf {
    let path = std::env::var_os("ORT_DYLIB_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".deps/onnxruntime/libonnxruntime.so"));
    assert!(
        path.is_file(),
        "{}: ONNX Runtime library missing: run scripts/setup_onnxruntime.sh (or set ORT_DYLIB_PATH)",
        path.display()
    );
    path
}
