//! iai_kinect2 calibration folders (`kinect2_calibration`'s output, one folder per sensor
//! serial): `calib_color.yaml`, `calib_ir.yaml`, `calib_pose.yaml`, `calib_depth.yaml`.

use std::path::Path;

use crate::files::write_atomic;
use crate::opencv_yaml::{FileStorage, format_matrix, format_number};
use crate::{CalibError, DEFAULT_DEPTH_SCALE, ImportedCamera, Intrinsics, Pose, RgbdCamera};

/// Kinect v2 colour image size, pixels (iai_kinect2 does not store it).
pub const KINECT2_COLOR_SIZE: [u32; 2] = [1920, 1080];
/// Kinect v2 depth (IR) image size, pixels.
pub const KINECT2_DEPTH_SIZE: [u32; 2] = [512, 424];

/// Reads an iai_kinect2 calibration folder into a camera named after the folder, the
/// notes of [`import_iai_kinect2`] logged at `info` level (`tracing`).
pub fn read_iai_kinect2(dir: &Path) -> Result<RgbdCamera, CalibError> {
    let imported = import_iai_kinect2(dir)?;
    for note in &imported.notes {
        tracing::info!("{note}");
    }
    Ok(imported.camera)
}

/// Reads an iai_kinect2 calibration folder into a camera named after the folder, with
/// what `kinect2_bridge` would assume for a missing file.
///
/// - `calib_color.yaml`, `calib_ir.yaml`: `cameraMatrix` (3×3) and
///   `distortionCoefficients` (1×5, k1 k2 p1 p2 k3; any 1×N or N×1 that OpenCV reads:
///   4, 5 or 8 values, see [`crate::Distortion::from_opencv`]). The image size is taken from
///   `image_width`/`image_height` when present, else the Kinect v2 sizes
///   ([`KINECT2_COLOR_SIZE`], [`KINECT2_DEPTH_SIZE`]).
/// - `calib_pose.yaml`: `rotation` (3×3) and `translation` (3×1, metres) map the IR frame
///   into the colour frame, `X_c = R·X_ir + T`: this is `color_from_depth`
///   (`kinect2_bridge` publishes it as the TF from the colour to the IR optical frame).
/// - `calib_depth.yaml`: `depthShift`, millimetres, added to raw depth → `depth_shift_mm`.
///   Folders without it exist (the upstream repository's `299150235147`);
///   `kinect2_bridge` then uses a shift of 0, and so does this reader, with a note.
///
/// `world_from_depth` is the identity (the folder knows nothing of the world) and
/// `depth_scale` is 1000 (Kinect v2 depth is in millimetres).
pub fn import_iai_kinect2(dir: &Path) -> Result<ImportedCamera, CalibError> {
    if !dir.is_dir() {
        return Err(CalibError::Read {
            cause: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "not an iai_kinect2 calibration folder",
            ),
            path: dir.to_path_buf(),
        });
    }
    let color = read_intrinsics(&dir.join("calib_color.yaml"), KINECT2_COLOR_SIZE)?;
    let depth = read_intrinsics(&dir.join("calib_ir.yaml"), KINECT2_DEPTH_SIZE)?;

    let pose_path = dir.join("calib_pose.yaml");
    let pose = FileStorage::read(&pose_path)?;
    let r = pose.matrix("rotation", 3, 3)?;
    let t = pose.matrix("translation", 3, 1)?;
    let color_from_depth = Pose::from_rotation_translation(
        [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]],
        [t[0], t[1], t[2]],
    )
    .map_err(|e| in_file(e, "rotation", &pose_path))?;

    let mut notes = Vec::new();
    let depth_path = dir.join("calib_depth.yaml");
    let depth_shift_mm = if depth_path.exists() {
        FileStorage::read(&depth_path)?.number("depthShift")?
    } else {
        notes.push(format!(
            "no calib_depth.yaml: depth shift 0 mm (what kinect2_bridge uses then): {}",
            dir.display()
        ));
        0.0
    };

    let name = dir.file_name().map_or_else(
        || "kinect2".to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    Ok(ImportedCamera {
        camera: RgbdCamera {
            name,
            depth,
            color,
            color_from_depth,
            world_from_depth: Pose::identity(),
            depth_scale: DEFAULT_DEPTH_SCALE,
            depth_shift_mm,
        },
        notes,
    })
}

/// Writes an iai_kinect2 calibration folder for `camera`: the four files in the layout
/// `kinect2_calibration` writes (OpenCV FileStorage `%YAML:1.0`, doubles as `%.16e`), so
/// that [`read_iai_kinect2`] — and iai_kinect2 itself — read them back. The folder is
/// created if needed; each file is written through a temporary and a rename.
///
/// - `calib_color.yaml`, `calib_ir.yaml`: `cameraMatrix`, `distortionCoefficients` (5
///   values, or 8 for a rational model),
///   `rotation` (identity) and `projection` (`[K | 0; 0 0 0 1]`), like the tool; plus
///   `image_width`/`image_height` only when the size is not the Kinect v2 one (the tool
///   never writes them, the reader accepts them).
/// - `calib_pose.yaml`: `rotation`, `translation` (`color_from_depth`), and the stereo
///   `essential` (`[t]× R`) and `fundamental` (`K_c⁻ᵀ E K_ir⁻¹`, scaled so its last entry is
///   1) matrices the tool also writes; readers ignore the last two.
/// - `calib_depth.yaml`: `depthShift` = `depth_shift_mm`.
///
/// The format has no `world_from_depth` (it is dropped) and no depth scale: a camera
/// whose `depth_scale` is not 1000 is refused (error on `depth_scale`). All written
/// values are printed with 17 significant digits, so a round trip is bit-exact.
pub fn write_iai_kinect2(dir: &Path, camera: &RgbdCamera) -> Result<(), CalibError> {
    camera.validate_millimetre_depth(
        "for an iai_kinect2 folder (Kinect v2 depth is in millimetres)",
    )?;
    std::fs::create_dir_all(dir).map_err(|cause| CalibError::Write {
        cause,
        path: dir.to_path_buf(),
    })?;
    write_atomic(
        &dir.join("calib_color.yaml"),
        &intrinsics_text(&camera.color, KINECT2_COLOR_SIZE),
    )?;
    write_atomic(
        &dir.join("calib_ir.yaml"),
        &intrinsics_text(&camera.depth, KINECT2_DEPTH_SIZE),
    )?;

    let r = camera.color_from_depth.rotation();
    let t = camera.color_from_depth.translation_m();
    let tx = [[0.0, -t[2], t[1]], [t[2], 0.0, -t[0]], [-t[1], t[0], 0.0]];
    let essential = mat_mul(&tx, &r);
    let k_inv = |i: &Intrinsics| {
        [
            [1.0 / i.fx, 0.0, -i.cx / i.fx],
            [0.0, 1.0 / i.fy, -i.cy / i.fy],
            [0.0, 0.0, 1.0],
        ]
    };
    let kc_inv = k_inv(&camera.color);
    let kc_inv_t = std::array::from_fn(|a| std::array::from_fn(|b| kc_inv[b][a]));
    let mut fundamental = mat_mul(&mat_mul(&kc_inv_t, &essential), &k_inv(&camera.depth));
    let scale = fundamental[2][2];
    if scale != 0.0 {
        fundamental = fundamental.map(|row| row.map(|v| v / scale));
    }
    let flat = |m: &[[f64; 3]; 3]| m.iter().flatten().copied().collect::<Vec<_>>();
    let pose_text = format!(
        "%YAML:1.0\n{}{}{}{}",
        format_matrix("rotation", 3, 3, &flat(&r)),
        format_matrix("translation", 3, 1, &t),
        format_matrix("essential", 3, 3, &flat(&essential)),
        format_matrix("fundamental", 3, 3, &flat(&fundamental)),
    );
    write_atomic(&dir.join("calib_pose.yaml"), &pose_text)?;
    write_atomic(
        &dir.join("calib_depth.yaml"),
        &format!(
            "%YAML:1.0\ndepthShift: {}\n",
            format_number(camera.depth_shift_mm)
        ),
    )
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn intrinsics_text(i: &Intrinsics, default_size: [u32; 2]) -> String {
    let mut out = String::from("%YAML:1.0\n");
    if [i.width, i.height] != default_size {
        out += &format!("image_width: {}\nimage_height: {}\n", i.width, i.height);
    }
    out += &format_matrix(
        "cameraMatrix",
        3,
        3,
        &[i.fx, 0.0, i.cx, 0.0, i.fy, i.cy, 0.0, 0.0, 1.0],
    );
    let d = i.distortion.coefficients();
    out += &format_matrix("distortionCoefficients", 1, d.len(), d);
    out += &format_matrix(
        "rotation",
        3,
        3,
        &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    );
    out += &format_matrix(
        "projection",
        4,
        4,
        &[
            i.fx, 0.0, i.cx, 0.0, 0.0, i.fy, i.cy, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ],
    );
    out
}

/// Turns a value error into one naming the file and its key.
fn in_file(e: CalibError, key: &str, path: &Path) -> CalibError {
    match e {
        CalibError::Invalid { field, reason } => CalibError::BadValue {
            key: key.to_string(),
            reason: format!("{field} {reason}"),
            path: path.to_path_buf(),
        },
        other => other,
    }
}

fn read_intrinsics(path: &Path, default_size: [u32; 2]) -> Result<Intrinsics, CalibError> {
    crate::opencv_yaml::read_opencv_yaml_intrinsics(path, Some(default_size))
}
