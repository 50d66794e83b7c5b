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
//! KEY=VALUE (BlazePose only): `parts=bodypix|landmarks` (`parsing.body_parts`; default
//! landmarks) with `bodypix_margin`, `bodypix_long_side`, `bodypix_threshold`,
//! `bodypix_background_below`, `drop_detached` (0/1); `roi_scale`,
//! `refine_passes`, `threads`, `min_pose_flag`, the switches `blank_retry`,
//! `mirror_average`, `flat_shoulders`, `thighs_past_frame` (0/1),
//! any numeric field of the rule's `RuleConfig` (`r_torso=0.3`, ...), and `poses=1` to
//! write each image's poses as `<name>.poses.json` beside its PNG (for overlays). Time it with
//! `perf stat -e task-clock,instructions:u` (the machine is shared: wall clock says little).

mod data;

use anyhow::{Context, bail};
use bodyseg_core::Label;
use bodyseg_parsing::blazepose::{DecodedPose, RuleConfig};
use bodyseg_parsing::{
    BlazePoseOptions, BlazePoseSegmenter, BodyParts, ModelSpec, OnnxOptions, OnnxSegmenter,
    Segmenter, sidecar_path,
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

/// The rule's settings the example takes as KEY=VALUE (numbers), with where they go.
fn rule_field<'a>(rule: &'a mut RuleConfig, key: &str) -> Option<&'a mut f64> {
    Some(match key {
        "mask_threshold" => &mut rule.mask_threshold,
        "min_presence" => &mut rule.min_presence,
        "min_visibility" => &mut rule.min_visibility,
        "r_head" => &mut rule.r_head,
        "face_to_width" => &mut rule.face_to_width,
        "head_down" => &mut rule.head_down,
        "head_up" => &mut rule.head_up,
        "r_torso" => &mut rule.r_torso,
        "r_upper_arm" => &mut rule.r_upper_arm,
        "r_lower_arm" => &mut rule.r_lower_arm,
        "r_upper_leg" => &mut rule.r_upper_leg,
        "r_lower_leg" => &mut rule.r_lower_leg,
        "hand_extend" => &mut rule.hand_extend,
        "torso_bias" => &mut rule.torso_bias,
        "behind_torso_depth" => &mut rule.behind_torso_depth,
        "max_score" => &mut rule.max_score,
        "margin_scale" => &mut rule.margin_scale,
        _ => return None,
    })
}

/// What runs: BlazePose (whose poses can be written out) or any other segmenter.
enum Opened {
    BlazePose {
        segmenter: Box<BlazePoseSegmenter>,
        /// Write `<name>.poses.json` beside each label PNG (setting `poses=1`).
        write_poses: bool,
    },
    Other(Box<dyn Segmenter>),
}

/// The segmenter `which` names, with BlazePose's `settings` applied.
fn open(which: &str, settings: &[String]) -> anyhow::Result<Opened> {
    let library = runtime_library();
    if let Some(variant) = which.strip_prefix("blazepose:") {
        let mut options = BlazePoseOptions::default();
        let mut write_poses = false;
        let mut parts = BodyParts::Landmarks;
        for s in settings {
            let (key, value) = s
                .split_once('=')
                .with_context(|| format!("{s}: expected KEY=VALUE"))?;
            let bad = |e: &dyn std::fmt::Display| anyhow::anyhow!("{key}={value}: {e}");
            match key {
                "roi_scale" => options.roi_scale = value.parse().map_err(|e| bad(&e))?,
                "refine_passes" => options.refine_passes = value.parse().map_err(|e| bad(&e))?,
                "threads" => options.threads = value.parse().map_err(|e| bad(&e))?,
                "min_pose_flag" => options.min_pose_flag = value.parse().map_err(|e| bad(&e))?,
                "poses" => write_poses = value == "1",
                "parts" => {
                    parts = match value {
                        "bodypix" => BodyParts::Bodypix,
                        "landmarks" => BodyParts::Landmarks,
                        _ => bail!("parts={value}: bodypix or landmarks"),
                    }
                }
                "bodypix_margin" => options.bodypix.margin = value.parse().map_err(|e| bad(&e))?,
                "bodypix_long_side" => {
                    options.bodypix.long_side = value.parse().map_err(|e| bad(&e))?
                }
                "bodypix_threshold" => {
                    options.bodypix.threshold = value.parse().map_err(|e| bad(&e))?
                }
                "bodypix_background_below" => {
                    options.bodypix_background_below = value.parse().map_err(|e| bad(&e))?
                }
                "drop_detached" => options.drop_detached = value == "1",
                "blank_retry" => options.blank_retry = value == "1",
                "mirror_average" => options.mirror_average = value == "1",
                "flat_shoulders" => options.rule.flat_shoulders = value == "1",
                "thighs_past_frame" => options.rule.thighs_past_frame = value == "1",
                _ => match rule_field(&mut options.rule, key) {
                    Some(field) => *field = value.parse().map_err(|e| bad(&e))?,
                    None => bail!(
                        "{key}: unknown setting (parts, bodypix_margin, bodypix_long_side, \
                         bodypix_threshold, bodypix_background_below, drop_detached, roi_scale, \
                         refine_passes, threads, min_pose_flag, poses, or a RuleConfig field; booleans 0/1)"
                    ),
                },
            }
        }
        let model = root().join(format!("models/blazepose_{variant}.onnx"));
        let bytes = std::fs::read(&model).with_context(|| model.display().to_string())?;
        let mut segmenter = BlazePoseSegmenter::new(&library, &bytes, &model, &options)?;
        if parts == BodyParts::Bodypix {
            let model = root().join("models/bodypix_mobilenet_v1_075_quant.onnx");
            let bytes = std::fs::read(&model).with_context(|| model.display().to_string())?;
            segmenter = segmenter.with_bodypix(&library, &bytes, &model)?;
        }
        return Ok(Opened::BlazePose {
            segmenter: Box::new(segmenter),
            write_poses,
        });
    }
    if let Some(model) = which.strip_prefix("onnx:") {
        let model = PathBuf::from(model);
        let sidecar = sidecar_path(&model);
        let text =
            std::fs::read_to_string(&sidecar).with_context(|| sidecar.display().to_string())?;
        let spec = ModelSpec::from_json(&text, &sidecar)?;
        let bytes = std::fs::read(&model).with_context(|| model.display().to_string())?;
        return Ok(Opened::Other(Box::new(OnnxSegmenter::new(
            &library,
            &bytes,
            &model,
            spec,
            &OnnxOptions::default(),
        )?)));
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
    let mut opened = open(which, settings)?;
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out).with_context(|| out.display().to_string())?;
    for item in &items {
        let path = dir.join("images").join(format!("{}.jpg", item.name));
        let image = bodyseg_io::read_rgb_image(&path)?;
        let views = [item.view(&image)];
        if let Opened::BlazePose {
            segmenter,
            write_poses: true,
        } = &mut opened
        {
            let poses = segmenter
                .poses(&image, Some(&item.regions))
                .with_context(|| path.display().to_string())?;
            let file = out.join(format!("{}.poses.json", item.name));
            std::fs::write(&file, poses_json(&poses).to_string())
                .with_context(|| file.display().to_string())?;
        }
        let segmenter: &mut dyn Segmenter = match &mut opened {
            Opened::BlazePose { segmenter, .. } => segmenter.as_mut(),
            Opened::Other(segmenter) => segmenter.as_mut(),
        };
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
    let holdout = items
        .iter()
        .filter(|i| i.split.as_deref() == Some("holdout"))
        .count();
    eprintln!(
        "{} images ({exact} with exact 7-class ground truth; {holdout} hold-out) -> {}",
        items.len(),
        out.display()
    );
    Ok(())
}

/// One image's poses (region order; `null` where a region has none): flag, ROI, and per
/// landmark x, y, depth (image px), visibility, presence.
fn poses_json(poses: &[Option<DecodedPose>]) -> serde_json::Value {
    serde_json::Value::Array(
        poses
            .iter()
            .map(|pose| match pose {
                None => serde_json::Value::Null,
                Some(p) => serde_json::json!({
                    "flag": p.flag,
                    "roi": {
                        "centre_px": p.roi.centre_px,
                        "side_px": p.roi.side_px,
                        "angle_rad": p.roi.angle_rad,
                    },
                    "xy": p.xy,
                    "visibility": p.visibility,
                    "presence": p.presence,
                    "depth_px": p.depth_px,
                }),
            })
            .collect(),
    )
}
