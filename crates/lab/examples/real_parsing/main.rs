//! Runs bodyseg's parsers on the real photographs of `scripts/real_parsing_data.py`
//! (.data/real_parsing/) and writes one label PNG per image (class ids 0–6) for
//! `scripts/score_parsing.py`. The index's person boxes are the regions (they stand in for
//! the boxes found from depth).
//!
//! ```text
//! cargo run --release -p bodyseg-lab --example real_parsing -- OUT_DIR blazepose:full [KEY=VALUE ...]
//! cargo run --release -p bodyseg-lab --example real_parsing -- OUT_DIR onnx:models/bodyseg_parser_small.onnx
//! ```
//!
//! KEY=VALUE (BlazePose only): `roi_scale`, `refine_passes`, `threads`, and the rule's
//! `min_presence`, `min_visibility`. Time it with
//! `perf stat -e task-clock,instructions:u` (the machine is shared: wall clock says little).

mod data;

use anyhow::{Context, bail};
use bodyseg_core::Label;
use bodyseg_parsing::{
    BlazePoseOptions, BlazePoseSegmenter, ModelSpec, OnnxOptions, OnnxSegmenter, Segmenter,
    sidecar_path,
};
use std::path::{Path, PathBuf};

const USAGE: &str =
    "usage: real_parsing OUT_DIR (blazepose:lite|full|heavy | onnx:MODEL) [KEY=VALUE ...]";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn runtime_library() -> PathBuf {
    std::env::var_os("ORT_DYLIB_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".deps/onnxruntime/libonnxruntime.so"))
}

/// The segmenter `which` names, with BlazePose's `settings` applied.
fn open(which: &str, settings: &[String]) -> anyhow::Result<Box<dyn Segmenter>> {
    let library = runtime_library();
    if let Some(variant) = which.strip_prefix("blazepose:") {
        let mut options = BlazePoseOptions::default();
        for s in settings {
            let (key, value) = s
                .split_once('=')
                .with_context(|| format!("{s}: expected KEY=VALUE"))?;
            let bad = |e: &dyn std::fmt::Display| anyhow::anyhow!("{key}={value}: {e}");
            match key {
                "roi_scale" => options.roi_scale = value.parse().map_err(|e| bad(&e))?,
                "refine_passes" => options.refine_passes = value.parse().map_err(|e| bad(&e))?,
                "threads" => options.threads = value.parse().map_err(|e| bad(&e))?,
                "min_presence" => options.rule.min_presence = value.parse().map_err(|e| bad(&e))?,
                "min_visibility" => {
                    options.rule.min_visibility = value.parse().map_err(|e| bad(&e))?;
                }
                _ => bail!(
                    "{key}: unknown setting (roi_scale, refine_passes, threads, min_presence, \
                     min_visibility)"
                ),
            }
        }
        let model = root().join(format!("models/blazepose_{variant}.onnx"));
        let bytes = std::fs::read(&model).with_context(|| model.display().to_string())?;
        return Ok(Box::new(BlazePoseSegmenter::new(
            &library, &bytes, &model, &options,
        )?));
    }
    if let Some(model) = which.strip_prefix("onnx:") {
        let model = PathBuf::from(model);
        let sidecar = sidecar_path(&model);
        let text =
            std::fs::read_to_string(&sidecar).with_context(|| sidecar.display().to_string())?;
        let spec = ModelSpec::from_json(&text, &sidecar)?;
        let bytes = std::fs::read(&model).with_context(|| model.display().to_string())?;
        return Ok(Box::new(OnnxSegmenter::new(
            &library,
            &bytes,
            &model,
            spec,
            &OnnxOptions::default(),
        )?));
    }
    bail!("{which}: {USAGE}")
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, which, settings @ ..] = &args[..] else {
        bail!("{USAGE}");
    };
    let dir = data::default_dir();
    let items = data::read_index(&dir)
        .context("run .venv/bin/python scripts/real_parsing_data.py first")?;
    let mut segmenter = open(which, settings)?;
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out).with_context(|| out.display().to_string())?;
    for item in &items {
        let path = dir.join("images").join(format!("{}.jpg", item.name));
        let image = bodyseg_io::read_rgb_image(&path)?;
        let views = [item.view(&image)];
        let mut parsed = segmenter
            .segment(&views)
            .with_context(|| path.display().to_string())?;
        let mut labels = parsed.pop().context("one view in, none out")?.labels;
        // The scorer takes class ids 0–6; a pixel no class claims is background.
        for l in &mut labels.labels {
            if *l == Label::UNKNOWN {
                *l = Label::BACKGROUND;
            }
        }
        bodyseg_io::write_label_png(&out.join(format!("{}.png", item.name)), &labels)?;
    }
    let exact = items.iter().filter(|i| i.scheme == "parts7").count();
    eprintln!(
        "{} images ({exact} with exact 7-class ground truth) -> {}",
        items.len(),
        out.display()
    );
    Ok(())
}
