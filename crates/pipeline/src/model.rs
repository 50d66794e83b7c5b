//! Where the 2D parser comes from: BlazePose's landmark model (`parsing.segmenter =
//! "blazepose"`, the default) or an SCHP-contract ONNX model (`"onnx"`), and the ONNX
//! Runtime library (found beside the executable, in the current folder or in the
//! checkout), or a recording's own predictions; [`open_segmenter`] makes the
//! [`Segmenter`] of `bodyseg run` and `convert`.

use crate::config::PipelineConfig;
use crate::recording::{Layer, Recording};
use anyhow::{Context, Result, bail};
use bodyseg_parsing::{BlazePoseSegmenter, BlazePoseVariant};
use bodyseg_parsing::{
    ModelSpec, OnnxSegmenter, RecordedSegmenter, Segmenter, SegmenterKind, sidecar_path,
};
use std::path::{Path, PathBuf};

/// The bundled SCHP-contract model, relative to the project root (its sidecar: the same
/// with `.json`).
pub(crate) const BUNDLED_MODEL: &str = "models/bodyseg_parser_small.onnx";

/// BlazePose's landmark model of a variant, relative to the project root.
pub(crate) fn blazepose_model(variant: BlazePoseVariant) -> String {
    format!("models/blazepose_{}.onnx", variant.name())
}

/// Where `scripts/setup_onnxruntime.sh` puts the ONNX Runtime library, relative to the
/// project root.
pub(crate) const LOCAL_RUNTIME_LIBRARY: &str = ".deps/onnxruntime/libonnxruntime.so";

/// Environment variable naming the ONNX Runtime library (ort's convention).
pub(crate) const RUNTIME_LIBRARY_ENV: &str = "ORT_DYLIB_PATH";

/// Where a run's 2D labels come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ParserChoice {
    /// Recorded predictions when the recording has `parsing/` folders, else the model.
    #[default]
    Auto,
    /// The configured parser (`parsing.segmenter`: BlazePose, or the ONNX model) on the
    /// colour images.
    Model,
    /// The recording's `<camera>/parsing/<frame>.png`.
    Recorded,
}

/// Candidate locations of a project-relative file: beside the executable and its parent
/// folders (a `target/release/bodyseg` of a checkout), the current folder, and the
/// checkout this binary was built from.
fn project_candidates(relative: &str) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        roots.extend(exe.ancestors().skip(1).take(4).map(Path::to_path_buf));
    }
    if let Ok(cwd) = std::env::current_dir() {
        roots.push(cwd);
    }
    roots.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."));
    roots.into_iter().map(|r| r.join(relative)).collect()
}

/// The ONNX Runtime library: `parsing.runtime_library`, else `ORT_DYLIB_PATH`, else the
/// project-local copy of `scripts/setup_onnxruntime.sh`.
///
/// # Errors
/// None of them is set or exists; the message says how to get the library.
pub(crate) fn resolve_runtime_library(config: &PipelineConfig) -> Result<PathBuf> {
    if !config.parsing.runtime_library.is_empty() {
        return Ok(PathBuf::from(&config.parsing.runtime_library));
    }
    if let Some(path) = std::env::var_os(RUNTIME_LIBRARY_ENV).filter(|p| !p.is_empty()) {
        return Ok(PathBuf::from(path));
    }
    bodyseg_io::first_existing_file(&project_candidates(LOCAL_RUNTIME_LIBRARY)).with_context(|| {
        format!(
            "ONNX Runtime library not found: run scripts/setup_onnxruntime.sh (it writes \
                 {LOCAL_RUNTIME_LIBRARY}), or set {RUNTIME_LIBRARY_ENV} or \
                 parsing.runtime_library to a libonnxruntime.so"
        )
    })
}

/// The model file of the configured parser: for `parsing.segmenter = "onnx"`,
/// `parsing.model`, else the bundled model; for `"blazepose"`,
/// `models/blazepose_<parsing.blazepose_variant>.onnx`.
///
/// # Errors
/// The model is not found (neither beside the executable, in the current folder, nor in
/// the checkout the binary was built from); for the heavy BlazePose model the message
/// says how to make it.
pub(crate) fn resolve_model(config: &PipelineConfig) -> Result<PathBuf> {
    match config.parsing.segmenter {
        SegmenterKind::Onnx => {
            if !config.parsing.model.is_empty() {
                return Ok(PathBuf::from(&config.parsing.model));
            }
            bodyseg_io::first_existing_file(&project_candidates(BUNDLED_MODEL)).with_context(|| {
                format!("bundled model {BUNDLED_MODEL} not found: pass --model FILE.onnx")
            })
        }
        SegmenterKind::Blazepose => {
            let variant = config.parsing.blazepose_variant;
            let relative = blazepose_model(variant);
            bodyseg_io::first_existing_file(&project_candidates(&relative)).with_context(|| {
                let how = if variant == BlazePoseVariant::Heavy {
                    "make it with scripts/convert_blazepose.py (see its header), or use \
                     parsing.blazepose_variant = \"full\""
                } else {
                    "it is part of the checkout (models/)"
                };
                format!("BlazePose model {relative} not found: {how}")
            })
        }
    }
}

/// Loads an SCHP-contract ONNX model and its sidecar (`model.json`) into an
/// [`OnnxSegmenter`].
///
/// # Errors
/// The model or sidecar cannot be read, the sidecar is invalid, the runtime library is
/// missing, or the model does not follow the contract; each names the file.
pub(crate) fn load_onnx_segmenter(config: &PipelineConfig, model: &Path) -> Result<OnnxSegmenter> {
    let sidecar = sidecar_path(model);
    let text = bodyseg_io::read_text(&sidecar)
        .context("model sidecar (the model's .json: input_size, channel_order, mean, std, ...)")?;
    let spec = ModelSpec::from_json(&text, &sidecar)?;
    let library = resolve_runtime_library(config)?;
    let bytes = bodyseg_io::read_bytes(model).context("parsing model")?;
    let segmenter = OnnxSegmenter::new(
        &library,
        &bytes,
        model,
        spec,
        &config.parsing.onnx_options(),
    )?;
    Ok(segmenter)
}

/// Loads the configured parser's model `model` ([`resolve_model`]): a
/// [`BlazePoseSegmenter`] for `parsing.segmenter = "blazepose"`, an [`OnnxSegmenter`] (with
/// its sidecar) for `"onnx"`.
///
/// # Errors
/// As [`load_onnx_segmenter`]; a BlazePose model that is not BlazePose-shaped.
pub(crate) fn load_segmenter(
    config: &PipelineConfig,
    model: &Path,
) -> Result<Box<dyn Segmenter + Send>> {
    Ok(match config.parsing.segmenter {
        SegmenterKind::Onnx => Box::new(load_onnx_segmenter(config, model)?),
        SegmenterKind::Blazepose => {
            let library = resolve_runtime_library(config)?;
            let bytes = bodyseg_io::read_bytes(model).context("BlazePose landmark model")?;
            Box::new(BlazePoseSegmenter::new(
                &library,
                &bytes,
                model,
                &config.parsing.blazepose_options(),
            )?)
        }
    })
}

/// The segmenter `choice` asks for on `rec`, and whether it is the model:
/// [`ParserChoice::Auto`] takes the recorded predictions when every camera has a
/// `parsing/` folder, else the model.
///
/// # Errors
/// Recorded predictions are asked for and the recording has none; the model, its sidecar
/// or the ONNX Runtime library is missing or invalid.
pub(crate) fn open_segmenter(
    choice: ParserChoice,
    rec: &Recording,
    config: &PipelineConfig,
) -> Result<(Box<dyn Segmenter + Send>, bool)> {
    let recorded_present = rec.has_layer(Layer::Parsing);
    let use_model = match choice {
        ParserChoice::Model => true,
        ParserChoice::Recorded => {
            if !recorded_present {
                bail!(
                    "{}: no <camera>/parsing/ folders (recorded predictions); run with \
                     --parser model",
                    rec.root().display()
                );
            }
            false
        }
        ParserChoice::Auto => !recorded_present,
    };
    let segmenter: Box<dyn Segmenter + Send> = if use_model {
        let model = resolve_model(config)?;
        load_segmenter(config, &model)?
    } else {
        Box::new(RecordedSegmenter::new())
    };
    Ok((segmenter, use_model))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explicit_paths_win() {
        let mut cfg = PipelineConfig::default();
        cfg.parsing.runtime_library = "/x/libonnxruntime.so".into();
        cfg.parsing.model = "m.onnx".into();
        cfg.parsing.segmenter = SegmenterKind::Onnx;
        assert_eq!(
            resolve_runtime_library(&cfg).expect("configured"),
            Path::new("/x/libonnxruntime.so")
        );
        assert_eq!(
            resolve_model(&cfg).expect("configured"),
            Path::new("m.onnx")
        );
        // BlazePose: the variant's model in the checkout.
        cfg.parsing.segmenter = SegmenterKind::Blazepose;
        let full = resolve_model(&cfg).expect("models/blazepose_full.onnx is in git");
        assert!(full.ends_with("models/blazepose_full.onnx"), "{full:?}");
    }
}
