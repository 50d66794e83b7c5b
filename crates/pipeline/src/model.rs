//! Where the 2D parser comes from: BlazePose's landmark model (`parsing.segmenter =
//! "blazepose"`, the default) or an SCHP-contract ONNX model (`"onnx"`), the ONNX Runtime
//! library, or a recording's own predictions; [`open_segmenter`] makes the [`Segmenter`] of `bodyseg run`
//! and `convert`.
//!
//! # Where the library and the model are looked for
//! A shared library is code: it is loaded only from a place the user or the installer
//! chose, never from the current folder or a folder above the executable (a planted
//! `.deps/onnxruntime/libonnxruntime.so` in `/tmp` must not run). In this order:
//!
//! 1. `parsing.runtime_library` (configuration, `--set`);
//! 2. the `ORT_DYLIB_PATH` environment variable;
//! 3. the install prefix: `<prefix>/lib/bodyseg/libonnxruntime.so`, where the executable
//!    is `<prefix>/bin/bodyseg` (a prefix install: `bin/bodyseg`,
//!    `lib/bodyseg/libonnxruntime.so`, `share/bodyseg/models/bodyseg_parser_small.onnx`
//!    and its `.json`);
//! 4. the checkout the binary was built from (a path fixed at build time):
//!    `.deps/onnxruntime/libonnxruntime.so`, where `scripts/setup_onnxruntime.sh` puts it.
//!
//! The bundled models follow the same rule (a model is data, but a planted one would
//! mislead): `parsing.model` (for `"onnx"`), else `<prefix>/share/bodyseg/models/…`, else
//! the checkout's `models/` (`bodyseg_parser_small.onnx`, `blazepose_<variant>.onnx`,
//! `bodypix_mobilenet_v1_075_quant.onnx` for `parsing.body_parts = "bodypix"`). [`describe_parser_files`] says what would be
//! loaded (`bodyseg version -v`).

use crate::config::PipelineConfig;
use crate::recording::{Layer, Recording};
use anyhow::{Context, Result, bail};
use bodyseg_parsing::{BlazePoseSegmenter, BlazePoseVariant, BodyParts};
use bodyseg_parsing::{
    ModelSpec, OnnxSegmenter, RecordedSegmenter, Segmenter, SegmenterKind, sidecar_path,
};
use std::fmt;
use std::path::{Path, PathBuf};

/// The bundled SCHP-contract model, relative to the checkout (its sidecar: the same with
/// `.json`).
pub(crate) const BUNDLED_MODEL: &str = "models/bodyseg_parser_small.onnx";

/// The bundled model, relative to an install prefix.
pub(crate) const PREFIX_MODEL: &str = "share/bodyseg/models/bodyseg_parser_small.onnx";

/// BlazePose's landmark model of a variant, relative to the checkout (the same under
/// `<prefix>/share/bodyseg/` for an install).
pub(crate) fn blazepose_model(variant: BlazePoseVariant) -> String {
    format!("models/blazepose_{}.onnx", variant.name())
}

/// BodyPix's model (`parsing.body_parts = "bodypix"`), relative to the checkout (the same
/// under `<prefix>/share/bodyseg/` for an install).
pub(crate) const BODYPIX_MODEL: &str = "models/bodypix_mobilenet_v1_075_quant.onnx";

/// BodyPix's model file: the install prefix's, else the checkout's.
///
/// # Errors
/// Neither exists.
fn resolve_bodypix_model() -> Result<(PathBuf, FoundBy)> {
    let exe = std::env::current_exe().ok();
    let prefix_relative = format!("share/bodyseg/{BODYPIX_MODEL}");
    first_file(bundled_candidates(
        exe.as_deref(),
        &prefix_relative,
        BODYPIX_MODEL,
    ))
    .with_context(|| {
        format!(
            "BodyPix model {BODYPIX_MODEL} not found (checkout or <prefix>/{prefix_relative}): \
                 it is part of the checkout (models/), or use parsing.body_parts = \"landmarks\""
        )
    })
}

/// Where `scripts/setup_onnxruntime.sh` puts the ONNX Runtime library, relative to the
/// checkout.
pub(crate) const LOCAL_RUNTIME_LIBRARY: &str = ".deps/onnxruntime/libonnxruntime.so";

/// The ONNX Runtime library of a prefix install, relative to the prefix.
pub(crate) const PREFIX_RUNTIME_LIBRARY: &str = "lib/bodyseg/libonnxruntime.so";

/// Environment variable naming the ONNX Runtime library (ort's convention).
pub(crate) const RUNTIME_LIBRARY_ENV: &str = "ORT_DYLIB_PATH";

/// Where a run's 2D labels come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ParserChoice {
    /// Recorded predictions when the recording has `parsing/` folders, else the model.
    #[default]
    Auto,
    /// The ONNX model (`parsing.model`, or the bundled one) on the colour images.
    Model,
    /// The recording's `<camera>/parsing/<frame>.png`.
    Recorded,
}

/// Which rule found a file ([`resolve_runtime_library`], [`resolve_model`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoundBy {
    /// The configuration (`parsing.runtime_library`, `parsing.model`).
    Config,
    /// The `ORT_DYLIB_PATH` environment variable.
    Environment,
    /// The install prefix of the executable (`<prefix>/bin/bodyseg`).
    Prefix,
    /// The checkout the binary was built from.
    Checkout,
}

impl fmt::Display for FoundBy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FoundBy::Config => "the configuration",
            FoundBy::Environment => RUNTIME_LIBRARY_ENV,
            FoundBy::Prefix => "the install prefix",
            FoundBy::Checkout => "the checkout bodyseg was built from",
        })
    }
}

/// The places a bundled file may be, in order: the install prefix of `exe`
/// (`<exe>/../../<prefix_relative>`) and the checkout this binary was built from. Never
/// the current folder, never another folder above the executable.
fn bundled_candidates(
    exe: Option<&Path>,
    prefix_relative: &str,
    checkout_relative: &str,
) -> Vec<(PathBuf, FoundBy)> {
    let mut out = Vec::new();
    if let Some(prefix) = exe.and_then(Path::parent).and_then(Path::parent) {
        out.push((prefix.join(prefix_relative), FoundBy::Prefix));
    }
    out.push((checkout_root().join(checkout_relative), FoundBy::Checkout));
    out
}

/// The checkout this binary was built from (fixed at build time).
fn checkout_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The first candidate that is a file.
fn first_file(candidates: Vec<(PathBuf, FoundBy)>) -> Option<(PathBuf, FoundBy)> {
    candidates.into_iter().find(|(p, _)| p.is_file())
}

/// The ONNX Runtime library and the rule that found it (see the module documentation):
/// `parsing.runtime_library`, else `ORT_DYLIB_PATH`, else the install prefix's, else the
/// checkout's copy of `scripts/setup_onnxruntime.sh`.
///
/// # Errors
/// None of them is set or exists; the message says how to get the library.
pub(crate) fn resolve_runtime_library(config: &PipelineConfig) -> Result<(PathBuf, FoundBy)> {
    let exe = std::env::current_exe().ok();
    let env = std::env::var_os(RUNTIME_LIBRARY_ENV);
    runtime_library_from(config, env.as_deref(), exe.as_deref())
}

/// [`resolve_runtime_library`] with the environment variable's value and the executable's
/// path given.
fn runtime_library_from(
    config: &PipelineConfig,
    env: Option<&std::ffi::OsStr>,
    exe: Option<&Path>,
) -> Result<(PathBuf, FoundBy)> {
    if !config.parsing.runtime_library.is_empty() {
        return Ok((
            PathBuf::from(&config.parsing.runtime_library),
            FoundBy::Config,
        ));
    }
    if let Some(path) = env.filter(|p| !p.is_empty()) {
        return Ok((PathBuf::from(path), FoundBy::Environment));
    }
    first_file(bundled_candidates(
        exe,
        PREFIX_RUNTIME_LIBRARY,
        LOCAL_RUNTIME_LIBRARY,
    ))
    .with_context(|| {
        format!(
            "ONNX Runtime library not found: run scripts/setup_onnxruntime.sh (it writes \
             {LOCAL_RUNTIME_LIBRARY} in the checkout), install it as \
             <prefix>/{PREFIX_RUNTIME_LIBRARY}, or set {RUNTIME_LIBRARY_ENV} or \
             parsing.runtime_library to a libonnxruntime.so"
        )
    })
}

/// The model file of the configured parser and the rule that found it: for
/// `parsing.segmenter = "onnx"`, `parsing.model`, else the bundled model of the install
/// prefix or the checkout; for `"blazepose"`, `blazepose_<parsing.blazepose_variant>.onnx`
/// there.
///
/// # Errors
/// The model is not found; for the heavy BlazePose model the message says how to make it.
pub(crate) fn resolve_model(config: &PipelineConfig) -> Result<(PathBuf, FoundBy)> {
    let exe = std::env::current_exe().ok();
    model_from(config, exe.as_deref())
}

/// [`resolve_model`] with the executable's path given.
fn model_from(config: &PipelineConfig, exe: Option<&Path>) -> Result<(PathBuf, FoundBy)> {
    match config.parsing.segmenter {
        SegmenterKind::Onnx => {
            if !config.parsing.model.is_empty() {
                return Ok((PathBuf::from(&config.parsing.model), FoundBy::Config));
            }
            first_file(bundled_candidates(exe, PREFIX_MODEL, BUNDLED_MODEL)).with_context(|| {
                format!(
                    "bundled model not found ({BUNDLED_MODEL} of the checkout, \
                     <prefix>/{PREFIX_MODEL}): pass --model FILE.onnx"
                )
            })
        }
        SegmenterKind::Blazepose => {
            let variant = config.parsing.blazepose_variant;
            let relative = blazepose_model(variant);
            let prefix_relative = format!("share/bodyseg/{relative}");
            first_file(bundled_candidates(exe, &prefix_relative, &relative)).with_context(|| {
                let how = if variant == BlazePoseVariant::Heavy {
                    "make it with scripts/convert_blazepose.py (see its header), or use \
                     parsing.blazepose_variant = \"full\""
                } else {
                    "it is part of the checkout (models/)"
                };
                format!("BlazePose model {relative} not found (checkout or <prefix>/{prefix_relative}): {how}")
            })
        }
    }
}

/// What `bodyseg version -v` prints about the parser's files, one line each: the ONNX
/// Runtime library that would be loaded and the rule that found it, and the model. Loads
/// nothing.
pub fn describe_parser_files(config: &PipelineConfig) -> Vec<String> {
    let line = |what: &str, found: Result<(PathBuf, FoundBy)>| match found {
        Ok((path, by)) => format!("{what}: {} (from {by})", path.display()),
        Err(e) => format!("{what}: none ({e:#})"),
    };
    let mut lines = vec![
        line("ONNX Runtime library", resolve_runtime_library(config)),
        line("model", resolve_model(config)),
    ];
    if uses_bodypix(config) {
        lines.push(line("body parts model", resolve_bodypix_model()));
    }
    lines
}

/// Whether the configured parser takes its body parts from BodyPix.
fn uses_bodypix(config: &PipelineConfig) -> bool {
    config.parsing.segmenter == SegmenterKind::Blazepose
        && config.parsing.body_parts == BodyParts::Bodypix
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
    let (library, _) = resolve_runtime_library(config)?;
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
            let (library, _) = resolve_runtime_library(config)?;
            let bytes = bodyseg_io::read_bytes(model).context("BlazePose landmark model")?;
            let segmenter = BlazePoseSegmenter::new(
                &library,
                &bytes,
                model,
                &config.parsing.blazepose_options(),
            )?;
            if uses_bodypix(config) {
                let (bodypix, _) = resolve_bodypix_model()?;
                let bytes = bodyseg_io::read_bytes(&bodypix).context("BodyPix model")?;
                Box::new(segmenter.with_bodypix(&library, &bytes, &bodypix)?)
            } else {
                Box::new(segmenter)
            }
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
        let (model, _) = resolve_model(config)?;
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
            runtime_library_from(&cfg, Some("/y/lib.so".as_ref()), None).expect("configured"),
            (PathBuf::from("/x/libonnxruntime.so"), FoundBy::Config)
        );
        assert_eq!(
            resolve_model(&cfg).expect("configured"),
            (PathBuf::from("m.onnx"), FoundBy::Config)
        );
        cfg.parsing.runtime_library.clear();
        assert_eq!(
            runtime_library_from(&cfg, Some("/y/lib.so".as_ref()), None).expect("env"),
            (PathBuf::from("/y/lib.so"), FoundBy::Environment)
        );
        // BlazePose: the variant's model in the checkout.
        cfg.parsing.segmenter = SegmenterKind::Blazepose;
        let (full, by) = resolve_model(&cfg).expect("models/blazepose_full.onnx is in git");
        assert!(full.ends_with("models/blazepose_full.onnx"), "{full:?}");
        assert_eq!(by, FoundBy::Checkout);
    }

    /// A library planted in the current folder, or in a folder above the executable, is
    /// never chosen: only the install prefix's and the checkout's.
    #[test]
    fn a_planted_library_is_never_chosen() {
        let dir = tempfile::tempdir().expect("temp dir");
        let root = dir.path();
        let plant = |folder: &Path| {
            let lib = folder.join(LOCAL_RUNTIME_LIBRARY);
            std::fs::create_dir_all(lib.parent().expect("parent")).expect("mkdir");
            std::fs::write(&lib, b"not a library").expect("plant");
            lib
        };
        // An executable at ROOT/a/bin/bodyseg, libraries planted at ROOT, ROOT/a,
        // ROOT/a/bin (the old search's parents) and in the current folder.
        let exe = root.join("a/bin/bodyseg");
        let planted: Vec<PathBuf> = [root, &root.join("a"), &root.join("a/bin")]
            .into_iter()
            .map(plant)
            .collect();
        let candidates =
            bundled_candidates(Some(&exe), PREFIX_RUNTIME_LIBRARY, LOCAL_RUNTIME_LIBRARY);
        assert_eq!(
            candidates,
            [
                (root.join("a").join(PREFIX_RUNTIME_LIBRARY), FoundBy::Prefix),
                (
                    checkout_root().join(LOCAL_RUNTIME_LIBRARY),
                    FoundBy::Checkout
                )
            ]
        );
        let cfg = PipelineConfig::default();
        if let Ok((path, by)) = runtime_library_from(&cfg, None, Some(&exe)) {
            assert_eq!(by, FoundBy::Checkout, "{}", path.display());
            assert!(!planted.contains(&path));
        }
        // The install prefix's library is found.
        let installed = root.join("a").join(PREFIX_RUNTIME_LIBRARY);
        std::fs::create_dir_all(installed.parent().expect("parent")).expect("mkdir");
        std::fs::write(&installed, b"x").expect("install");
        assert_eq!(
            runtime_library_from(&cfg, Some("".as_ref()), Some(&exe)).expect("prefix"),
            (installed, FoundBy::Prefix)
        );
        let lines = describe_parser_files(&cfg);
        assert!(lines[0].starts_with("ONNX Runtime library: "), "{lines:?}");
        assert!(lines[1].starts_with("model: "), "{lines:?}");
    }
}
