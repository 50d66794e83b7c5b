//! `bodyseg import cloud`: organised point clouds of one depth camera (PCL's PCD as its
//! grabbers write them, or an organised PLY) → a one-camera recording (FORMATS.md) that
//! `bodyseg run` reads: `cam0/depth/<stem>.png` (z in millimetres), `cam0/color/<stem>.png`,
//! and `rig.toml` whose intrinsics are fitted from the grid and whose world frame is the
//! floor's.
//!
//! An organised cloud in its camera's frame is a pinhole grid: the point of cell (u, v)
//! projects back onto it, `u = fx·x/z + cx`, `v = fy·y/z + cy`. Least squares over every
//! valid point of every input gives fx, cx and fy, cy (two independent 2-parameter fits);
//! the RMS of the residuals says whether the cloud is such a grid (PCL's grabbers compute
//! x and y from the depth with exactly these intrinsics: the residual is float rounding)
//! or was moved into another frame, which no pinhole camera explains. Colour and depth are
//! the same sensor (`color_from_depth` identity, no distortion); `world_from_depth` puts
//! the floor found in the first cloud that shows one at z = 0, z up
//! ([`bodyseg_people::find_floor`]). The camera is assumed static over the inputs.

use crate::floor::likely_cause;
use crate::outputs::read_cloud_file;
use crate::recording::{Layer, RecordingWriter};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_calib::{Intrinsics, Pose, RgbdCamera, Rig};
use bodyseg_io::{CloudFile, CloudGrid, discard_folder, publish_folder, staging_folder};
use bodyseg_people::{Floor, FloorHint};
use std::path::{Path, PathBuf};

/// The grid fit's RMS residual above which a cloud is refused as no pinhole grid,
/// pixels: PCL's grabbers and ROS's depth_image_proc compute x, y from the depth with the
/// camera's intrinsics, so their residual is float rounding (< 0.01 px); a cloud moved
/// into another frame, or a lens model with distortion, is off by many pixels.
pub const MAX_GRID_RMS_PX: f64 = 0.5;
/// The fit needs at least this many valid points.
const MIN_FIT_POINTS: usize = 100;
/// The name of the one camera.
const CAMERA: &str = "cam0";
/// Raw depth units per metre of the written depth PNGs: millimetres.
const DEPTH_UNITS_PER_M: f64 = 1000.0;

/// What [`import_cloud`] reads and writes.
#[derive(Clone, Debug)]
pub struct ImportCloudOptions {
    /// Organised clouds, in frame order: `.pcd` or `.ply` files, or folders of them (their
    /// `.pcd`/`.ply` files sorted by name). At least one.
    pub inputs: Vec<PathBuf>,
    /// The recording folder to write.
    pub out: PathBuf,
    /// The floor, when the user knows it (`--ground`, `--up`); default: found.
    pub floor: FloorHint,
    /// Replace an existing `out`.
    pub force: bool,
}

/// The pinhole intrinsics fitted from the clouds' grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFit {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point, column, pixels.
    pub cx: f64,
    /// Principal point, row, pixels.
    pub cy: f64,
    /// RMS of the residuals (u and v together), pixels.
    pub rms_px: f64,
    /// Points the fit used.
    pub points: usize,
}

/// What [`import_cloud`] did.
#[derive(Clone, Debug)]
pub struct ImportCloudSummary {
    /// The frames written: stem and the cloud it came from, in order.
    pub frames: Vec<(String, PathBuf)>,
    /// The intrinsics written (depth and colour sensor alike).
    pub fit: GridFit,
    /// The floor that gives `world_from_depth`; `None`: none found, identity.
    pub floor: Option<Floor>,
    /// What the user should know that is no error, one line each.
    pub notes: Vec<String>,
    /// Per stage (read, intrinsics, floor, write): time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// Turns organised clouds into a one-camera recording (module docs).
///
/// # Errors
/// No input; an input cannot be read (the reader's error names the file); a cloud is not
/// organised (the message names PCD's `HEIGHT`, PLY's `num_cols`/`num_rows`) or its grid
/// differs from the first's; the grid fit has too few points, a non-positive focal length
/// or an RMS residual above [`MAX_GRID_RMS_PX`] (not a camera's frame); `--ground` is not
/// a plane; `out` exists without `force`; writing fails. Nothing is written unless every
/// input was read and checked, and a failed write leaves no partial recording.
pub fn import_cloud(opts: &ImportCloudOptions) -> Result<ImportCloudSummary> {
    let mut stages = Vec::new();
    let mut notes = Vec::new();
    if opts.out.exists() && !opts.force {
        bail!(
            "{}: already exists (use --force to replace it)",
            opts.out.display()
        );
    }
    let files = input_files(&opts.inputs)?;
    let (clouds, took) = timed(|| -> Result<Vec<(CloudFile, CloudGrid)>> {
        let mut out: Vec<(CloudFile, CloudGrid)> = Vec::with_capacity(files.len());
        for path in &files {
            let mut file = read_cloud_file(path).context("input cloud")?;
            let Some(grid) = file.grid.take() else {
                bail!("{}", not_organised(path));
            };
            if let Some((_, first)) = out.first()
                && (grid.width, grid.height) != (first.width, first.height)
            {
                bail!(
                    "{}: a {}x{} grid, but {} is {}x{}: the clouds of one recording come from one \
                     camera",
                    path.display(),
                    grid.width,
                    grid.height,
                    files[0].display(),
                    first.width,
                    first.height
                );
            }
            out.push((file, grid));
        }
        Ok(out)
    })?;
    let (width, height) = (clouds[0].1.width, clouds[0].1.height);
    stages.push(Stage::new(
        "read",
        took,
        format!(
            "{}, {width}x{height} grid",
            plural(clouds.len(), "organised cloud", "organised clouds")
        ),
    ));

    let (fit, took) = timed(|| fit_grid(&clouds, &files))?;
    stages.push(Stage::new(
        "intrinsics",
        took,
        format!(
            "fx {:.2} fy {:.2} cx {:.2} cy {:.2} px, RMS residual {:.4} px over {}",
            fit.fx,
            fit.fy,
            fit.cx,
            fit.cy,
            fit.rms_px,
            plural(fit.points, "point", "points")
        ),
    ));

    let (floor, took) = timed(|| -> Result<Option<Floor>> {
        for (file, _) in &clouds {
            let found = bodyseg_people::find_floor(&file.cloud.positions_m, &opts.floor)
                .map_err(|e| anyhow::anyhow!("--ground: {e}"))?;
            if found.is_some() {
                return Ok(found);
            }
        }
        Ok(None)
    })?;
    let world_from_depth = match &floor {
        Some(f) => {
            let t = f.world_from_cloud();
            Pose::from_rotation_translation(t.rotation, t.translation_m)
                .context("world_from_depth from the floor")?
        }
        None => {
            tracing::warn!(
                "{}: no floor found in any of the clouds (no large plane that the points stand \
                 on); likely cause: {}. world_from_depth is the identity, so the world frame is \
                 the camera's (y down) and `bodyseg run` will find no person; give the floor \
                 with --ground a,b,c,d or --up AXIS",
                files[0].display(),
                likely_cause(&clouds[0].0.cloud.positions_m, false)
            );
            Pose::identity()
        }
    };
    stages.push(Stage::new(
        "floor",
        took,
        match &floor {
            Some(f) => format!(
                "normal ({:.3}, {:.3}, {:.3}) in the camera's frame, {:.2} m below it: \
                 world_from_depth puts it at z = 0, z up",
                f.normal[0], f.normal[1], f.normal[2], f.offset_m
            ),
            None => "none found: world_from_depth is the identity".into(),
        },
    ));

    let sensor = Intrinsics::pinhole(width, height, fit.fx, fit.fy, fit.cx, fit.cy);
    let mut camera = RgbdCamera::new(CAMERA, sensor, sensor);
    camera.world_from_depth = world_from_depth;
    camera.depth_scale = DEPTH_UNITS_PER_M;
    let rig = Rig {
        cameras: vec![camera],
    };
    rig.validate().context("the imported rig")?;

    let frames: Vec<(String, PathBuf)> = files
        .iter()
        .enumerate()
        .map(|(k, p)| (format!("{k:06}"), p.clone()))
        .collect();
    let mut far = 0usize;
    let mut grey = false;
    let ((), took) = timed(|| -> Result<()> {
        let staging = staging_folder(&opts.out)?;
        let result = (|| -> Result<()> {
            let rec = RecordingWriter::create(&staging, &rig, &[Layer::Color, Layer::Depth])?;
            for ((stem, _), (file, grid)) in frames.iter().zip(&clouds) {
                let (depth, beyond) = depth_image(file, grid);
                far += beyond;
                rec.write_depth(0, stem, &depth)?;
                let rgb = match &grid.colors {
                    Some(colors) => colors.iter().flatten().copied().collect(),
                    None => {
                        grey = true;
                        vec![128u8; grid.width as usize * grid.height as usize * 3]
                    }
                };
                rec.write_color(0, stem, &rgb)?;
            }
            Ok(())
        })();
        if let Err(e) = result {
            discard_folder(&staging);
            return Err(e);
        }
        Ok(publish_folder(&staging, &opts.out, opts.force)?)
    })?;
    if far > 0 {
        notes.push(format!(
            "{} farther than {:.1} m (beyond a 16-bit depth PNG in millimetres) written as no \
             measurement",
            plural(far, "point", "points"),
            f64::from(u16::MAX) / DEPTH_UNITS_PER_M
        ));
    }
    if grey {
        notes.push(
            "the clouds have no colour: the colour images are grey (geometry-mode boxes need \
             none; a parser finds nothing in them)"
                .into(),
        );
    }
    stages.push(Stage::new(
        "write",
        took,
        format!(
            "{}: rig.toml, {}",
            opts.out.display(),
            plural(frames.len(), "frame", "frames")
        ),
    ));
    Ok(ImportCloudSummary {
        frames,
        fit,
        floor,
        notes,
        stages,
    })
}

/// The cloud files of `inputs`: files as given, folders' `.pcd`/`.ply` files sorted by
/// name.
fn input_files(inputs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for input in inputs {
        if input.is_dir() {
            let before = files.len();
            for entry in bodyseg_io::list_folder(input, "input")? {
                let lower = entry.name.to_ascii_lowercase();
                if !entry.is_folder && (lower.ends_with(".pcd") || lower.ends_with(".ply")) {
                    files.push(input.join(&entry.name));
                }
            }
            if files.len() == before {
                bail!("{}: no .pcd or .ply file in this folder", input.display());
            }
        } else {
            files.push(input.clone());
        }
    }
    if files.is_empty() {
        bail!("no input cloud: give at least one .pcd or .ply file, or a folder of them");
    }
    Ok(files)
}

/// The error for a cloud without a grid, naming the header field that says so.
fn not_organised(path: &Path) -> String {
    let pcd = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pcd"));
    if pcd {
        format!(
            "{}: not an organised cloud: its HEIGHT is 1 (WIDTH is the point count); import \
             cloud needs a depth camera's image grid (WIDTH x HEIGHT with HEIGHT > 1, as PCL's \
             grabbers write it)",
            path.display()
        )
    } else {
        format!(
            "{}: not an organised cloud: no 'obj_info num_cols' / 'obj_info num_rows' with a \
             range_grid element or num_cols x num_rows vertices (as PCL writes an organised \
             PLY); import cloud needs a depth camera's image grid",
            path.display()
        )
    }
}

/// Least squares of `u = fx·x/z + cx` and `v = fy·y/z + cy` over every point with z > 0
/// (cell (u, v) from its origin's pixel), with the RMS residual; refused as the module
/// docs say.
fn fit_grid(clouds: &[(CloudFile, CloudGrid)], files: &[PathBuf]) -> Result<GridFit> {
    // Sums for the two 2×2 normal equations: [Σa² Σa; Σa n] [f; c] = [Σau; Σu].
    let mut s = [[0.0f64; 5]; 2];
    let mut n = 0usize;
    for (file, grid) in clouds {
        for (p, o) in file.cloud.positions_m.iter().zip(&file.cloud.origins) {
            if p[2] <= 0.0 {
                continue;
            }
            let z = f64::from(p[2]);
            let cell = [
                f64::from(o.pixel % grid.width),
                f64::from(o.pixel / grid.width),
            ];
            for axis in 0..2 {
                let a = f64::from(p[axis]) / z;
                let t = &mut s[axis];
                t[0] += a * a;
                t[1] += a;
                t[2] += a * cell[axis];
                t[3] += cell[axis];
                t[4] += cell[axis] * cell[axis];
            }
            n += 1;
        }
    }
    if n < MIN_FIT_POINTS {
        bail!(
            "{}: {} in front of the camera (z > 0), too few to fit the intrinsics (at least \
             {MIN_FIT_POINTS})",
            files[0].display(),
            plural(n, "valid point", "valid points")
        );
    }
    let k = n as f64;
    let mut fc = [[0.0f64; 2]; 2];
    for axis in 0..2 {
        let t = &s[axis];
        let det = t[0] * k - t[1] * t[1];
        if det.abs() <= 1e-12 * t[0] * k {
            bail!(
                "{}: every point lies on one ray through the camera along {}: not a depth \
                 camera's grid",
                files[0].display(),
                ["x", "y"][axis]
            );
        }
        let f = (t[2] * k - t[1] * t[3]) / det;
        let c = (t[0] * t[3] - t[1] * t[2]) / det;
        fc[axis] = [f, c];
    }
    // Residual sum of squares from the sums: Σ(f a + c − u)².
    let mut rss = 0.0;
    for axis in 0..2 {
        let t = &s[axis];
        let [f, c] = fc[axis];
        rss +=
            f * f * t[0] + 2.0 * f * c * t[1] + c * c * k - 2.0 * f * t[2] - 2.0 * c * t[3] + t[4];
    }
    let fit = GridFit {
        fx: fc[0][0],
        fy: fc[1][0],
        cx: fc[0][1],
        cy: fc[1][1],
        rms_px: (rss.max(0.0) / k).sqrt(),
        points: n,
    };
    if !(fit.fx > 0.0 && fit.fy > 0.0) {
        bail!(
            "{}: the grid fits fx {:.1}, fy {:.1}: a mirrored or transformed grid, not a depth \
             camera's own frame (x right, y down, z forward)",
            files[0].display(),
            fit.fx,
            fit.fy
        );
    }
    if fit.rms_px.is_nan() || fit.rms_px > MAX_GRID_RMS_PX {
        bail!(
            "{}: the points are no pinhole grid: fitting u = fx*x/z + cx, v = fy*y/z + cy leaves \
             an RMS residual of {:.2} px (at most {MAX_GRID_RMS_PX} px): the cloud is not in its \
             camera's frame (moved into another one?) or its lens has distortion",
            files[0].display(),
            fit.rms_px
        );
    }
    Ok(fit)
}

/// The depth image of one cloud (z in millimetres, 0 where the cell has no point, z <= 0
/// or z beyond a u16), and how many points were too far for it.
fn depth_image(file: &CloudFile, grid: &CloudGrid) -> (Vec<u16>, usize) {
    let mut depth = vec![0u16; grid.width as usize * grid.height as usize];
    let mut far = 0;
    for (p, o) in file.cloud.positions_m.iter().zip(&file.cloud.origins) {
        let mm = (f64::from(p[2]) * DEPTH_UNITS_PER_M).round();
        let Some(cell) = depth.get_mut(o.pixel as usize) else {
            continue;
        };
        if mm > f64::from(u16::MAX) {
            far += 1;
        } else if mm >= 1.0 {
            *cell = mm as u16;
        }
    }
    (depth, far)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::{LabeledCloud, PointOrigin};
    use bodyseg_io::FileLabels;

    /// A 40×30 grid seen by a camera with `f` and `c`, the points at a bumpy depth of
    /// 2–2.5 m, optionally moved by `shift` (no longer in the camera's frame).
    fn grid_cloud(f: [f64; 2], c: [f64; 2], shift: [f32; 3]) -> (CloudFile, CloudGrid) {
        let (w, h) = (40u32, 30u32);
        let mut cloud = LabeledCloud::default();
        for v in 0..h {
            for u in 0..w {
                let z = depth_at(u, v);
                let x = (f64::from(u) - c[0]) * z / f[0];
                let y = (f64::from(v) - c[1]) * z / f[1];
                cloud.positions_m.push([
                    x as f32 + shift[0],
                    y as f32 + shift[1],
                    z as f32 + shift[2],
                ]);
                cloud.labels.push(bodyseg_core::Label::UNKNOWN);
                cloud.origins.push(PointOrigin {
                    camera: 0,
                    pixel: v * w + u,
                });
            }
        }
        let grid = CloudGrid {
            width: w,
            height: h,
            colors: None,
        };
        let file = CloudFile {
            cloud,
            labels: FileLabels::Absent,
            grid: None,
        };
        (file, grid)
    }

    /// The depth of cell (u, v), metres: 2 m plus steps that follow neither u nor v, so
    /// that a moved cloud's x/z, y/z cannot be fitted by other intrinsics.
    fn depth_at(u: u32, v: u32) -> f64 {
        2.0 + 0.05 * f64::from((7 * u + 3 * v) % 11)
    }

    #[test]
    fn the_grid_fit_recovers_the_intrinsics_and_refuses_a_moved_cloud() {
        let files = [PathBuf::from("c.pcd")];
        let fit = fit_grid(
            &[grid_cloud([525.0, 520.0], [19.5, 14.5], [0.0; 3])],
            &files,
        )
        .expect("a pinhole grid");
        // f32 positions: the fit is exact to float rounding.
        assert!(
            (fit.fx - 525.0).abs() < 0.05 && (fit.fy - 520.0).abs() < 0.05,
            "{fit:?}"
        );
        assert!(
            (fit.cx - 19.5).abs() < 0.01 && (fit.cy - 14.5).abs() < 0.01,
            "{fit:?}"
        );
        assert!(fit.rms_px < 0.01, "{fit:?}");
        assert_eq!(fit.points, 1200);
        // The same cloud moved 0.3 m sideways is no camera's grid any more.
        let moved = fit_grid(
            &[grid_cloud([525.0, 520.0], [19.5, 14.5], [0.3, 0.0, 0.0])],
            &files,
        )
        .expect_err("moved");
        assert!(moved.to_string().contains("no pinhole grid"), "{moved}");
    }

    #[test]
    fn depth_is_written_in_millimetres_with_the_far_points_counted() {
        let (mut file, grid) = grid_cloud([525.0, 525.0], [19.5, 14.5], [0.0; 3]);
        file.cloud.positions_m[0][2] = 70.0; // beyond 65.535 m
        file.cloud.positions_m[1][2] = -1.0; // behind the camera
        let (depth, far) = depth_image(&file, &grid);
        assert_eq!(far, 1);
        assert_eq!((depth[0], depth[1]), (0, 0));
        assert_eq!(depth[2], (depth_at(2, 0) * 1000.0).round() as u16);
        assert_eq!(depth[2], 2150);
    }
}
