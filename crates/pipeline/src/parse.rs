//! `bodyseg parse`: one frame of a recording (rig.toml, colour images) → 2D body-part
//! label images (class ids) and palette previews, per camera.

use crate::config::PipelineConfig;
use crate::frame::{Frame, FrameNeeds, ParsedFrame, parse_frame};
use crate::fs::write_text;
use crate::recording::{Layer, Layout, Recording, check_stem};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result};
use bodyseg_core::{Class, LabelImage, RgbImage};
use bodyseg_parsing::{ModelSpec, OnnxSegmenter, RecordedSegmenter, Segmenter, sidecar_path};
use std::path::{Path, PathBuf};

/// The bundled model, relative to the project root (its sidecar: the same with `.json`).
pub const BUNDLED_MODEL: &str = "models/bodyseg_parser_small.onnx";

/// Where `scripts/setup_onnxruntime.sh` puts the ONNX Runtime library, relative to the
/// project root.
pub const LOCAL_RUNTIME_LIBRARY: &str = ".deps/onnxruntime/libonnxruntime.so";

/// Environment variable naming the ONNX Runtime library (ort's convention).
pub const RUNTIME_LIBRARY_ENV: &str = "ORT_DYLIB_PATH";

/// Which segmenter [`parse_file`] runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ParseSource {
    /// An ONNX model (`parsing.model` of the configuration, or the bundled one).
    Model,
    /// The recording's own `parsing/` label images (synthetic predictions, or a parser
    /// run elsewhere), through [`RecordedSegmenter`].
    Recorded,
}

/// What [`parse_file`] reads, writes and how.
#[derive(Clone, Debug)]
pub struct ParseOptions {
    /// The recording folder: `rig.toml` and per camera `<camera>/color/<frame>.png` (or
    /// `.jpg`, `.jpeg`).
    pub recording: PathBuf,
    /// The frame's file stem (`000012`).
    pub frame: String,
    /// The resolved configuration; its `[parsing]` section is used.
    pub config: PipelineConfig,
    /// Which segmenter runs.
    pub source: ParseSource,
    /// Output folder: `<camera>/parsing/<frame>.png` (8-bit class ids) and
    /// `<camera>/parsing_preview/<frame>.png` (palette over the dimmed image) per camera,
    /// and `parse.config.resolved.toml`. Created if missing; existing files of the same
    /// names are replaced.
    pub out: PathBuf,
}

/// What [`parse_file`] did.
#[derive(Clone, Debug)]
pub struct ParseSummary {
    /// Camera names, rig order.
    pub cameras: Vec<String>,
    /// Pixels labelled as a body part (not background), per camera.
    pub body_pixels: Vec<usize>,
    /// The model file that ran (`None` for recorded labels).
    pub model: Option<PathBuf>,
    /// Files written: label images, then previews, then the resolved configuration.
    pub written: Vec<PathBuf>,
    /// Per stage (read, parse, write): time and a one-line summary.
    pub stages: Vec<Stage>,
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
pub fn resolve_runtime_library(config: &PipelineConfig) -> Result<PathBuf> {
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

/// The model file: `parsing.model`, else the bundled model.
///
/// # Errors
/// The bundled model is not found (neither beside the executable, in the current folder,
/// nor in the checkout the binary was built from).
pub fn resolve_model(config: &PipelineConfig) -> Result<PathBuf> {
    if !config.parsing.model.is_empty() {
        return Ok(PathBuf::from(&config.parsing.model));
    }
    bodyseg_io::first_existing_file(&project_candidates(BUNDLED_MODEL))
        .with_context(|| format!("bundled model {BUNDLED_MODEL} not found: pass --model FILE.onnx"))
}

/// Loads an ONNX model and its sidecar (`model.json`) into an [`OnnxSegmenter`].
///
/// # Errors
/// The model or sidecar cannot be read, the sidecar is invalid, the runtime library is
/// missing, or the model does not follow the contract; each names the file.
pub fn load_segmenter(config: &PipelineConfig, model: &Path) -> Result<OnnxSegmenter> {
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

/// A palette preview: body pixels in their class colour, background as the dimmed image.
pub fn palette_preview(image: &RgbImage, labels: &LabelImage) -> Vec<u8> {
    let mut out = Vec::with_capacity(labels.num_pixels() * 3);
    for (i, label) in labels.labels.iter().enumerate() {
        match label.class().filter(|c| *c != Class::Background) {
            Some(class) => out.extend(class.color()),
            None => {
                let px = image.rgb.get(3 * i..3 * i + 3).unwrap_or(&[0, 0, 0]);
                out.extend(px.iter().map(|&v| v / 3));
            }
        }
    }
    out
}

/// Runs 2D parsing on every camera of one frame and writes the label images and
/// previews (see [`ParseOptions::out`]).
///
/// # Errors
/// The frame stem is a path; `rig.toml` cannot be read; a colour image is missing, does
/// not decode or has another size than the rig's colour sensor; the model, its sidecar or
/// the ONNX Runtime library is missing or invalid; writing fails. Each names the file.
/// Nothing is written unless every view was parsed.
pub fn parse_file(opts: &ParseOptions) -> Result<ParseSummary> {
    check_stem(&opts.frame)?;
    let cfg = &opts.config;
    // The colour images for the previews; the recorded predictions for --recorded.
    let needs = FrameNeeds {
        colour: true,
        parsing: opts.source == ParseSource::Recorded,
        ..FrameNeeds::default()
    };
    let ((rec, frame), read) = timed(|| -> Result<_> {
        let rec = Recording::open(&opts.recording)?;
        let frame = Frame::read(&rec, &opts.frame, needs)?;
        Ok((rec, frame))
    })?;
    let cameras: Vec<String> = rec.cameras().map(str::to_string).collect();
    let mut stages = vec![Stage::new(
        "read",
        read,
        format!(
            "{}, frame {}",
            plural(cameras.len(), "colour image", "colour images"),
            opts.frame
        ),
    )];

    let model = match opts.source {
        ParseSource::Model => Some(resolve_model(cfg)?),
        ParseSource::Recorded => None,
    };
    let (parsed, took) = timed(|| -> Result<ParsedFrame> {
        let mut segmenter: Box<dyn Segmenter> = match &model {
            Some(path) => Box::new(load_segmenter(cfg, path)?),
            None => Box::new(RecordedSegmenter::new()),
        };
        parse_frame(frame, rec.rig(), segmenter.as_mut())
            .with_context(|| format!("{}: frame {}", opts.recording.display(), opts.frame))
    })?;
    let images = parsed
        .frame
        .colour
        .as_deref()
        .context("the colour images were read")?;
    let body_pixels: Vec<usize> = parsed
        .labels
        .iter()
        .map(|labels| {
            labels
                .labels
                .iter()
                .filter(|l| l.class().is_some_and(|c| c != Class::Background))
                .count()
        })
        .collect();
    let per_view_ms = took.as_secs_f64() * 1e3 / cameras.len().max(1) as f64;
    let what = match &model {
        Some(path) => format!(
            "model {}, {per_view_ms:.0} ms per view incl. loading the model",
            path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            )
        ),
        None => "recorded parsing/ labels".to_string(),
    };
    stages.push(Stage::new(
        "parse",
        took,
        format!(
            "{} ({what}), {} body pixels",
            plural(parsed.labels.len(), "view", "views"),
            body_pixels.iter().sum::<usize>()
        ),
    ));

    let (written, took) = timed(|| -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        let out = Layout::new(&opts.out);
        for ((camera, image), labels) in cameras.iter().zip(images).zip(&parsed.labels) {
            let labels_path = out.image_path(camera, Layer::Parsing, &opts.frame)?;
            let preview_path = out.parsing_preview_path(camera, &opts.frame)?;
            for p in [&labels_path, &preview_path] {
                if let Some(parent) = p.parent() {
                    bodyseg_io::create_folder(parent).context("output folder (--out)")?;
                }
            }
            bodyseg_io::write_label_png(&labels_path, labels)
                .with_context(|| format!("camera {camera}: label image"))?;
            let (w, h) = (labels.width, labels.height);
            bodyseg_io::write_rgb_png(&preview_path, w, h, &palette_preview(image, labels))
                .with_context(|| format!("camera {camera}: preview"))?;
            written.push(labels_path);
            written.push(preview_path);
        }
        let mut resolved = cfg.clone();
        if let Some(path) = &model {
            resolved.parsing.model = path.display().to_string();
        }
        let config_path = opts.out.join("parse.config.resolved.toml");
        write_text(&config_path, &resolved.resolved_toml()?).context("resolved configuration")?;
        written.push(config_path);
        Ok(written)
    })?;
    stages.push(Stage::new(
        "write",
        took,
        format!(
            "{} in {}",
            plural(written.len(), "file", "files"),
            opts.out.display()
        ),
    ));
    Ok(ParseSummary {
        cameras,
        body_pixels,
        model,
        written,
        stages,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::Label;

    #[test]
    fn preview_paints_body_parts_and_dims_background() {
        let image = RgbImage::new(2, 1, vec![90, 60, 30, 90, 60, 30]).expect("2x1");
        let labels = LabelImage::new(2, 1, vec![Label::BACKGROUND, Label::from(Class::Head)])
            .expect("2 labels");
        assert_eq!(
            palette_preview(&image, &labels),
            vec![30, 20, 10, 128, 0, 0]
        );
    }

    #[test]
    fn explicit_paths_win() {
        let mut cfg = PipelineConfig::default();
        cfg.parsing.runtime_library = "/x/libonnxruntime.so".into();
        cfg.parsing.model = "m.onnx".into();
        assert_eq!(
            resolve_runtime_library(&cfg).expect("configured"),
            Path::new("/x/libonnxruntime.so")
        );
        assert_eq!(
            resolve_model(&cfg).expect("configured"),
            Path::new("m.onnx")
        );
    }
}
