//! `bodyseg parse`: one frame of a recording (rig.toml, colour images) → 2D body-part
//! label images (class ids) and palette previews, per camera.

use crate::config::PipelineConfig;
use crate::frame::{FrameNeeds, ParsedFrame, parse_frame, read_one_frame};
use crate::model::{load_segmenter, resolve_model};
use crate::outputs::{check_output_folder, write_text};
use crate::recording::{Layer, Layout, Recording, check_stem};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result};
use bodyseg_core::{Class, LabelImage, RgbImage};
use bodyseg_parsing::{RecordedSegmenter, Segmenter, SegmenterKind};
use std::path::PathBuf;

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

/// A palette preview: body pixels in their class colour, background as the dimmed image.
pub(crate) fn palette_preview(image: &RgbImage, labels: &LabelImage) -> Vec<u8> {
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
    check_output_folder(&opts.out, "--recording", &opts.recording)?;
    let cfg = &opts.config;
    // The colour images for the previews; the recorded predictions for --recorded; the
    // depth images, where the recording has them, for a parser that takes the people found
    // from depth (BlazePose).
    let people_from_depth =
        opts.source == ParseSource::Model && cfg.parsing.segmenter == SegmenterKind::Blazepose;
    let needs = |rec: &Recording| FrameNeeds {
        color: true,
        parsing: opts.source == ParseSource::Recorded,
        depth: people_from_depth && rec.has_layer(Layer::Depth),
        ..FrameNeeds::default()
    };
    let images = ("colour image", "colour images");
    let (rec, frame, read) = read_one_frame(&opts.recording, &opts.frame, needs, images)?;
    let cameras: Vec<String> = rec.cameras().map(str::to_string).collect();
    let mut stages = vec![read];

    let model = match opts.source {
        ParseSource::Model => Some(resolve_model(cfg)?.0),
        ParseSource::Recorded => None,
    };
    let (parsed, took) = timed(|| -> Result<ParsedFrame> {
        let mut segmenter: Box<dyn Segmenter> = match &model {
            Some(path) => load_segmenter(cfg, path)?,
            None => Box::new(RecordedSegmenter::new()),
        };
        parse_frame(frame, rec.rig(), segmenter.as_mut(), cfg)
            .with_context(|| format!("{}: frame {}", opts.recording.display(), opts.frame))
    })?;
    let images = parsed
        .frame
        .color
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
        if let Some(path) = &model
            && cfg.parsing.segmenter == SegmenterKind::Onnx
        {
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
}
