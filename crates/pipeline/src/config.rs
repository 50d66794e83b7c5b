//! [`PipelineConfig`]: every stage's configuration in one TOML document.

use anyhow::{Context, Result, anyhow, bail};
use bodyseg_calib::{BackProjectOptions, CloudFrame};
use bodyseg_parsing::ParsingConfig;
use bodyseg_people::{BoxMode, BoxesConfig};
use bodyseg_project::{ProjectConfig, ProjectMode};
use bodyseg_refine::{RefineConfig, RefineError, Steps};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Most ONNX Runtime threads `parsing.threads` accepts: far beyond any machine's cores, low
/// enough to catch a typo before ONNX Runtime tries to start them.
pub const MAX_PARSING_THREADS: u32 = 1024;

/// The whole configuration, one section per stage (`[backproject]`, `[project]`,
/// `[boxes]`, `[refine]`, and later `[parsing]`, ...). It only nests the stages' own configurations: each stage
/// crate documents its fields, units and defaults.
///
/// Precedence: built-in defaults ([`PipelineConfig::default`], equal to
/// `configs/default.toml`) < a configuration file ([`PipelineConfig::load`]) < command-line
/// flags ([`PipelineConfig::apply_refine_overrides`]). A file may leave out any section or
/// key; an unknown one is an error.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineConfig {
    /// Depth back-projection before the label projection (`[backproject]`).
    pub backproject: BackProjectConfig,
    /// The 2D → 3D label projection (`[project]`, bodyseg-project's [`ProjectConfig`]).
    pub project: ProjectConfig,
    /// The person boxes (`[boxes]`, bodyseg-people's [`BoxesConfig`]).
    pub boxes: BoxesConfig,
    /// The clustering refinement (`[refine]`).
    pub refine: RefineConfig,
    /// 2D human parsing (`[parsing]`, bodyseg-parsing's [`ParsingConfig`]).
    pub parsing: ParsingConfig,
}

/// Which depth pixels become points (`[backproject]`): the serializable part of
/// bodyseg-calib's [`BackProjectOptions`] (whose output frame the projection fixes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BackProjectConfig {
    /// Depths below this give no point, metres (after `depth_scale` and
    /// `depth_shift_mm`). Must be finite and >= 0. Default 0: every measured depth.
    pub depth_min_m: f64,
    /// Depths above this give no point, metres. Must be >= `depth_min_m`; `inf` = no
    /// limit. Default `inf` (Kinect v2 data is unreliable beyond ~4.5 m: lower it there).
    pub depth_max_m: f64,
    /// Keep every `stride`-th depth pixel along rows and columns (`u % stride == 0` and
    /// `v % stride == 0`). Must be >= 1. Default 1: every pixel. Raise
    /// `project.splat_radius_px` with it: sparser points leave holes in the z-buffer.
    pub stride: u32,
}

impl Default for BackProjectConfig {
    fn default() -> Self {
        let o = BackProjectOptions::default();
        BackProjectConfig {
            depth_min_m: o.depth_min_m,
            depth_max_m: o.depth_max_m,
            stride: o.stride,
        }
    }
}

impl BackProjectConfig {
    /// bodyseg-calib's options for these values, world frame.
    pub fn options(&self) -> BackProjectOptions {
        BackProjectOptions {
            depth_min_m: self.depth_min_m,
            depth_max_m: self.depth_max_m,
            stride: self.stride,
            frame: CloudFrame::World,
        }
    }

    /// Checks the ranges; the error names the field (`backproject.stride must be >= 1,
    /// got 0`).
    pub fn validate(&self) -> Result<()> {
        if self.stride == 0 {
            bail!("backproject.stride must be >= 1, got 0");
        }
        if !(self.depth_min_m.is_finite() && self.depth_min_m >= 0.0) {
            bail!(
                "backproject.depth_min_m must be a finite number >= 0, got {}",
                self.depth_min_m
            );
        }
        if self.depth_max_m.is_nan() || self.depth_max_m < self.depth_min_m {
            bail!(
                "backproject.depth_max_m must be >= backproject.depth_min_m ({}), got {}",
                self.depth_min_m,
                self.depth_max_m
            );
        }
        Ok(())
    }
}

/// Command-line values that replace the `[refine]` section's; `None` leaves a field as the
/// defaults and the configuration file set it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefineOverrides {
    /// `--steps`: `refine.steps`.
    pub steps: Option<Steps>,
    /// `--eps-m`: `refine.eps_m`, metres.
    pub eps_m: Option<f32>,
    /// `--min-points`: `refine.min_points`.
    pub min_points: Option<usize>,
    /// `--keep-outside-boxes`: `refine.keep_outside_boxes`.
    pub keep_outside_boxes: Option<bool>,
}

impl PipelineConfig {
    /// Reads a TOML configuration file, fills what it leaves out with the built-in
    /// defaults, and validates it.
    ///
    /// # Errors
    /// The file cannot be read or is not UTF-8 ([`bodyseg_io::read_text`]); it is not TOML; it has a key no section knows (the error
    /// names the key, its line and its section); a value is out of range (the error names
    /// the field: `config.toml: refine.eps_m must be a finite number > 0, got -1`).
    pub fn load(path: &Path) -> Result<PipelineConfig> {
        let text = bodyseg_io::read_text(path)?;
        PipelineConfig::from_toml(&text, path)
    }

    /// Parses and validates configuration text; `path_for_errors` only names the file in
    /// error messages. See [`PipelineConfig::load`].
    ///
    /// # Errors
    /// As [`PipelineConfig::load`], without the read.
    pub fn from_toml(text: &str, path_for_errors: &Path) -> Result<PipelineConfig> {
        let config: PipelineConfig = toml::from_str(text).map_err(|e| {
            anyhow!(
                "{}: {}",
                path_for_errors.display(),
                describe_toml_error(&e, text)
            )
        })?;
        config
            .validate()
            .with_context(|| format!("{}", path_for_errors.display()))?;
        Ok(config)
    }

    /// Checks every section; the error names the field (`refine.eps_m must be ...`).
    ///
    /// # Errors
    /// The first field out of range.
    pub fn validate(&self) -> Result<()> {
        self.backproject.validate()?;
        self.project.validate()?;
        self.boxes.validate()?;
        self.refine.validate()?;
        if self.parsing.threads > MAX_PARSING_THREADS {
            bail!(
                "parsing.threads must be in 0..={MAX_PARSING_THREADS} (0 = one per core), got {}",
                self.parsing.threads
            );
        }
        Ok(())
    }

    /// Applies `--mode` over `project.mode` (`None` keeps it).
    pub fn apply_project_mode(&mut self, mode: Option<ProjectMode>) {
        if let Some(mode) = mode {
            self.project.mode = mode;
        }
    }

    /// Applies `--mode` over `boxes.mode` (`None` keeps it).
    pub fn apply_boxes_mode(&mut self, mode: Option<BoxMode>) {
        if let Some(mode) = mode {
            self.boxes.mode = mode;
        }
    }

    /// Applies command-line values over this configuration and validates the result.
    ///
    /// # Errors
    /// A value out of range; the error names the flag and the field
    /// (`--eps-m: refine.eps_m must be a finite number > 0, got -1`).
    pub fn apply_refine_overrides(&mut self, o: &RefineOverrides) -> Result<()> {
        let r = &mut self.refine;
        if let Some(steps) = o.steps {
            r.steps = steps;
        }
        if let Some(eps_m) = o.eps_m {
            r.eps_m = eps_m;
        }
        if let Some(min_points) = o.min_points {
            r.min_points = min_points;
        }
        if let Some(keep) = o.keep_outside_boxes {
            r.keep_outside_boxes = keep;
        }
        self.refine.validate().map_err(|e| match &e {
            RefineError::InvalidConfig { field, .. } => {
                anyhow!("--{}: {e}", field.replace('_', "-"))
            }
            _ => anyhow!("command-line flags: {e}"),
        })
    }

    /// The configuration as TOML, every field written out: the file written beside
    /// outputs (`config.resolved.toml`) so that any result can be reproduced.
    ///
    /// # Errors
    /// Serialization fails (it does not for these types).
    pub fn resolved_toml(&self) -> Result<String> {
        let body = toml::to_string(self).context("cannot serialize the configuration as TOML")?;
        Ok(format!(
            "# bodyseg {} resolved configuration: built-in defaults < config file < flags\n{body}",
            env!("CARGO_PKG_VERSION")
        ))
    }
}

/// One line out of a TOML error (the crate's own `Display` spans several lines and draws
/// the offending line): ``line 3: unknown key `refine.eps`, expected one of ...``.
fn describe_toml_error(e: &toml::de::Error, text: &str) -> String {
    let message = e.message().trim().replace('\n', "; ");
    let Some(span) = e.span() else {
        return message;
    };
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line = text[..line_start].matches('\n').count() + 1;
    // The innermost `[table]` header above the error's line, if any.
    let section = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .and_then(|l| l.split('#').next())
        .map(|l| {
            l.trim()
                .trim_start_matches('[')
                .trim_end_matches(']')
                .trim()
        });
    // serde says "unknown field `x`"; name the key with its section, as users write it.
    if let Some(rest) = message.strip_prefix("unknown field `")
        && let Some((name, rest)) = rest.split_once('`')
    {
        let key = section.map_or_else(|| name.to_string(), |s| format!("{s}.{name}"));
        return format!("line {line}: unknown key `{key}`{rest}");
    }
    match section {
        Some(s) => format!("line {line}, in [{s}]: {message}"),
        None => format!("line {line}: {message}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<PipelineConfig> {
        PipelineConfig::from_toml(text, Path::new("c.toml"))
    }

    #[test]
    fn empty_file_is_the_defaults_and_partial_sections_fill_in() {
        assert_eq!(parse("").ok(), Some(PipelineConfig::default()));
        let c = parse("[refine]\nmin_points = 7\n").expect("valid");
        assert_eq!(c.refine.min_points, 7);
        assert_eq!(c.refine.eps_m, RefineConfig::default().eps_m);
    }

    #[test]
    fn unreadable_file_is_named_and_its_cause_printed_once() {
        let path = Path::new("/nonexistent/bodyseg/c.toml");
        let e = format!("{:#}", PipelineConfig::load(path).expect_err("missing"));
        assert!(
            e.starts_with("/nonexistent/bodyseg/c.toml: cannot read: "),
            "{e}"
        );
        assert_eq!(e.matches("(os error").count(), 1, "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn unknown_keys_are_named_with_line_and_section() {
        let e = format!(
            "{:#}",
            parse("[refine]\n\nepsilon = 1\n").expect_err("error")
        );
        assert!(
            e.starts_with("c.toml: line 3: unknown key `refine.epsilon`, expected one of"),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
        let e = format!("{:#}", parse("[refin]\n").expect_err("error"));
        assert!(e.starts_with("c.toml: line 1: unknown key `refin`"), "{e}");
    }

    #[test]
    fn out_of_range_values_name_the_file_and_field() {
        let e = format!("{:#}", parse("[refine]\neps_m = -1\n").expect_err("error"));
        assert_eq!(
            e,
            "c.toml: refine.eps_m must be a finite number > 0, got -1"
        );
        let e = format!(
            "{:#}",
            parse("[refine]\nsteps = \"m-x\"\n").expect_err("error")
        );
        assert!(
            e.contains("line 2, in [refine]") && e.contains("'x'"),
            "{e}"
        );
    }

    #[test]
    fn project_and_backproject_sections_are_read_and_validated() {
        let c = parse("[project]\nmode = \"naive\"\n[backproject]\ndepth_max_m = 4.5\n")
            .expect("valid");
        assert_eq!(c.project.mode, ProjectMode::Naive);
        assert_eq!(c.backproject.options().depth_max_m, 4.5);
        assert_eq!(c.backproject.options().frame, CloudFrame::World);
        let e = format!(
            "{:#}",
            parse("[backproject]\nstride = 0\n").expect_err("error")
        );
        assert_eq!(e, "c.toml: backproject.stride must be >= 1, got 0");
        let e = format!(
            "{:#}",
            parse("[project]\nocclusion_tol_m = -1\n").expect_err("error")
        );
        assert!(
            e.starts_with("c.toml: project.occlusion_tol_m must be"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            parse("[project]\nmode = \"x\"\n").expect_err("error")
        );
        assert!(e.contains("line 2, in [project]"), "{e}");
        let mut c = PipelineConfig::default();
        c.apply_project_mode(Some(ProjectMode::Naive));
        assert_eq!(c.project.mode, ProjectMode::Naive);
        c.apply_project_mode(None);
        assert_eq!(c.project.mode, ProjectMode::Naive);
    }

    #[test]
    fn overrides_win_and_are_validated_naming_the_flag() {
        let mut c = PipelineConfig::default();
        let o = RefineOverrides {
            eps_m: Some(0.02),
            min_points: Some(5),
            steps: Some(Steps::Reference),
            keep_outside_boxes: Some(true),
        };
        c.apply_refine_overrides(&o).expect("valid");
        assert_eq!(c.refine.eps_m, 0.02);
        assert_eq!(c.refine.min_points, 5);
        assert_eq!(c.refine.steps, Steps::Reference);
        assert!(c.refine.keep_outside_boxes);
        let bad = RefineOverrides {
            eps_m: Some(0.0),
            ..Default::default()
        };
        let e = format!("{:#}", c.apply_refine_overrides(&bad).expect_err("error"));
        assert_eq!(
            e,
            "--eps-m: refine.eps_m must be a finite number > 0, got 0"
        );
    }

    #[test]
    fn boxes_section_is_read_and_validated_naming_the_field() {
        let c = parse("[boxes]\nmode = \"geometry\"\nperson_gap_m = 0.2\n").expect("valid");
        assert_eq!(c.boxes.mode, BoxMode::Geometry);
        assert_eq!(c.boxes.person_gap_m, 0.2);
        let e = format!("{:#}", parse("[boxes]\nvoxel_m = 0\n").expect_err("error"));
        assert_eq!(
            e,
            "c.toml: boxes.voxel_m must be a finite number > 0, got 0"
        );
        let e = format!("{:#}", parse("[boxes]\ngap = 1\n").expect_err("error"));
        assert!(
            e.starts_with("c.toml: line 2: unknown key `boxes.gap`"),
            "{e}"
        );
        let mut c = PipelineConfig::default();
        c.apply_boxes_mode(Some(BoxMode::File));
        assert_eq!(c.boxes.mode, BoxMode::File);
    }

    #[test]
    fn resolved_toml_reads_back_to_the_same_config() {
        let c = PipelineConfig {
            refine: RefineConfig {
                eps_m: 0.03,
                steps: "m-n".parse().expect("valid steps"),
                ..Default::default()
            },
            project: ProjectConfig::naive(),
            backproject: BackProjectConfig {
                depth_max_m: 4.5,
                stride: 2,
                ..Default::default()
            },
            boxes: BoxesConfig {
                mode: BoxMode::Geometry,
                voxel_m: 0.03,
                ..Default::default()
            },
            parsing: bodyseg_parsing::ParsingConfig {
                model: "m.onnx".into(),
                threads: 4,
                ..Default::default()
            },
        };
        let text = c.resolved_toml().expect("serializes");
        assert_eq!(parse(&text).ok(), Some(c), "{text}");
    }
}
