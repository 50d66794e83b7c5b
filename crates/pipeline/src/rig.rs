//! `bodyseg rig import` and `bodyseg rig show`: calibration files → `rig.toml`, and a
//! human-readable summary of a rig.

use crate::outputs::write_text;
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, anyhow, bail};
use bodyseg_calib::{RgbdCamera, Rig};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Calibration formats `bodyseg rig import` reads, one folder (or file) per camera.
///
/// A new reader in bodyseg-calib becomes a variant here, an arm in [`read_camera`] and a
/// value of the binary's `--from`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RigFormat {
    /// iai_kinect2 (`kinect2_calibration`): a folder holding `calib_color.yaml`,
    /// `calib_ir.yaml`, `calib_pose.yaml` and `calib_depth.yaml`. No world pose.
    IaiKinect2,
}

impl RigFormat {
    /// The name the command line uses (`iai_kinect2`).
    pub fn name(self) -> &'static str {
        match self {
            RigFormat::IaiKinect2 => "iai_kinect2",
        }
    }

    /// Whether the format stores where each camera is in the world. When it does not,
    /// the imported `world_from_depth` is the identity.
    pub fn has_world_pose(self) -> bool {
        match self {
            RigFormat::IaiKinect2 => false,
        }
    }
}

/// What [`import_rig`] reads and writes.
#[derive(Clone, Debug)]
pub struct RigImportOptions {
    /// Format of the inputs.
    pub format: RigFormat,
    /// One calibration folder per camera, in rig order.
    pub inputs: Vec<PathBuf>,
    /// Camera names, one per input in the same order; empty: each camera is named after
    /// its folder.
    pub names: Vec<String>,
    /// The caller accepts identity `world_from_depth` poses for formats without a world
    /// pose: no note is given about them.
    pub world_from_depth_identity: bool,
    /// The `rig.toml` to write. Replaced atomically; untouched when the command fails.
    pub out: PathBuf,
}

/// What [`import_rig`] did.
#[derive(Clone, Debug)]
pub struct RigImportSummary {
    /// Camera names in rig order.
    pub cameras: Vec<String>,
    /// Things the user must know about the written rig (one line each), e.g. that its
    /// world poses are identities.
    pub notes: Vec<String>,
    /// The one stage (`import`): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// Reads one camera of `format` from `input`.
fn read_camera(format: RigFormat, input: &Path) -> Result<RgbdCamera> {
    match format {
        RigFormat::IaiKinect2 => Ok(bodyseg_calib::read_iai_kinect2(input)?),
    }
}

/// The default camera name of an input: its folder name (of the canonical path for `.`).
fn folder_name(input: &Path) -> Result<String> {
    if let Some(n) = input.file_name() {
        return Ok(n.to_string_lossy().into_owned());
    }
    let canonical = input
        .canonicalize()
        .with_context(|| format!("cannot resolve {}", input.display()))?;
    canonical
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| {
            anyhow!(
                "{}: no folder name to name the camera; give --name",
                input.display()
            )
        })
}

/// Reads one calibration per camera, assembles a [`Rig`] in the order given, validates it
/// and writes it as `rig.toml` (FORMATS.md).
///
/// Formats without a world pose (iai_kinect2) give `world_from_depth` = identity; the
/// summary then holds a note saying so, unless
/// [`RigImportOptions::world_from_depth_identity`] is set.
///
/// # Errors
/// No input; names given but not one per input; an empty or repeated camera name (the
/// error names it); an input that cannot be read or is invalid (the error names the file
/// and key); writing fails. Nothing is written unless every camera was read.
pub fn import_rig(opts: &RigImportOptions) -> Result<RigImportSummary> {
    if opts.inputs.is_empty() {
        bail!("no calibration folder given");
    }
    if !opts.names.is_empty() && opts.names.len() != opts.inputs.len() {
        bail!(
            "{} for {}: give one --name per folder, in the same order",
            plural(opts.names.len(), "--name", "--names"),
            plural(opts.inputs.len(), "folder", "folders")
        );
    }
    let (rig, took) = timed(|| -> Result<Rig> {
        let mut names = Vec::with_capacity(opts.inputs.len());
        for (i, input) in opts.inputs.iter().enumerate() {
            let name = match opts.names.get(i) {
                Some(n) => n.clone(),
                None => folder_name(input)?,
            };
            if name.trim().is_empty() {
                bail!("camera name of {} is empty", input.display());
            }
            if let Some(j) = names.iter().position(|n| *n == name) {
                bail!(
                    "camera name {name:?} is used twice ({} and {}): give distinct names with --name",
                    opts.inputs[j].display(),
                    input.display()
                );
            }
            names.push(name);
        }
        let mut cameras = Vec::with_capacity(opts.inputs.len());
        for (input, name) in opts.inputs.iter().zip(names) {
            let mut camera =
                read_camera(opts.format, input).with_context(|| format!("camera {name}"))?;
            tracing::debug!(camera = %name, input = %input.display(), "read calibration");
            camera.name = name;
            cameras.push(camera);
        }
        let rig = Rig { cameras };
        rig.validate().context("invalid rig")?;
        Ok(rig)
    })?;
    let text = bodyseg_calib::rig_to_toml_string(&rig)?;
    let ((), write_took) = timed(|| write_text(&opts.out, &text).context("rig (--out)"))?;

    let mut notes = Vec::new();
    if !opts.format.has_world_pose() && !opts.world_from_depth_identity {
        notes.push(format!(
            "{} files hold no world pose: every camera's world_from_depth is the identity; \
             set the world poses with `bodyseg calibrate world` or by editing {}",
            opts.format.name(),
            opts.out.display()
        ));
    }
    Ok(RigImportSummary {
        cameras: rig.cameras.iter().map(|c| c.name.clone()).collect(),
        notes,
        stages: vec![Stage::new(
            "import",
            took + write_took,
            format!(
                "{} → {}",
                plural(rig.cameras.len(), "camera", "cameras"),
                opts.out.display()
            ),
        )],
    })
}

/// Reads and validates a `rig.toml` (FORMATS.md); the error names the file and the camera
/// field at fault.
pub fn read_rig(path: &Path) -> Result<Rig> {
    Ok(bodyseg_calib::read_rig_toml(path)?)
}

/// A human-readable summary of a rig, a few lines per camera: image sizes and
/// `fx fy cx cy` (pixels) of both sensors, the colour-from-depth baseline and rotation,
/// depth scale and shift, and where the depth sensor is in the world.
pub fn describe_rig(rig: &Rig) -> String {
    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(s, "{}", plural(rig.cameras.len(), "camera", "cameras"));
    for (i, c) in rig.cameras.iter().enumerate() {
        let _ = writeln!(s, "[{i}] {}", c.name);
        for (sensor, k) in [("depth", &c.depth), ("color", &c.color)] {
            let size = format!("{}x{}", k.width, k.height);
            let _ = writeln!(
                s,
                "    {sensor:<5}  {size:>9}  fx {:.2}  fy {:.2}  cx {:.2}  cy {:.2}",
                k.fx, k.fy, k.cx, k.cy
            );
        }
        let t = c.color_from_depth.translation_m();
        let baseline_mm = t.iter().map(|v| v * v).sum::<f64>().sqrt() * 1e3;
        let _ = writeln!(
            s,
            "    color_from_depth  baseline {baseline_mm:.1} mm  (t = {:.1}, {:.1}, {:.1} mm)  \
             rotation {:.2} deg",
            t[0] * 1e3,
            t[1] * 1e3,
            t[2] * 1e3,
            rotation_angle_rad(&c.color_from_depth.rotation()).to_degrees()
        );
        let _ = writeln!(
            s,
            "    depth  shift {:.2} mm  scale {} units/m",
            c.depth_shift_mm, c.depth_scale
        );
        let w = c.world_from_depth.translation_m();
        let identity = c.world_from_depth == bodyseg_calib::Pose::identity();
        let _ = writeln!(
            s,
            "    world_from_depth  position ({:.3}, {:.3}, {:.3}) m{}",
            w[0],
            w[1],
            w[2],
            if identity {
                "  (identity: no world pose set)"
            } else {
                ""
            }
        );
    }
    s
}

/// Angle of a rotation matrix, radians in [0, π]: `acos((trace − 1) / 2)`, clamped
/// against rounding.
fn rotation_angle_rad(r: &[[f64; 3]; 3]) -> f64 {
    ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0)
        .clamp(-1.0, 1.0)
        .acos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_angle_of_a_quarter_turn() {
        let r = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        // Exact inputs; acos near 0 is the only rounding.
        assert!((rotation_angle_rad(&r) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let id = bodyseg_calib::Pose::identity().rotation();
        assert_eq!(rotation_angle_rad(&id), 0.0);
    }

    #[test]
    fn names_must_match_the_inputs() {
        let opts = RigImportOptions {
            format: RigFormat::IaiKinect2,
            inputs: vec!["a".into(), "b".into()],
            names: vec!["x".into()],
            world_from_depth_identity: false,
            out: "rig.toml".into(),
        };
        let e = format!(
            "{:#}",
            import_rig(&opts).expect_err("one name for two folders")
        );
        assert_eq!(
            e,
            "1 --name for 2 folders: give one --name per folder, in the same order"
        );
    }

    #[test]
    fn repeated_folder_names_are_an_error_naming_the_name() {
        let opts = RigImportOptions {
            format: RigFormat::IaiKinect2,
            inputs: vec!["x/cam".into(), "y/cam".into()],
            names: vec![],
            world_from_depth_identity: false,
            out: "rig.toml".into(),
        };
        let e = format!("{:#}", import_rig(&opts).expect_err("duplicate"));
        assert!(e.contains("\"cam\" is used twice"), "{e}");
    }
}
