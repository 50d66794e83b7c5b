//! Chessboard calibration with OpenCV (feature `opencv`): corner detection with sub-pixel
//! refinement, single-sensor intrinsics (`calibrateCamera`), the stereo extrinsic of two
//! sensors (`stereoCalibrate` with both intrinsics fixed), a sensor's pose from one board
//! view (`solvePnP`), and intrinsics files in OpenCV's FileStorage (YAML or XML) read and
//! written by OpenCV itself.
//!
//! OpenCV types stay inside this module: callers see [`GrayImage`], [`Board`],
//! [`Intrinsics`], [`Pose`] and plain arrays. Pixel coordinates follow the crate's
//! convention, which is OpenCV's (integer coordinates at pixel centres).

use std::path::Path;

use opencv::core::{self, FileStorage, Mat, Point2f, Point3f, Size, TermCriteria, Vector};
use opencv::prelude::*;
use opencv::{calib3d, imgproc};

use crate::board::{Board, BoardZ, GrayImage, canonical_corner_order};
use crate::{CalibError, Intrinsics, Pose};

/// Largest half side, pixels, of the `cornerSubPix` search window (OpenCV's tutorials use
/// 11 for boards of 30+ px squares).
const SUBPIX_MAX_HALF_WINDOW_PX: i32 = 11;

/// Smallest half side of the window, pixels.
const SUBPIX_MIN_HALF_WINDOW_PX: i32 = 2;

/// Distance, pixels, the `cornerSubPix` window keeps from the square edges that do not pass
/// through its corner: the width of a blurred edge plus a margin.
const SUBPIX_EDGE_MARGIN_PX: f64 = 2.0;

/// `cornerSubPix` stops after this many iterations or a move below
/// [`SUBPIX_EPSILON_PX`].
const SUBPIX_MAX_ITERATIONS: i32 = 100;

/// `cornerSubPix` stops when a corner moves less than this, pixels.
const SUBPIX_EPSILON_PX: f64 = 1e-3;

/// Fewest board views [`calibrate_intrinsics`] accepts: five-coefficient distortion and
/// four pinhole parameters need several board orientations (15–20 are advised).
pub const MIN_INTRINSICS_VIEWS: usize = 3;

fn cv_err(operation: &str) -> impl Fn(opencv::Error) -> CalibError + '_ {
    move |e| CalibError::OpenCv {
        operation: operation.to_string(),
        cause: e.message,
    }
}

fn size_i32(width: u32, height: u32) -> Result<Size, CalibError> {
    let w = i32::try_from(width).map_err(|_| CalibError::invalid("width", "too large"))?;
    let h = i32::try_from(height).map_err(|_| CalibError::invalid("height", "too large"))?;
    Ok(Size::new(w, h))
}

/// Finds the board's inner corners in `image`, refines them to sub-pixel accuracy and puts
/// them in the board's canonical order ([`canonical_corner_order`] with `z`). `Ok(None)`
/// when the board is not found.
pub fn find_board_corners(
    image: &GrayImage,
    board: &Board,
    z: BoardZ,
) -> Result<Option<Vec<[f64; 2]>>, CalibError> {
    let size = size_i32(image.width, image.height)?;
    if image.data.len() != image.width as usize * image.height as usize {
        return Err(CalibError::invalid(
            "image",
            format!(
                "{}x{} needs {} pixels, got {}",
                image.width,
                image.height,
                image.width as usize * image.height as usize,
                image.data.len()
            ),
        ));
    }
    let mat = Mat::new_rows_cols_with_data(size.height, size.width, &image.data)
        .map_err(cv_err("image"))?;
    let pattern = size_i32(board.inner_corners[0], board.inner_corners[1])?;
    // OpenCV's classic detector first (quick to reject an image without a board: fast
    // check); where it fails (small or foreshortened squares, e.g. a floor board seen by an
    // IR sensor from 3 m), the sector-based detector of Duda & Frese (findChessboardCornersSB),
    // slower but more robust.
    let mut corners: Vector<Point2f> = Vector::new();
    let mut found = calib3d::find_chessboard_corners(
        &mat,
        pattern,
        &mut corners,
        calib3d::CALIB_CB_ADAPTIVE_THRESH
            | calib3d::CALIB_CB_NORMALIZE_IMAGE
            | calib3d::CALIB_CB_FAST_CHECK,
    )
    .map_err(cv_err("findChessboardCorners"))?;
    if !found {
        corners = Vector::new();
        found = calib3d::find_chessboard_corners_sb(
            &mat,
            pattern,
            &mut corners,
            calib3d::CALIB_CB_NORMALIZE_IMAGE,
        )
        .map_err(cv_err("findChessboardCornersSB"))?;
    }
    if !found || corners.len() != board.num_corners() {
        return Ok(None);
    }
    let pts: Vec<[f64; 2]> = corners
        .iter()
        .map(|p| [f64::from(p.x), f64::from(p.y)])
        .collect();
    let (hx, hy) = subpix_window(&pts, board.inner_corners[0] as usize);
    imgproc::corner_sub_pix(
        &mat,
        &mut corners,
        Size::new(hx, hy),
        Size::new(-1, -1),
        TermCriteria::new(
            core::TermCriteria_COUNT + core::TermCriteria_EPS,
            SUBPIX_MAX_ITERATIONS,
            SUBPIX_EPSILON_PX,
        )
        .map_err(cv_err("TermCriteria"))?,
    )
    .map_err(cv_err("cornerSubPix"))?;
    let refined: Vec<[f64; 2]> = corners
        .iter()
        .map(|p| [f64::from(p.x), f64::from(p.y)])
        .collect();
    canonical_corner_order(board, &refined, image, z).map(Some)
}

/// The `cornerSubPix` half window (x, y), pixels: the largest window (by area) that keeps
/// [`SUBPIX_EDGE_MARGIN_PX`] from every square edge not passing through the corner, at
/// every corner of the board (`corners` rows of `nx`). Only the edges through the corner
/// satisfy `cornerSubPix`'s model (the gradient orthogonal to the ray from the corner);
/// the others pull the estimate. The window is rectangular because a foreshortened board
/// (a floor board seen from 3 m) has squares several times wider than high: a square
/// window would be cut to the short side and lose most of the usable pixels.
fn subpix_window(corners: &[[f64; 2]], nx: usize) -> (i32, i32) {
    // Per corner and grid direction: the unit normal of the non-incident edge lines and
    // their distance from the corner. A box of half sides (hx, hy) stays off a line of unit
    // normal n at distance d when hx·|n_u| + hy·|n_v| < d.
    let mut lines: Vec<([f64; 2], f64)> = Vec::new();
    let at = |i: usize, j: usize| corners.get(j * nx + i).copied();
    let ny = corners.len() / nx.max(1);
    for j in 0..ny {
        for i in 0..nx {
            let Some(c) = at(i, j) else { continue };
            // Edge vectors to the next corner along x and y (backwards at the far side).
            let step = |di: isize, dj: isize| {
                let (a, b) = (i as isize + di, j as isize + dj);
                let q = (a >= 0 && b >= 0)
                    .then(|| at(a as usize, b as usize))
                    .flatten()
                    .filter(|_| (a as usize) < nx && (b as usize) < ny)?;
                Some([q[0] - c[0], q[1] - c[1]])
            };
            let (Some(ex), Some(ey)) = (
                step(1, 0).or_else(|| step(-1, 0)),
                step(0, 1).or_else(|| step(0, -1)),
            ) else {
                continue;
            };
            let area = (ex[0] * ey[1] - ex[1] * ey[0]).abs();
            // The edge lines through the next corners: through c + ex along ey, and through
            // c + ey along ex, at distances area / |ey| and area / |ex|.
            for along in [ey, ex] {
                let len = (along[0] * along[0] + along[1] * along[1]).sqrt();
                if len > 0.0 {
                    lines.push(([-along[1] / len, along[0] / len], area / len));
                }
            }
        }
    }
    let fits = |hx: i32, hy: i32| {
        lines.iter().all(|(n, d)| {
            f64::from(hx) * n[0].abs() + f64::from(hy) * n[1].abs() < d - SUBPIX_EDGE_MARGIN_PX
        })
    };
    let mut best = (SUBPIX_MIN_HALF_WINDOW_PX, SUBPIX_MIN_HALF_WINDOW_PX);
    for hx in SUBPIX_MIN_HALF_WINDOW_PX..=SUBPIX_MAX_HALF_WINDOW_PX {
        for hy in SUBPIX_MIN_HALF_WINDOW_PX..=SUBPIX_MAX_HALF_WINDOW_PX {
            if (2 * hx + 1) * (2 * hy + 1) > (2 * best.0 + 1) * (2 * best.1 + 1) && fits(hx, hy) {
                best = (hx, hy);
            }
        }
    }
    best
}

/// Intrinsics fitted to board views, with their reprojection errors.
#[derive(Clone, Debug, PartialEq)]
pub struct IntrinsicsFit {
    /// The fitted sensor (five distortion coefficients).
    pub intrinsics: Intrinsics,
    /// Root-mean-square reprojection error over every corner of every view, pixels.
    pub rms_px: f64,
    /// Per view, the RMS reprojection error of its corners, pixels (views in input order).
    pub view_rms_px: Vec<f64>,
    /// Per view, the fitted pose of the board in the sensor frame.
    pub sensor_from_board: Vec<Pose>,
}

fn object_vector(board: &Board) -> Vector<Point3f> {
    board
        .object_points()
        .iter()
        .map(|p| Point3f::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect()
}

fn image_vector(corners: &[[f64; 2]]) -> Vector<Point2f> {
    corners
        .iter()
        .map(|p| Point2f::new(p[0] as f32, p[1] as f32))
        .collect()
}

fn check_views(board: &Board, views: &[Vec<[f64; 2]>]) -> Result<(), CalibError> {
    if let Some((k, v)) = views
        .iter()
        .enumerate()
        .find(|(_, v)| v.len() != board.num_corners())
    {
        return Err(CalibError::invalid(
            format!("view {k}"),
            format!(
                "has {} corners, a {} board has {}",
                v.len(),
                board.size_text(),
                board.num_corners()
            ),
        ));
    }
    Ok(())
}

fn camera_matrix(i: &Intrinsics) -> Result<Mat, CalibError> {
    Mat::from_slice_2d(&[[i.fx, 0.0, i.cx], [0.0, i.fy, i.cy], [0.0, 0.0, 1.0]])
        .map_err(cv_err("camera matrix"))
}

/// The distortion as OpenCV's `1×N` vector: 5 values (Brown-Conrady) or 8 (rational),
/// which OpenCV's functions tell apart by the length.
fn distortion_mat(i: &Intrinsics) -> Result<Mat, CalibError> {
    Mat::from_slice_2d(&[i.distortion.coefficients()]).map_err(cv_err("distortion"))
}

/// Reads `n` doubles of a continuous `CV_64F` matrix (any shape).
fn mat_values(m: &Mat, n: usize, what: &str) -> Result<Vec<f64>, CalibError> {
    let values = m.data_typed::<f64>().map_err(cv_err(what))?.to_vec();
    if values.len() < n {
        return Err(CalibError::OpenCv {
            operation: what.to_string(),
            cause: format!("expected {n} values, got {}", values.len()),
        });
    }
    Ok(values)
}

fn intrinsics_from(
    width: u32,
    height: u32,
    k: &Mat,
    dist: &Mat,
    what: &str,
) -> Result<Intrinsics, CalibError> {
    let k = mat_values(k, 9, what)?;
    let d = mat_values(dist, 5, what)?;
    let intrinsics = Intrinsics::from_camera_matrix(width, height, &k, &d).ok_or_else(|| {
        CalibError::OpenCv {
            operation: what.to_string(),
            cause: format!(
                "returned {} distortion coefficients, expected 5 or 8",
                d.len()
            ),
        }
    })?;
    intrinsics.validate()?;
    Ok(intrinsics)
}

/// When `calibrateCamera` and `stereoCalibrate` stop: 100 Levenberg-Marquardt iterations
/// or no change at machine precision (OpenCV's default is 30 iterations or 1e-16 change).
fn fit_criteria() -> Result<TermCriteria, CalibError> {
    TermCriteria::new(
        core::TermCriteria_COUNT + core::TermCriteria_EPS,
        100,
        f64::EPSILON,
    )
    .map_err(cv_err("TermCriteria"))
}

/// A pose from a row-major 3×3 rotation (OpenCV's `CV_64F` matrix values) and a translation.
fn pose_from_values(r: &[f64], t: &[f64]) -> Result<Pose, CalibError> {
    Pose::from_rotation_translation(
        [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]],
        [t[0], t[1], t[2]],
    )
}

/// A pose from OpenCV's rotation vector (Rodrigues) and translation.
fn pose_from_rvec_tvec(rvec: &impl core::ToInputArray, t: [f64; 3]) -> Result<Pose, CalibError> {
    let mut r = Mat::default();
    calib3d::rodrigues(rvec, &mut r, &mut core::no_array()).map_err(cv_err("Rodrigues"))?;
    pose_from_values(&mat_values(&r, 9, "Rodrigues")?, &t)
}

/// Fits a sensor's intrinsics (pinhole and `k1 k2 p1 p2 k3`) to the corners of at least
/// [`MIN_INTRINSICS_VIEWS`] views of `board` in images of `width × height` (OpenCV's
/// `calibrateCamera`).
pub fn calibrate_intrinsics(
    board: &Board,
    views: &[Vec<[f64; 2]>],
    width: u32,
    height: u32,
) -> Result<IntrinsicsFit, CalibError> {
    check_views(board, views)?;
    if views.len() < MIN_INTRINSICS_VIEWS {
        return Err(CalibError::invalid(
            "views",
            format!(
                "calibration needs at least {MIN_INTRINSICS_VIEWS} views of the board (15 or more advised), got {}",
                views.len()
            ),
        ));
    }
    let object = object_vector(board);
    let object_points: Vector<Vector<Point3f>> = views.iter().map(|_| object.clone()).collect();
    let image_points: Vector<Vector<Point2f>> = views.iter().map(|v| image_vector(v)).collect();
    let mut k = Mat::default();
    let mut dist = Mat::default();
    let mut rvecs: Vector<Mat> = Vector::new();
    let mut tvecs: Vector<Mat> = Vector::new();
    let mut std_intrinsics = Mat::default();
    let mut std_extrinsics = Mat::default();
    let mut per_view = Mat::default();
    let rms_px = calib3d::calibrate_camera_extended(
        &object_points,
        &image_points,
        size_i32(width, height)?,
        &mut k,
        &mut dist,
        &mut rvecs,
        &mut tvecs,
        &mut std_intrinsics,
        &mut std_extrinsics,
        &mut per_view,
        0,
        fit_criteria()?,
    )
    .map_err(cv_err("calibrateCamera"))?;
    let intrinsics = intrinsics_from(width, height, &k, &dist, "calibrateCamera")?;
    let view_rms_px = mat_values(&per_view, views.len(), "calibrateCamera per-view errors")?;
    let mut sensor_from_board = Vec::with_capacity(views.len());
    for (rvec, tvec) in rvecs.iter().zip(tvecs.iter()) {
        let t = mat_values(&tvec, 3, "calibrateCamera translation")?;
        sensor_from_board.push(pose_from_rvec_tvec(&rvec, [t[0], t[1], t[2]])?);
    }
    Ok(IntrinsicsFit {
        intrinsics,
        rms_px,
        view_rms_px: view_rms_px[..views.len()].to_vec(),
        sensor_from_board,
    })
}

/// One board view seen by two sensors at once: its corners in the first sensor's image and
/// in the second's, both in canonical order, pixels.
pub type CornerPair = (Vec<[f64; 2]>, Vec<[f64; 2]>);

/// The stereo extrinsic of two sensors fitted to simultaneous board views.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoFit {
    /// Maps points of the first sensor's frame into the second's.
    pub second_from_first: Pose,
    /// The first sensor's intrinsics: the given ones, or refined with the extrinsic.
    pub first: Intrinsics,
    /// The second sensor's intrinsics, likewise.
    pub second: Intrinsics,
    /// RMS reprojection error over both sensors' corners, pixels.
    pub rms_px: f64,
}

/// Fits the rigid transform between two sensors from views of `board` seen by both at the
/// same instants (`pairs[k]` = corners in the first and in the second sensor, both in
/// canonical order): OpenCV's `stereoCalibrate`, with the intrinsics fixed
/// (`refine_intrinsics` false) or refined together with the transform, starting from the
/// given ones. Refining helps: each sensor alone fits its focal lengths to within a few
/// tenths of a percent, and two independent errors of that size put millimetres of error
/// into the baseline along the viewing direction; a board pose shared by both sensors
/// removes most of it.
pub fn calibrate_stereo(
    board: &Board,
    first: &Intrinsics,
    second: &Intrinsics,
    pairs: &[CornerPair],
    refine_intrinsics: bool,
) -> Result<StereoFit, CalibError> {
    let (a, b): (Vec<_>, Vec<_>) = pairs.iter().cloned().unzip();
    check_views(board, &a)?;
    check_views(board, &b)?;
    if pairs.is_empty() {
        return Err(CalibError::invalid(
            "views",
            "stereo calibration needs at least one view of the board seen by both sensors",
        ));
    }
    let object = object_vector(board);
    let object_points: Vector<Vector<Point3f>> = pairs.iter().map(|_| object.clone()).collect();
    let points_a: Vector<Vector<Point2f>> = a.iter().map(|v| image_vector(v)).collect();
    let points_b: Vector<Vector<Point2f>> = b.iter().map(|v| image_vector(v)).collect();
    let (mut k1, mut d1) = (camera_matrix(first)?, distortion_mat(first)?);
    let (mut k2, mut d2) = (camera_matrix(second)?, distortion_mat(second)?);
    let (mut r, mut t, mut e, mut f) = (
        Mat::default(),
        Mat::default(),
        Mat::default(),
        Mat::default(),
    );
    let rms_px = calib3d::stereo_calibrate(
        &object_points,
        &points_a,
        &points_b,
        &mut k1,
        &mut d1,
        &mut k2,
        &mut d2,
        size_i32(first.width, first.height)?,
        &mut r,
        &mut t,
        &mut e,
        &mut f,
        if refine_intrinsics {
            calib3d::CALIB_USE_INTRINSIC_GUESS
        } else {
            calib3d::CALIB_FIX_INTRINSIC
        },
        fit_criteria()?,
    )
    .map_err(cv_err("stereoCalibrate"))?;
    let rv = mat_values(&r, 9, "stereoCalibrate rotation")?;
    let tv = mat_values(&t, 3, "stereoCalibrate translation")?;
    let second_from_first = pose_from_values(&rv, &tv)?;
    Ok(StereoFit {
        second_from_first,
        first: intrinsics_from(first.width, first.height, &k1, &d1, "stereoCalibrate")?,
        second: intrinsics_from(second.width, second.height, &k2, &d2, "stereoCalibrate")?,
        rms_px,
    })
}

/// The pose of `board` in a sensor's frame from one view of it (OpenCV's `solvePnP`,
/// iterative), with the RMS reprojection error of its corners, pixels.
pub fn board_pose(
    board: &Board,
    intrinsics: &Intrinsics,
    corners_px: &[[f64; 2]],
) -> Result<(Pose, f64), CalibError> {
    check_views(board, &[corners_px.to_vec()])?;
    let object = object_vector(board);
    let image = image_vector(corners_px);
    let (mut rvec, mut tvec) = (Mat::default(), Mat::default());
    let ok = calib3d::solve_pnp(
        &object,
        &image,
        &camera_matrix(intrinsics)?,
        &distortion_mat(intrinsics)?,
        &mut rvec,
        &mut tvec,
        false,
        calib3d::SOLVEPNP_ITERATIVE,
    )
    .map_err(cv_err("solvePnP"))?;
    if !ok {
        return Err(CalibError::OpenCv {
            operation: "solvePnP".into(),
            cause: "no pose found".into(),
        });
    }
    let t = mat_values(&tvec, 3, "solvePnP translation")?;
    let pose = pose_from_rvec_tvec(&rvec, [t[0], t[1], t[2]])?;
    Ok((
        pose,
        reprojection_rms_px(board, intrinsics, &pose, corners_px),
    ))
}

/// RMS distance, pixels, between `corners_px` and the board's corners projected through
/// `sensor_from_board` and `intrinsics`.
pub fn reprojection_rms_px(
    board: &Board,
    intrinsics: &Intrinsics,
    sensor_from_board: &Pose,
    corners_px: &[[f64; 2]],
) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (p, c) in board.object_points().iter().zip(corners_px) {
        if let Some(uv) = intrinsics.project(sensor_from_board.transform_point(*p)) {
            sum += (uv[0] - c[0]).powi(2) + (uv[1] - c[1]).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        f64::INFINITY
    } else {
        (sum / n as f64).sqrt()
    }
}

/// Writes a sensor's intrinsics with OpenCV's FileStorage, YAML or XML after the file's
/// extension (`.yaml`, `.yml`, `.xml`), with iai_kinect2's keys (`cameraMatrix`,
/// `distortionCoefficients`) plus `image_width`, `image_height` and, when given, the RMS
/// reprojection error `reprojection_error_px`. Written to a temporary file and renamed.
pub fn write_opencv_intrinsics(
    path: &Path,
    intrinsics: &Intrinsics,
    rms_px: Option<f64>,
) -> Result<(), CalibError> {
    intrinsics.validate()?;
    let format = storage_format(path)?;
    let write_err = |cause: String| CalibError::Write {
        cause: std::io::Error::other(cause),
        path: path.to_path_buf(),
    };
    // OpenCV picks the syntax from the name: the temporary keeps the extension.
    let ext = path
        .extension()
        .map_or_else(String::new, |e| e.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}.{ext}",
        path.file_stem()
            .map_or_else(|| "intrinsics".into(), |s| s.to_string_lossy().into_owned()),
        std::process::id()
    ));
    let result = (|| -> Result<(), CalibError> {
        let mut fs = FileStorage::new(
            tmp.to_string_lossy().as_ref(),
            core::FileStorage_WRITE | format,
            "",
        )
        .map_err(|e| write_err(e.message))?;
        if !fs.is_opened().map_err(|e| write_err(e.message))? {
            return Err(write_err("OpenCV cannot open it for writing".into()));
        }
        let w = |e: opencv::Error| write_err(e.message);
        let size = size_i32(intrinsics.width, intrinsics.height)?;
        fs.write_i32("image_width", size.width).map_err(w)?;
        fs.write_i32("image_height", size.height).map_err(w)?;
        fs.write_mat("cameraMatrix", &camera_matrix(intrinsics)?)
            .map_err(w)?;
        fs.write_mat("distortionCoefficients", &distortion_mat(intrinsics)?)
            .map_err(w)?;
        if let Some(rms) = rms_px {
            fs.write_f64("reprojection_error_px", rms).map_err(w)?;
        }
        fs.release().map_err(w)?;
        std::fs::rename(&tmp, path).map_err(|e| write_err(e.to_string()))
    })();
    if result.is_err() {
        // Best effort: the temporary may not exist.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn storage_format(path: &Path) -> Result<i32, CalibError> {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("yaml" | "yml") => Ok(core::FileStorage_FORMAT_YAML),
        Some("xml") => Ok(core::FileStorage_FORMAT_XML),
        _ => Err(CalibError::BadValue {
            key: "file name".into(),
            reason: "an OpenCV FileStorage file ends in .yaml, .yml or .xml".into(),
            path: path.to_path_buf(),
        }),
    }
}

/// Reads a sensor's intrinsics from an OpenCV FileStorage file (YAML or XML) through
/// OpenCV: `cameraMatrix` or `camera_matrix` (3×3), `distortionCoefficients` or
/// `distortion_coefficients` (5 values, k1 k2 p1 p2 k3; 4 are read with k3 = 0; 8 are
/// the rational model k1 k2 p1 p2 k3 k4 k5 k6), and the
/// image size from `image_width` and `image_height`, or `default_size` when the file has
/// none (iai_kinect2's files).
pub fn read_opencv_intrinsics(
    path: &Path,
    default_size: Option<[u32; 2]>,
) -> Result<Intrinsics, CalibError> {
    storage_format(path)?;
    if !path.is_file() {
        return Err(CalibError::Read {
            cause: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
            path: path.to_path_buf(),
        });
    }
    let syntax = |reason: String| CalibError::Syntax {
        line: 0,
        reason,
        path: path.to_path_buf(),
    };
    let fs = FileStorage::new(path.to_string_lossy().as_ref(), core::FileStorage_READ, "")
        .map_err(|e| syntax(e.message))?;
    if !fs.is_opened().map_err(|e| syntax(e.message))? {
        return Err(syntax("OpenCV cannot parse it as FileStorage".into()));
    }
    let bad = |key: &str, reason: String| CalibError::BadValue {
        key: key.into(),
        reason,
        path: path.to_path_buf(),
    };
    let node = |keys: &[&str]| -> Result<Option<(String, core::FileNode)>, CalibError> {
        for key in keys {
            let n = fs.get(key).map_err(|e| bad(key, e.message))?;
            if !n.is_none().map_err(|e| bad(key, e.message))? {
                return Ok(Some(((*key).to_string(), n)));
            }
        }
        Ok(None)
    };
    let matrix = |keys: &[&str], lens: &[usize]| -> Result<Vec<f64>, CalibError> {
        let Some((key, n)) = node(keys)? else {
            return Err(CalibError::MissingKey {
                key: keys.join(" or "),
                path: path.to_path_buf(),
            });
        };
        let m = n.mat().map_err(|e| bad(&key, e.message))?;
        let mut m64 = Mat::default();
        m.convert_to(&mut m64, core::CV_64F, 1.0, 0.0)
            .map_err(|e| bad(&key, e.message))?;
        let values: Vec<f64> = m64
            .data_typed::<f64>()
            .map_err(|e| bad(&key, e.message))?
            .to_vec();
        if !lens.contains(&values.len()) {
            return Err(bad(
                &key,
                format!("must have {lens:?} values, got {}", values.len()),
            ));
        }
        Ok(values)
    };
    let k = matrix(&["cameraMatrix", "camera_matrix"], &[9])?;
    let d = matrix(
        &["distortionCoefficients", "distortion_coefficients"],
        &[4, 5, 8],
    )?;
    let dim = |key: &str| -> Result<Option<u32>, CalibError> {
        match node(&[key])? {
            None => Ok(None),
            Some((_, n)) => {
                let v = n.to_i32().map_err(|e| bad(key, e.message))?;
                u32::try_from(v)
                    .map(Some)
                    .map_err(|_| bad(key, format!("must be a pixel count, got {v}")))
            }
        }
    };
    let [width, height] = match (dim("image_width")?, dim("image_height")?, default_size) {
        (Some(w), Some(h), _) => [w, h],
        (_, _, Some(size)) => size,
        _ => {
            return Err(CalibError::MissingKey {
                key: "image_width and image_height".into(),
                path: path.to_path_buf(),
            });
        }
    };
    let intrinsics = Intrinsics::from_camera_matrix(width, height, &k, &d)
        .ok_or_else(|| bad("distortionCoefficients", format!("{} values", d.len())))?;
    intrinsics.validate().map_err(|e| match e {
        CalibError::Invalid { field, reason } => bad(&field, reason),
        other => other,
    })?;
    Ok(intrinsics)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(ex: [f64; 2], ey: [f64; 2]) -> Vec<[f64; 2]> {
        let mut out = Vec::new();
        for j in 0..6 {
            for i in 0..9 {
                let (i, j) = (f64::from(i), f64::from(j));
                out.push([100.0 + i * ex[0] + j * ey[0], 80.0 + i * ex[1] + j * ey[1]]);
            }
        }
        out
    }

    #[test]
    fn subpix_window_stays_off_the_other_edges() {
        // Squares of 11 px: the far edges are 11 px away, 2 px margin → half side 8.
        assert_eq!(subpix_window(&grid([11.0, 0.0], [0.0, 11.0]), 9), (8, 8));
        // Foreshortened 20 × 7 px: wide in x (capped at 11), narrow in y.
        assert_eq!(subpix_window(&grid([20.0, 0.0], [0.0, 7.0]), 9), (11, 4));
        // Tiny squares: never below the minimum.
        assert_eq!(subpix_window(&grid([3.0, 0.0], [0.0, 3.0]), 9), (2, 2));
        // Sheared squares: the window shrinks to keep off the slanted edges.
        let (hx, hy) = subpix_window(&grid([20.0, 0.0], [14.0, 7.0]), 9);
        assert!(hx < 11 && hy <= 4, "{hx} {hy}");
    }
}
