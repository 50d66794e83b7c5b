//! `bodyseg rig import` and `bodyseg rig show`: calibration files → `rig.toml`, and a
//! human-readable summary of a rig.

use crate::outputs::write_text;
use crate::recording::check_camera_name;
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, anyhow, bail};
use bodyseg_calib::{AzureKinectMode, Intrinsics, Pose, RgbdCamera, Rig};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Calibration formats `bodyseg rig import` reads.
///
/// A new reader in bodyseg-calib becomes a variant here, an arm in `read_camera` and a
/// value of the binary's `--from`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RigFormat {
    /// iai_kinect2 (`kinect2_calibration`): a folder holding `calib_color.yaml`,
    /// `calib_ir.yaml`, `calib_pose.yaml` and `calib_depth.yaml` (without it: depth
    /// shift 0, as `kinect2_bridge`). No world pose.
    IaiKinect2,
    /// Azure Kinect factory calibration JSON (`k4arecorder`'s attachment, the SDK's
    /// raw calibration): both sensors and their extrinsic, rational distortion. No world
    /// pose.
    AzureKinect,
    /// ROS `camera_info` YAML: one sensor per file (`plumb_bob` or
    /// `rational_polynomial`). No extrinsic between the sensors, no world pose.
    Ros,
    /// OpenCV FileStorage YAML of one sensor (`camera_matrix` or `cameraMatrix`,
    /// `distortion_coefficients` or `distortionCoefficients`, `image_width`,
    /// `image_height`), as `cv::FileStorage` or `bodyseg calibrate intrinsics` write it.
    /// No extrinsic between the sensors, no world pose.
    OpenCv,
}

impl RigFormat {
    /// The name the command line uses (`iai_kinect2`).
    pub fn name(self) -> &'static str {
        match self {
            RigFormat::IaiKinect2 => "iai_kinect2",
            RigFormat::AzureKinect => "azure_kinect",
            RigFormat::Ros => "ros",
            RigFormat::OpenCv => "opencv",
        }
    }

    /// Whether a file of the format describes one sensor only, so that a camera needs
    /// two (depth and colour) or one for both sensors.
    pub fn is_one_sensor(self) -> bool {
        matches!(self, RigFormat::Ros | RigFormat::OpenCv)
    }
}

/// One camera's calibration files.
#[derive(Clone, Debug, PartialEq)]
pub struct RigInput {
    /// Their format.
    pub format: RigFormat,
    /// The folder (iai_kinect2), the JSON file (Azure Kinect), or the depth sensor's file
    /// (ROS, OpenCV).
    pub path: PathBuf,
    /// One-sensor formats: the colour sensor's file. `None`: the depth images are
    /// registered to the sensor of `path` (both sensors get its intrinsics and
    /// `color_from_depth` is the identity), as a ROS `depth_registered` stream or an
    /// aligned RealSense stream is.
    pub color: Option<PathBuf>,
}

/// What [`import_rig`] reads and writes.
#[derive(Clone, Debug)]
pub struct RigImportOptions {
    /// One calibration per camera, in rig order.
    pub inputs: Vec<RigInput>,
    /// Camera names, one per input in the same order; empty: each camera is named after
    /// its folder (iai_kinect2) or its file's stem.
    pub names: Vec<String>,
    /// OpenPTrack `camera_poses.yaml` (`opt_calibration`'s output): each camera's world
    /// pose, found by the camera's name. OpenPTrack calibrates the colour sensors, so a
    /// pose is `world_from_color`, and `world_from_depth = world_from_color ·
    /// color_from_depth`.
    pub poses: Option<PathBuf>,
    /// Azure Kinect capture mode whose images the intrinsics are for (default: the
    /// sensors' full images, as stored).
    pub azure_mode: AzureKinectMode,
    /// The caller accepts identity `world_from_depth` poses when no `poses` file is
    /// given: no note is given about them.
    pub world_from_depth_identity: bool,
    /// The `rig.toml` to write. Replaced atomically; untouched when the command fails.
    pub out: PathBuf,
}

/// What [`import_rig`] did.
#[derive(Clone, Debug)]
pub struct RigImportSummary {
    /// Camera names in rig order.
    pub cameras: Vec<String>,
    /// Things the user must know about the written rig (one line each): defaults the
    /// readers took (a missing depth shift, a missing distortion model), identity poses.
    pub notes: Vec<String>,
    /// The one stage (`import`): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// Reads one camera from `input`; its notes are appended to `notes`.
fn read_camera(
    input: &RigInput,
    azure_mode: AzureKinectMode,
    notes: &mut Vec<String>,
) -> Result<RgbdCamera> {
    let path = &input.path;
    if input.color.is_some() && !input.format.is_one_sensor() {
        bail!(
            "{}: {} holds both sensors; give one path per camera (no DEPTH,COLOR pair)",
            path.display(),
            input.format.name()
        );
    }
    match input.format {
        RigFormat::IaiKinect2 => {
            let imported = bodyseg_calib::import_iai_kinect2(path)?;
            notes.extend(imported.notes);
            Ok(imported.camera)
        }
        RigFormat::AzureKinect => {
            let imported = bodyseg_calib::read_azure_kinect_json(path, "", azure_mode)?;
            notes.extend(imported.notes);
            Ok(imported.camera)
        }
        RigFormat::Ros | RigFormat::OpenCv => {
            let read = |p: &Path, notes: &mut Vec<String>| -> Result<Intrinsics> {
                Ok(if input.format == RigFormat::Ros {
                    let info = bodyseg_calib::read_ros_camera_info(p)?;
                    notes.extend(info.notes);
                    info.intrinsics
                } else {
                    read_opencv(p)?
                })
            };
            let depth = read(path, notes)?;
            let color = match &input.color {
                Some(c) => {
                    notes.push(format!(
                        "{} files hold no pose between the sensors: color_from_depth is the \
                         identity; set it with `bodyseg calibrate stereo` or edit \
                         [camera.color_from_depth]",
                        input.format.name()
                    ));
                    read(c, notes)?
                }
                None => {
                    notes.push(format!(
                        "one {} file: depth registered to that sensor (both sensors get its \
                         intrinsics, color_from_depth is the identity): {}",
                        input.format.name(),
                        path.display()
                    ));
                    depth
                }
            };
            Ok(RgbdCamera::new("", depth, color))
        }
    }
}

/// An OpenCV FileStorage file: YAML in pure Rust, XML through OpenCV (feature `opencv`).
fn read_opencv(path: &Path) -> Result<Intrinsics> {
    let xml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if xml {
        #[cfg(feature = "opencv")]
        return Ok(bodyseg_calib::read_opencv_intrinsics(path, None)?);
        #[cfg(not(feature = "opencv"))]
        bail!(
            "{}: OpenCV FileStorage XML is read through OpenCV: build bodyseg with \
             `--features opencv`, or convert the file to YAML",
            path.display()
        );
    }
    Ok(bodyseg_calib::read_opencv_yaml_intrinsics(path, None)?)
}

/// The default camera name of an input: the folder name (iai_kinect2, of the canonical
/// path for `.`) or the file's stem.
fn default_name(input: &RigInput) -> Result<String> {
    let path = &input.path;
    let name = if input.format == RigFormat::IaiKinect2 {
        path.file_name()
    } else {
        path.file_stem()
    };
    if let Some(n) = name {
        return Ok(n.to_string_lossy().into_owned());
    }
    let canonical = path
        .canonicalize()
        .with_context(|| format!("cannot resolve {}", path.display()))?;
    canonical
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| {
            anyhow!(
                "{}: no folder name to name the camera; give --name",
                path.display()
            )
        })
}

/// Reads one calibration per camera, assembles a [`Rig`] in the order given, places the
/// cameras in the world with the OpenPTrack poses if given, validates the rig and writes
/// it as `rig.toml` (FORMATS.md).
///
/// Without a poses file `world_from_depth` is the identity; the summary then holds a
/// note saying so, unless [`RigImportOptions::world_from_depth_identity`] is set. Every
/// default a reader took is a note too (an iai_kinect2 folder without `calib_depth.yaml`
/// has depth shift 0; a ROS file without `distortion_model` is `plumb_bob`; one-sensor
/// formats have no `color_from_depth`).
///
/// # Errors
/// No input; names given but not one per input; an empty or repeated camera name (the
/// error names it); an input that cannot be read or is invalid (the error names the file
/// and key); a camera the poses file does not have (the error lists those it has);
/// writing fails. Nothing is written unless every camera was read.
pub fn import_rig(opts: &RigImportOptions) -> Result<RigImportSummary> {
    if opts.inputs.is_empty() {
        bail!("no calibration given");
    }
    if !opts.names.is_empty() && opts.names.len() != opts.inputs.len() {
        bail!(
            "{} for {}: give one --name per camera, in the same order",
            plural(opts.names.len(), "--name", "--names"),
            plural(opts.inputs.len(), "camera", "cameras")
        );
    }
    let mut notes = Vec::new();
    let (rig, took) = timed(|| -> Result<Rig> {
        let mut names = Vec::with_capacity(opts.inputs.len());
        for (i, input) in opts.inputs.iter().enumerate() {
            let name = match opts.names.get(i) {
                Some(n) => n.clone(),
                None => default_name(input)?,
            };
            if name.trim().is_empty() {
                bail!("camera name of {} is empty", input.path.display());
            }
            // The name becomes the camera's folder of every recording with this rig.
            check_camera_name(&name).with_context(|| match opts.names.get(i) {
                Some(_) => "--name".to_string(),
                None => format!("{}: give --name", input.path.display()),
            })?;
            if let Some(j) = names.iter().position(|n| *n == name) {
                bail!(
                    "camera name {name:?} is used twice ({} and {}): give distinct names with --name",
                    opts.inputs[j].path.display(),
                    input.path.display()
                );
            }
            names.push(name);
        }
        let poses = opts
            .poses
            .as_deref()
            .map(|p| -> Result<_> { Ok((p, bodyseg_calib::read_openptrack_poses(p)?)) })
            .transpose()?;
        let mut cameras = Vec::with_capacity(opts.inputs.len());
        for (input, name) in opts.inputs.iter().zip(names) {
            let mut camera_notes = Vec::new();
            let mut camera = read_camera(input, opts.azure_mode, &mut camera_notes)
                .with_context(|| format!("camera {name}"))?;
            notes.extend(
                camera_notes
                    .into_iter()
                    .map(|n| format!("camera {name}: {n}")),
            );
            tracing::debug!(camera = %name, input = %input.path.display(), "read calibration");
            if let Some((path, poses)) = &poses {
                camera.world_from_depth = world_from_depth(&name, &camera, path, poses)?;
            }
            camera.name = name;
            cameras.push(camera);
        }
        if let Some((path, poses)) = &poses {
            let unused: Vec<&str> = poses
                .iter()
                .map(|(n, _)| n.as_str())
                .filter(|n| !cameras.iter().any(|c| c.name == *n))
                .collect();
            if !unused.is_empty() {
                notes.push(format!(
                    "{}: sensors not imported (no camera of that name): {}",
                    path.display(),
                    unused.join(", ")
                ));
            }
        }
        let rig = Rig { cameras };
        rig.validate().context("invalid rig")?;
        Ok(rig)
    })?;
    let text = bodyseg_calib::rig_to_toml_string(&rig)?;
    let ((), write_took) = timed(|| write_text(&opts.out, &text).context("rig (--out)"))?;

    if opts.poses.is_none() && !opts.world_from_depth_identity {
        let formats: Vec<&str> =
            opts.inputs
                .iter()
                .map(|i| i.format.name())
                .fold(Vec::new(), |mut v, n| {
                    if !v.contains(&n) {
                        v.push(n);
                    }
                    v
                });
        notes.push(format!(
            "{} files hold no world pose: every camera's world_from_depth is the identity; \
             give OpenPTrack's camera_poses.yaml with --poses, set the world poses with \
             `bodyseg calibrate world`, or edit {}",
            formats.join(" and "),
            opts.out.display()
        ));
    }
    for note in &notes {
        tracing::info!("{note}");
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

/// A camera's `world_from_depth` from OpenPTrack's poses (`world_from_color`, see
/// [`RigImportOptions::poses`]).
fn world_from_depth(
    name: &str,
    camera: &RgbdCamera,
    path: &Path,
    poses: &[(String, Pose)],
) -> Result<Pose> {
    let Some((_, world_from_color)) = poses.iter().find(|(n, _)| n == name) else {
        let names: Vec<&str> = poses.iter().map(|(n, _)| n.as_str()).collect();
        bail!(
            "camera {name}: no sensor {name:?} in {} (it has {}); name the cameras after \
             its sensors with --name",
            path.display(),
            names.join(", ")
        );
    };
    Ok(world_from_color.compose(&camera.color_from_depth))
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
            let model = if k.distortion.is_rational() {
                "rational distortion (8)"
            } else {
                "Brown-Conrady distortion (5)"
            };
            let _ = writeln!(
                s,
                "    {sensor:<5}  {size:>9}  fx {:.2}  fy {:.2}  cx {:.2}  cy {:.2}  {model}",
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

    fn iai(path: &str) -> RigInput {
        RigInput {
            format: RigFormat::IaiKinect2,
            path: path.into(),
            color: None,
        }
    }

    fn options(inputs: Vec<RigInput>, names: Vec<String>) -> RigImportOptions {
        RigImportOptions {
            inputs,
            names,
            poses: None,
            azure_mode: AzureKinectMode::default(),
            world_from_depth_identity: false,
            out: "rig.toml".into(),
        }
    }

    #[test]
    fn names_must_match_the_inputs() {
        let opts = options(vec![iai("a"), iai("b")], vec!["x".into()]);
        let e = format!(
            "{:#}",
            import_rig(&opts).expect_err("one name for two folders")
        );
        assert_eq!(
            e,
            "1 --name for 2 cameras: give one --name per camera, in the same order"
        );
    }

    #[test]
    fn names_that_would_leave_a_recording_are_refused() {
        for bad in [
            "../../x",
            "/abs",
            "a/b",
            ".",
            "..",
            "kamera_ä",
            "a\0b",
            "a b",
        ] {
            let opts = options(vec![iai("a")], vec![bad.into()]);
            let e = format!("{:#}", import_rig(&opts).expect_err(bad));
            assert!(
                e.starts_with("--name: camera ") && e.contains("letters, digits"),
                "{bad}: {e}"
            );
        }
        // A folder name that is no valid camera name: named, with the way out.
        let opts = options(vec![iai("calib/kamera ä")], vec![]);
        let e = format!("{:#}", import_rig(&opts).expect_err("folder name"));
        assert!(e.starts_with("calib/kamera ä: give --name: camera"), "{e}");
    }

    #[test]
    fn repeated_folder_names_are_an_error_naming_the_name() {
        let opts = options(vec![iai("x/cam"), iai("y/cam")], vec![]);
        let e = format!("{:#}", import_rig(&opts).expect_err("duplicate"));
        assert!(e.contains("\"cam\" is used twice"), "{e}");
    }

    #[test]
    fn default_names_are_folder_names_and_file_stems() {
        let name = |format, path: &str| {
            default_name(&RigInput {
                format,
                path: path.into(),
                color: None,
            })
            .expect("a name")
        };
        assert_eq!(name(RigFormat::IaiKinect2, "calib/0113.v2"), "0113.v2");
        assert_eq!(name(RigFormat::AzureKinect, "k4a/front.json"), "front");
        assert_eq!(name(RigFormat::Ros, "depth_A00.yaml"), "depth_A00");
    }

    #[test]
    fn a_pair_for_a_two_sensor_format_is_refused() {
        let input = RigInput {
            format: RigFormat::AzureKinect,
            path: "a.json".into(),
            color: Some("b.json".into()),
        };
        let e = read_camera(&input, AzureKinectMode::default(), &mut Vec::new()).expect_err("pair");
        assert!(
            e.to_string()
                .starts_with("a.json: azure_kinect holds both sensors"),
            "{e}"
        );
    }
}
