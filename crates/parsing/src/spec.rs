//! [`ModelSpec`]: the sidecar JSON that describes a parsing model (ALGORITHM.md §2).

use crate::ParsingError;
use bodyseg_core::{Class, NUM_CLASSES};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest accepted square input side, pixels: far above any parsing network (SCHP: 473
/// or 512), low enough that a typo (`51200`) is caught before allocating gigabytes.
pub const MAX_INPUT_SIZE: u32 = 4096;

/// Order of the colour channels the model expects in its input tensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ChannelOrder {
    /// Red, green, blue.
    #[serde(rename = "RGB")]
    Rgb,
    /// Blue, green, red (SCHP, trained on OpenCV images).
    #[serde(rename = "BGR")]
    Bgr,
}

/// A model's sidecar (`model.json` next to `model.onnx`): how to feed it and read its
/// output. Field names are those of the JSON file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Input size `[height, width]`, pixels; must be square (SCHP's affine pre-processing
    /// maps the image into a square, ALGORITHM.md §2).
    pub input_size: [u32; 2],
    /// Channel order of the input tensor.
    pub channel_order: ChannelOrder,
    /// Per-channel mean, in `channel_order`, of pixels / 255 (SCHP BGR: 0.406, 0.456,
    /// 0.485).
    pub mean: [f32; 3],
    /// Per-channel standard deviation, in `channel_order`, of pixels / 255; each > 0
    /// (SCHP BGR: 0.225, 0.224, 0.229).
    pub std: [f32; 3],
    /// Names of the output channels, in order; must be the 7 classes of ALGORITHM.md §0
    /// (case and spaces are ignored: `Upper Arms` = `upper_arms`).
    pub class_names: Vec<String>,
    /// Input size / logits size: 4 for SCHP's fusion head (512 → 128), 1 for full-size
    /// logits. The model's output size must be `ceil` or `floor` of input / stride.
    pub output_stride: u32,
    /// Whether the logits are upsampled with `align_corners = true` (SCHP) or false.
    pub align_corners: bool,
    /// Free text: where the model comes from, how it was trained.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
}

impl ModelSpec {
    /// SCHP's values (Pascal-Person-Part checkpoint exported at 512×512 by
    /// `scripts/export_schp_onnx.py`).
    pub fn schp() -> ModelSpec {
        ModelSpec {
            input_size: [512, 512],
            channel_order: ChannelOrder::Bgr,
            mean: [0.406, 0.456, 0.485],
            std: [0.225, 0.224, 0.229],
            class_names: Class::ALL.iter().map(|c| c.name().to_string()).collect(),
            output_stride: 4,
            align_corners: true,
            description: String::new(),
        }
    }

    /// Parses and validates sidecar JSON; `path` only names the file in errors.
    ///
    /// # Errors
    /// [`ParsingError::SidecarSyntax`] for invalid JSON, a missing or unknown key;
    /// [`ParsingError::Sidecar`] naming the field for a value out of range.
    pub fn from_json(text: &str, path: &Path) -> Result<ModelSpec, ParsingError> {
        let spec: ModelSpec =
            serde_json::from_str(text).map_err(|e| ParsingError::SidecarSyntax {
                cause: e.to_string(),
                path: path.to_path_buf(),
            })?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// The square input side S, pixels.
    pub fn input_side(&self) -> u32 {
        self.input_size[0]
    }

    /// Checks every field; the error names it.
    ///
    /// # Errors
    /// [`ParsingError::Sidecar`].
    pub fn validate(&self, path: &Path) -> Result<(), ParsingError> {
        let bad = |field: &'static str, reason: String| ParsingError::Sidecar {
            field,
            reason,
            path: path.to_path_buf(),
        };
        let [h, w] = self.input_size;
        if h != w {
            return Err(bad(
                "input_size",
                format!("must be square (SCHP pre-processing), got [{h}, {w}]"),
            ));
        }
        if !(2..=MAX_INPUT_SIZE).contains(&h) {
            return Err(bad(
                "input_size",
                format!("must be in 2..={MAX_INPUT_SIZE} pixels, got {h}"),
            ));
        }
        if let Some(m) = self.mean.iter().find(|m| !m.is_finite()) {
            return Err(bad("mean", format!("must be finite, got {m}")));
        }
        if let Some(s) = self.std.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
            return Err(bad("std", format!("must be finite and > 0, got {s}")));
        }
        if self.output_stride == 0 || self.output_stride > h {
            return Err(bad(
                "output_stride",
                format!(
                    "must be in 1..={h} (the input size), got {}",
                    self.output_stride
                ),
            ));
        }
        let want: Vec<&str> = Class::ALL.iter().map(|c| c.name()).collect();
        let got: Vec<String> = self.class_names.iter().map(|n| normalize(n)).collect();
        if got.len() != NUM_CLASSES || got.iter().zip(&want).any(|(g, w)| g != w) {
            return Err(bad(
                "class_names",
                format!(
                    "must be the {NUM_CLASSES} classes in this order: {}; got [{}]",
                    want.join(", "),
                    self.class_names.join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// Whether a logits map of `out_h` × `out_w` fits the input size and output stride.
    pub fn output_size_fits(&self, out_h: u32, out_w: u32) -> bool {
        let s = self.input_side();
        let (floor, ceil) = (s / self.output_stride, s.div_ceil(self.output_stride));
        [out_h, out_w].iter().all(|&d| d == floor || d == ceil)
    }
}

/// `Upper Arms` → `upper_arms`.
fn normalize(name: &str) -> String {
    name.trim().to_lowercase().replace([' ', '-'], "_")
}

/// The sidecar of a model file: the same path with extension `.json`
/// (`models/parser.onnx` → `models/parser.json`).
pub fn sidecar_path(model: &Path) -> PathBuf {
    model.with_extension("json")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn json(spec: &ModelSpec) -> String {
        serde_json::to_string(spec).expect("serializable")
    }

    #[test]
    fn schp_values_round_trip() {
        let p = Path::new("m.json");
        let spec = ModelSpec::schp();
        assert_eq!(ModelSpec::from_json(&json(&spec), p).expect("valid"), spec);
        let mut named = spec.clone();
        named.class_names = [
            "Background",
            "Head",
            "Torso",
            "Upper Arms",
            "Lower Arms",
            "Upper Legs",
            "Lower Legs",
        ]
        .map(String::from)
        .to_vec();
        assert!(
            named.validate(p).is_ok(),
            "SCHP's own class names are accepted"
        );
        assert!(spec.output_size_fits(128, 128));
        assert!(!spec.output_size_fits(64, 128));
    }

    #[test]
    fn errors_name_the_field() {
        let p = Path::new("m.json");
        type Break = fn(&mut ModelSpec);
        let cases: Vec<(Break, &str)> = vec![
            (
                |s| s.input_size = [512, 256],
                "m.json: input_size must be square",
            ),
            (
                |s| s.input_size = [1, 1],
                "m.json: input_size must be in 2..=4096",
            ),
            (
                |s| s.std[1] = 0.0,
                "m.json: std must be finite and > 0, got 0",
            ),
            (|s| s.mean[0] = f32::NAN, "m.json: mean must be finite"),
            (
                |s| s.output_stride = 0,
                "m.json: output_stride must be in 1..=512",
            ),
            (
                |s| s.class_names.truncate(5),
                "m.json: class_names must be the 7 classes",
            ),
            (
                |s| s.class_names.swap(1, 2),
                "m.json: class_names must be the 7 classes",
            ),
        ];
        for (break_it, want) in cases {
            let mut spec = ModelSpec::schp();
            break_it(&mut spec);
            let e = spec.validate(p).expect_err(want).to_string();
            assert!(e.starts_with(want), "{e}");
        }
        let e = ModelSpec::from_json("{\"input_size\": [512, 512]}", p)
            .expect_err("missing keys")
            .to_string();
        assert!(
            e.starts_with("m.json: bad model sidecar: missing field"),
            "{e}"
        );
        let text = json(&ModelSpec::schp()).replace("\"mean\"", "\"meen\"");
        let e = ModelSpec::from_json(&text, p)
            .expect_err("typo")
            .to_string();
        assert!(e.contains("unknown field `meen`"), "{e}");
    }

    #[test]
    fn sidecar_sits_next_to_the_model() {
        assert_eq!(
            sidecar_path(Path::new("models/a.onnx")),
            Path::new("models/a.json")
        );
    }
}
