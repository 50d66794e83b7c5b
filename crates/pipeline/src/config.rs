//! [`PipelineConfig`]: every stage's configuration in one TOML document.

use crate::layers::{Setting, has_key, keys_of, merge_tables};
use anyhow::{Context, Result, anyhow, bail};
use bodyseg_calib::{BackProjectOptions, CloudFrame};
use bodyseg_parsing::ParsingConfig;
use bodyseg_people::{BoxMode, BoxesConfig};
use bodyseg_project::{ProjectConfig, ProjectMode};
use bodyseg_refine::{RefineConfig, RefineError, Steps};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Most ONNX Runtime threads `parsing.threads` accepts: far beyond any machine's cores, low
/// enough to catch a typo before ONNX Runtime tries to start them.
pub const MAX_PARSING_THREADS: u32 = 1024;

/// The whole configuration, one section per stage (`[backproject]`, `[project]`,
/// `[boxes]`, `[refine]`, `[parsing]`). It only nests the stages' own configurations: each
/// stage crate documents its fields, units and defaults (and, for a key that applies in one
/// mode only, that mode).
///
/// Precedence ([`PipelineConfig::resolve`]): built-in defaults ([`PipelineConfig::default`],
/// equal to `configs/default.toml`) < configuration files, in order (`--config`, a later
/// file overriding only the keys it sets) < `section.key=value` settings (`--set`) <
/// command-line flags ([`PipelineConfig::apply_refine_overrides`], ...). A file may leave
/// out any section or key; an unknown one is an error.
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
    /// the field: `config.toml: refine.eps_m must be in (0, 5] metres, got -1`).
    pub fn load(path: &Path) -> Result<PipelineConfig> {
        PipelineConfig::resolve(&[path.to_path_buf()], &[])
    }

    /// The configuration of `files` (TOML, merged in order: a later file overrides only
    /// the keys it sets) with `settings` applied after them (`section.key=value`; the
    /// value is TOML, `0.03`, `true`, `"naive"`, or else a bare string, `naive`), over
    /// the built-in defaults; deserialized once and validated.
    ///
    /// # Errors
    /// A file cannot be read, is not TOML or has a key no section knows (the error names
    /// the file, the line and the key); a setting is not `KEY=VALUE`, names an unknown key
    /// or has a value of the wrong type (the error names the setting and the key); a value
    /// is out of range (the error names the field, after the file or setting that set it:
    /// `--set refine.eps_m=-1: refine.eps_m must be in (0, 5] metres, got -1`).
    pub fn resolve(files: &[PathBuf], settings: &[String]) -> Result<PipelineConfig> {
        let mut table = toml::Table::new();
        let mut file_tables = Vec::with_capacity(files.len());
        for path in files {
            let text = bodyseg_io::read_text(path)?;
            let file = parse_table(&text, path)?;
            merge_tables(&mut table, file.clone());
            file_tables.push((path, file));
        }
        let known = toml::Table::try_from(PipelineConfig::default())
            .context("cannot serialize the default configuration")?;
        let mut parsed = Vec::with_capacity(settings.len());
        for item in settings {
            let setting = Setting::parse(item).with_context(|| format!("--set {item}"))?;
            if !has_key(&known, &setting.key) {
                let section = setting.key.rsplit_once('.').map_or("", |(s, _)| s);
                bail!(
                    "--set {item}: unknown key `{}` (known{}: {})",
                    setting.key,
                    if section.is_empty() || !has_section(&known, section) {
                        " sections".to_string()
                    } else {
                        format!(" in [{section}]")
                    },
                    keys_of(&known, section).join(", ")
                );
            }
            setting
                .apply(&mut table)
                .with_context(|| format!("--set {item}"))?;
            // A value of the wrong type is named with its setting here, before later ones.
            from_table(table.clone())
                .map_err(|e| anyhow!("--set {item}: {}: {}", setting.key, e.message().trim()))?;
            parsed.push((item, setting));
        }
        let config = from_table(table)
            .map_err(|e| anyhow!("configuration: {}", e.message().trim().replace('\n', "; ")))?;
        config.validate().map_err(|e| {
            // Name the last source that set the field at fault (the message starts with
            // it), else every source.
            let message = format!("{e:#}");
            let field = message.split_whitespace().next().unwrap_or_default();
            let setting = parsed.iter().rev().find(|(_, s)| s.key == field);
            let file = file_tables
                .iter()
                .rev()
                .find(|(_, t)| has_key(t, field))
                .map(|(p, _)| p.display().to_string());
            let source = match (setting, file) {
                (Some((item, _)), _) => format!("--set {item}"),
                (None, Some(file)) => file,
                (None, None) => {
                    let mut all: Vec<String> =
                        files.iter().map(|p| p.display().to_string()).collect();
                    all.extend(settings.iter().map(|s| format!("--set {s}")));
                    if all.is_empty() {
                        "configuration".to_string()
                    } else {
                        all.join(", ")
                    }
                }
            };
            anyhow!("{source}: {message}")
        })?;
        Ok(config)
    }

    /// Parses and validates configuration text; `path_for_errors` only names the file in
    /// error messages. See [`PipelineConfig::load`].
    ///
    /// # Errors
    /// As [`PipelineConfig::load`], without the read.
    pub fn from_toml(text: &str, path_for_errors: &Path) -> Result<PipelineConfig> {
        let config = parse_config(text, path_for_errors)?;
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
    /// (`--eps-m: refine.eps_m must be in (0, 5] metres, got -1`).
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

/// Deserializes configuration text, unvalidated; the error names the file, the line and
/// the key.
fn parse_config(text: &str, path: &Path) -> Result<PipelineConfig> {
    toml::from_str(text)
        .map_err(|e| anyhow!("{}: {}", path.display(), describe_toml_error(&e, text)))
}

/// A configuration file's table, checked key by key as [`parse_config`] does (so that an
/// unknown key or a wrong type is named with its line before files are merged).
fn parse_table(text: &str, path: &Path) -> Result<toml::Table> {
    parse_config(text, path)?;
    toml::from_str(text)
        .map_err(|e| anyhow!("{}: {}", path.display(), describe_toml_error(&e, text)))
}

/// Deserializes a merged configuration table.
fn from_table(table: toml::Table) -> Result<PipelineConfig, toml::de::Error> {
    toml::Value::Table(table).try_into()
}

/// Whether the dotted `section` names a table of `known`.
fn has_section(known: &toml::Table, section: &str) -> bool {
    let mut node = known;
    for part in section.split('.') {
        match node.get(part) {
            Some(toml::Value::Table(t)) => node = t,
            _ => return false,
        }
    }
    true
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

    /// The error (chain, one line) of a file `c.toml` holding `text`.
    fn parse_error(text: &str) -> String {
        format!("{:#}", parse(text).expect_err("invalid"))
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
        let e = parse_error("[refine]\n\nepsilon = 1\n");
        assert!(
            e.starts_with("c.toml: line 3: unknown key `refine.epsilon`, expected one of"),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
        let e = parse_error("[refin]\n");
        assert!(e.starts_with("c.toml: line 1: unknown key `refin`"), "{e}");
    }

    #[test]
    fn out_of_range_values_name_the_file_and_field() {
        let e = parse_error("[refine]\neps_m = -1\n");
        assert_eq!(e, "c.toml: refine.eps_m must be in (0, 5] metres, got -1");
        let e = parse_error("[refine]\nsteps = \"m-x\"\n");
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
        let e = parse_error("[backproject]\nstride = 0\n");
        assert_eq!(e, "c.toml: backproject.stride must be >= 1, got 0");
        let e = parse_error("[project]\nocclusion_tol_m = -1\n");
        assert!(
            e.starts_with("c.toml: project.occlusion_tol_m must be"),
            "{e}"
        );
        let e = parse_error("[project]\nmode = \"x\"\n");
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
        assert_eq!(e, "--eps-m: refine.eps_m must be in (0, 5] metres, got 0");
    }

    #[test]
    fn boxes_section_is_read_and_validated_naming_the_field() {
        let c = parse("[boxes]\nmode = \"geometry\"\nperson_gap_m = 0.2\n").expect("valid");
        assert_eq!(c.boxes.mode, BoxMode::Geometry);
        assert_eq!(c.boxes.person_gap_m, 0.2);
        let e = parse_error("[boxes]\nvoxel_m = 0\n");
        assert_eq!(
            e,
            "c.toml: boxes.voxel_m must be in [0.01, 0.5] metres, got 0"
        );
        let e = parse_error("[boxes]\ngap = 1\n");
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
                segmenter: bodyseg_parsing::SegmenterKind::Onnx,
                blazepose_variant: bodyseg_parsing::BlazePoseVariant::Lite,
                model: "m.onnx".into(),
                threads: 4,
                ..Default::default()
            },
        };
        let text = c.resolved_toml().expect("serializes");
        assert_eq!(parse(&text).ok(), Some(c), "{text}");
    }

    /// Writes `files` (name, text) into a temporary folder; returns it and their paths.
    fn files(files: &[(&str, &str)]) -> (tempfile::TempDir, Vec<PathBuf>) {
        let dir = tempfile::tempdir().expect("temp dir");
        let paths = files
            .iter()
            .map(|(name, text)| {
                let path = dir.path().join(name);
                std::fs::write(&path, text).expect("write");
                path
            })
            .collect();
        (dir, paths)
    }

    fn sets(items: &[&str]) -> Vec<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_later_file_overrides_only_the_keys_it_sets() {
        let (_dir, paths) = files(&[
            (
                "a.toml",
                "[refine]\neps_m = 0.02\nmin_points = 7\n[project]\nmode = \"naive\"\n",
            ),
            ("b.toml", "[refine]\neps_m = 0.04\n"),
        ]);
        let c = PipelineConfig::resolve(&paths, &[]).expect("valid");
        assert_eq!(c.refine.eps_m, 0.04, "b.toml wins");
        assert_eq!(c.refine.min_points, 7, "a.toml's other keys stay");
        assert_eq!(c.project.mode, ProjectMode::Naive);
        let reversed: Vec<PathBuf> = paths.iter().rev().cloned().collect();
        assert_eq!(
            PipelineConfig::resolve(&reversed, &[])
                .expect("valid")
                .refine
                .eps_m,
            0.02
        );
        assert_eq!(
            PipelineConfig::resolve(&[], &[]).ok(),
            Some(PipelineConfig::default())
        );
        // A file's own errors name it, its line and the key, before any merging.
        let (_dir, bad) = files(&[("bad.toml", "[refine]\n\nepsilon = 1\n")]);
        let e = format!(
            "{:#}",
            PipelineConfig::resolve(&[paths[0].clone(), bad[0].clone()], &[]).expect_err("bad")
        );
        assert!(
            e.contains("bad.toml: line 3: unknown key `refine.epsilon`"),
            "{e}"
        );
    }

    #[test]
    fn settings_beat_the_files_and_are_checked_naming_the_key() {
        let (_dir, paths) = files(&[("a.toml", "[refine]\neps_m = 0.02\nmin_points = 7\n")]);
        let c = PipelineConfig::resolve(
            &paths,
            &sets(&[
                "refine.eps_m=0.03",
                "project.mode=naive",
                "refine.steps=M-N",
                "project.occlusion = false",
                "backproject.depth_max_m=inf",
                "boxes.mode=\"geometry\"",
            ]),
        )
        .expect("valid");
        assert_eq!(c.refine.eps_m, 0.03, "--set beats the file");
        assert_eq!(c.refine.min_points, 7, "the file's other keys stay");
        assert_eq!(c.project.mode, ProjectMode::Naive);
        assert_eq!(c.refine.steps.to_string(), "M-N");
        assert!(!c.project.occlusion);
        assert!(c.backproject.depth_max_m.is_infinite());
        assert_eq!(c.boxes.mode, BoxMode::Geometry);
        // The later of two settings of one key wins.
        let c = PipelineConfig::resolve(&[], &sets(&["refine.eps_m=0.03", "refine.eps_m=0.04"]))
            .expect("valid");
        assert_eq!(c.refine.eps_m, 0.04);

        let err = |items: &[&str]| {
            format!(
                "{:#}",
                PipelineConfig::resolve(&paths, &sets(items)).expect_err("invalid")
            )
        };
        // Each error names the setting first, then what is wrong with it.
        for (setting, what) in [
            (
                "refine.epsx=1",
                "unknown key `refine.epsx` (known in [refine]: ",
            ),
            (
                "refin.eps_m=1",
                "unknown key `refin.eps_m` (known sections: ",
            ),
            ("refine=1", "unknown key `refine`"),
            ("refine.eps_m=abc", "refine.eps_m: "),
            ("project.mode=sideways", "project.mode: "),
            ("refine.eps_m", "not KEY=VALUE"),
        ] {
            let e = err(&[setting]);
            let named = format!("--set {setting}: ");
            assert!(e.starts_with(&named) && e.contains(what), "{e}");
        }
        assert!(err(&["refine.epsx=1"]).contains("eps_m"));
        // A value out of range is named with the setting that gave it...
        assert_eq!(
            err(&["refine.eps_m=-1"]),
            "--set refine.eps_m=-1: refine.eps_m must be in (0, 5] metres, got -1"
        );
        // ... or the file.
        let (_dir, bad) = files(&[("neg.toml", "[refine]\neps_m = -1\n")]);
        let e = format!(
            "{:#}",
            PipelineConfig::resolve(
                &[paths[0].clone(), bad[0].clone()],
                &sets(&["refine.min_points=3"])
            )
            .expect_err("invalid")
        );
        assert!(
            e.ends_with("neg.toml: refine.eps_m must be in (0, 5] metres, got -1"),
            "{e}"
        );
        // A setting can mend a file's value: only the result is validated.
        let c = PipelineConfig::resolve(&bad, &sets(&["refine.eps_m=0.05"])).expect("mended");
        assert_eq!(c.refine.eps_m, 0.05);
    }
}
