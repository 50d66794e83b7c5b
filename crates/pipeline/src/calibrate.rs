//! `bodyseg calibrate`: chessboard images → intrinsics, colour-from-depth, world poses →
//! `rig.toml`, with OpenCV (feature `opencv`; without it every command returns an error
//! saying how to build it).
//!
//! ```text
//! calibrate_intrinsics: folder of one sensor's board views → intrinsics (.toml, .yaml/.yml/.xml)
//! calibrate_stereo:     IR and colour views of the same instants (+ intrinsics) → one-camera rig.toml
//! calibrate_world:      rig(s) + every camera's view of a board on the floor → rig.toml, world = board
//! ```
//!
//! A view where the board is not found is reported and skipped; a run fails (writing
//! nothing) when no view shows the board, when images of one sensor differ in size, or
//! when an image's size is not its sensor's.

use crate::stage::Stage;
use anyhow::Result;
use bodyseg_calib::Board;
use std::path::{Path, PathBuf};

/// What [`calibrate_intrinsics`] reads and writes.
#[derive(Clone, Debug)]
pub struct IntrinsicsCalibOptions {
    /// Folder of board views of one sensor (PNG or JPEG, all the same size).
    pub images: PathBuf,
    /// The board.
    pub board: Board,
    /// Output: `.toml` (the fields of a rig.toml sensor table) or OpenCV FileStorage
    /// `.yaml`, `.yml`, `.xml`. Written atomically.
    pub out: PathBuf,
}

/// How one board view went.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewReport {
    /// The image file (for a stereo pair, the first sensor's).
    pub file: PathBuf,
    /// RMS reprojection error of the view's corners, pixels; `None` when the board was
    /// not found (the view was skipped).
    pub rms_px: Option<f64>,
}

/// What a calibration command did.
#[derive(Clone, Debug)]
pub struct CalibrateSummary {
    /// Per view (or per camera for `world`), its reprojection error or its rejection.
    pub views: Vec<ViewReport>,
    /// Overall RMS reprojection error, pixels.
    pub rms_px: f64,
    /// Things the user should know (skipped views, unpaired images), one line each.
    pub notes: Vec<String>,
    /// Per stage: time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// What [`calibrate_stereo`] reads and writes.
#[derive(Clone, Debug)]
pub struct StereoCalibOptions {
    /// Folder of the IR (depth sensor) views.
    pub ir: PathBuf,
    /// Folder of the colour views; a view pairs with the IR view of the same file stem.
    pub color: PathBuf,
    /// The board.
    pub board: Board,
    /// IR intrinsics file (`.toml`, `.yaml`, `.yml`, `.xml`); `None`: calibrated from the
    /// IR views first.
    pub ir_intrinsics: Option<PathBuf>,
    /// Colour intrinsics file; `None`: calibrated from the colour views first.
    pub color_intrinsics: Option<PathBuf>,
    /// Keep both intrinsics as given (or as calibrated per sensor) instead of refining
    /// them together with colour-from-depth.
    pub fix_intrinsics: bool,
    /// Camera name in the written rig; `None`: the name of the folder holding `ir`.
    pub name: Option<String>,
    /// The one-camera `rig.toml` to write (world pose: identity). Written atomically.
    pub out: PathBuf,
}

/// What [`calibrate_world`] reads and writes.
#[derive(Clone, Debug)]
pub struct WorldCalibOptions {
    /// Rig files whose cameras (in file order, then rig order) are placed; their
    /// intrinsics and colour-from-depth are kept.
    pub rigs: Vec<PathBuf>,
    /// Folder of the floor views: `<floor>/<camera>/ir.png` and/or `color.png` (or
    /// `.jpg`), taken while the board lay still on the floor.
    pub floor: PathBuf,
    /// The floor board; its frame becomes the world frame (z up).
    pub board: Board,
    /// The `rig.toml` to write. Written atomically.
    pub out: PathBuf,
}

/// What `--out` of `calibrate intrinsics` may end in.
const INTRINSICS_EXTENSIONS: &str = ".toml, .yaml, .yml or .xml";

/// The lower-case extension of `path`.
fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Checks that an intrinsics file name has a known extension.
fn check_intrinsics_name(path: &Path, what: &str) -> Result<()> {
    if !matches!(extension(path).as_str(), "toml" | "yaml" | "yml" | "xml") {
        anyhow::bail!(
            "{}: {what} must end in {INTRINSICS_EXTENSIONS}",
            path.display()
        );
    }
    Ok(())
}

/// Calibrates one sensor's intrinsics from a folder of board views (OpenCV's
/// `calibrateCamera` on sub-pixel chessboard corners) and writes them to `options.out`.
pub fn calibrate_intrinsics(options: &IntrinsicsCalibOptions) -> Result<CalibrateSummary> {
    check_intrinsics_name(&options.out, "--out")?;
    #[cfg(feature = "opencv")]
    {
        imp::intrinsics(options)
    }
    #[cfg(not(feature = "opencv"))]
    {
        Err(without_opencv())
    }
}

/// Calibrates one Kinect's colour-from-depth from IR and colour views of the same board
/// poses (OpenCV's `stereoCalibrate`, intrinsics fixed) and writes a one-camera rig.
pub fn calibrate_stereo(options: &StereoCalibOptions) -> Result<CalibrateSummary> {
    for path in [&options.ir_intrinsics, &options.color_intrinsics]
        .into_iter()
        .flatten()
    {
        check_intrinsics_name(path, "an intrinsics file")?;
    }
    require_asymmetric(&options.board)?;
    #[cfg(feature = "opencv")]
    {
        imp::stereo(options)
    }
    #[cfg(not(feature = "opencv"))]
    {
        Err(without_opencv())
    }
}

/// Places every camera of the given rigs in the world frame of a board lying on the floor
/// (OpenCV's `solvePnP` per sensor; IR and colour views refined together) and writes the
/// rig.
pub fn calibrate_world(options: &WorldCalibOptions) -> Result<CalibrateSummary> {
    if options.rigs.is_empty() {
        anyhow::bail!("no rig given: name one or more rig files (--rig)");
    }
    require_asymmetric(&options.board)?;
    #[cfg(feature = "opencv")]
    {
        imp::world(options)
    }
    #[cfg(not(feature = "opencv"))]
    {
        Err(without_opencv())
    }
}

/// Stereo and world poses need a board whose corner (0, 0) one image can tell.
fn require_asymmetric(board: &Board) -> Result<()> {
    if !board.is_asymmetric() {
        anyhow::bail!(
            "board {} looks the same turned by 180 degrees, so its corners cannot be matched \
             between views: use a board with one even and one odd count of inner corners \
             (e.g. 9x6)",
            board.size_text()
        );
    }
    Ok(())
}

#[cfg(not(feature = "opencv"))]
fn without_opencv() -> anyhow::Error {
    anyhow::anyhow!(
        "this bodyseg was built without OpenCV: `bodyseg calibrate` needs \
         `cargo build --release --features opencv` (with libopencv-dev, clang and \
         libclang-dev installed: scripts/setup_opencv.sh)"
    )
}

#[cfg(feature = "opencv")]
mod imp {
    use super::*;
    use crate::outputs::write_text;
    use crate::stage::plural;
    use anyhow::{Context, bail};
    use bodyseg_calib::{
        BoardZ, GrayImage, Intrinsics, MIN_INTRINSICS_VIEWS, Pose, RgbdCamera, Rig, SensorCorners,
        board_pose, calibrate_intrinsics as fit_intrinsics, calibrate_stereo as fit_stereo,
        find_board_corners, read_intrinsics_toml, read_opencv_intrinsics, read_rig_toml,
        refine_board_pose, rig_to_toml_string, write_intrinsics_toml, write_opencv_intrinsics,
    };
    use rayon::prelude::*;
    use std::time::Instant;

    /// One image with the board's corners in it, if found.
    struct View {
        file: PathBuf,
        width: u32,
        height: u32,
        corners: Option<Vec<[f64; 2]>>,
    }

    fn read_gray(path: &Path) -> Result<GrayImage> {
        let rgb = bodyseg_io::read_rgb_image(path)?;
        Ok(GrayImage::from_rgb(rgb.width, rgb.height, &rgb.rgb))
    }

    /// Reads and searches every image (in parallel); the views keep the files' order.
    fn detect(files: &[PathBuf], board: &Board, z: BoardZ) -> Result<Vec<View>> {
        files
            .par_iter()
            .map(|file| {
                let image = read_gray(file)?;
                let corners = find_board_corners(&image, board, z)
                    .with_context(|| file.display().to_string())?;
                Ok(View {
                    file: file.clone(),
                    width: image.width,
                    height: image.height,
                    corners,
                })
            })
            .collect()
    }

    /// The size shared by all views; an error naming the first image of another size.
    fn common_size(views: &[View]) -> Result<[u32; 2]> {
        let first = views.first().context("no images")?;
        if let Some(odd) = views
            .iter()
            .find(|v| [v.width, v.height] != [first.width, first.height])
        {
            bail!(
                "{}: image is {}x{}, but {} is {}x{}: the views of one sensor must all have \
                 the same size",
                odd.file.display(),
                odd.width,
                odd.height,
                first.file.display(),
                first.width,
                first.height
            );
        }
        Ok([first.width, first.height])
    }

    fn no_board_error(dir: &Path, board: &Board, checked: usize) -> anyhow::Error {
        anyhow::anyhow!(
            "{}: no image shows a {} chessboard ({} checked): check --board, the inner \
             corners per row and per column (a board of 10x7 squares is 9x6)",
            dir.display(),
            board.size_text(),
            plural(checked, "image", "images")
        )
    }

    /// Reads an intrinsics file (`.toml` or OpenCV FileStorage) whose sensor must have
    /// `size`; FileStorage files without a size take it.
    fn read_intrinsics_file(path: &Path, size: [u32; 2]) -> Result<Intrinsics> {
        let intrinsics = if extension(path) == "toml" {
            read_intrinsics_toml(path)?
        } else {
            read_opencv_intrinsics(path, Some(size))?
        };
        if [intrinsics.width, intrinsics.height] != size {
            bail!(
                "{}: intrinsics are for {}x{} images, the views are {}x{}",
                path.display(),
                intrinsics.width,
                intrinsics.height,
                size[0],
                size[1]
            );
        }
        Ok(intrinsics)
    }

    /// Detects the board in a folder's images and fits the intrinsics to the views that
    /// show it; reports per view.
    struct SensorFit {
        intrinsics: Intrinsics,
        rms_px: f64,
        reports: Vec<ViewReport>,
        notes: Vec<String>,
    }

    fn fit_sensor(dir: &Path, views: &[View], board: &Board) -> Result<SensorFit> {
        let [width, height] = common_size(views)?;
        let found: Vec<&View> = views.iter().filter(|v| v.corners.is_some()).collect();
        if found.is_empty() {
            return Err(no_board_error(dir, board, views.len()));
        }
        if found.len() < MIN_INTRINSICS_VIEWS {
            bail!(
                "{}: only {} of {} show the {} board: calibration needs at least \
                 {MIN_INTRINSICS_VIEWS} (15 or more advised)",
                dir.display(),
                found.len(),
                plural(views.len(), "image", "images"),
                board.size_text()
            );
        }
        let corners: Vec<Vec<[f64; 2]>> = found.iter().filter_map(|v| v.corners.clone()).collect();
        let fit = fit_intrinsics(board, &corners, width, height)
            .with_context(|| dir.display().to_string())?;
        let mut errors = fit.view_rms_px.iter();
        let mut notes = Vec::new();
        let reports = views
            .iter()
            .map(|v| ViewReport {
                file: v.file.clone(),
                rms_px: match v.corners {
                    Some(_) => errors.next().copied(),
                    None => {
                        notes.push(format!(
                            "{}: no {} board found, view skipped",
                            v.file.display(),
                            board.size_text()
                        ));
                        None
                    }
                },
            })
            .collect();
        Ok(SensorFit {
            intrinsics: fit.intrinsics,
            rms_px: fit.rms_px,
            reports,
            notes,
        })
    }

    fn describe(i: &Intrinsics) -> String {
        format!(
            "{}x{} fx {:.2} fy {:.2} cx {:.2} cy {:.2}",
            i.width, i.height, i.fx, i.fy, i.cx, i.cy
        )
    }

    pub(super) fn intrinsics(options: &IntrinsicsCalibOptions) -> Result<CalibrateSummary> {
        let start = Instant::now();
        let files = bodyseg_io::image_files(&options.images, "board images")?;
        if files.is_empty() {
            bail!("{}: no PNG or JPEG images", options.images.display());
        }
        let views = detect(&files, &options.board, BoardZ::AwayFromCamera)?;
        let detected = views.iter().filter(|v| v.corners.is_some()).count();
        let mut stages = vec![Stage::new(
            "detect",
            start.elapsed(),
            format!(
                "{} board in {detected} of {}",
                options.board.size_text(),
                plural(views.len(), "image", "images")
            ),
        )];
        let t = Instant::now();
        let fit = fit_sensor(&options.images, &views, &options.board)?;
        stages.push(Stage::new(
            "fit",
            t.elapsed(),
            format!(
                "{}, RMS reprojection error {:.3} px",
                describe(&fit.intrinsics),
                fit.rms_px
            ),
        ));
        let t = Instant::now();
        if extension(&options.out) == "toml" {
            let mut comment = format!(
                "bodyseg calibrate intrinsics: {} board of {} m squares, {detected} of {} \
                 images used\nRMS reprojection error {:.4} px; per image:\n",
                options.board.size_text(),
                options.board.square_m,
                views.len(),
                fit.rms_px
            );
            for r in &fit.reports {
                let name = r.file.file_name().unwrap_or_default().to_string_lossy();
                match r.rms_px {
                    Some(e) => comment.push_str(&format!("  {name}: {e:.4} px\n")),
                    None => comment.push_str(&format!("  {name}: board not found, skipped\n")),
                }
            }
            write_intrinsics_toml(&fit.intrinsics, &comment, &options.out)?;
        } else {
            write_opencv_intrinsics(&options.out, &fit.intrinsics, Some(fit.rms_px))?;
        }
        stages.push(Stage::new(
            "write",
            t.elapsed(),
            options.out.display().to_string(),
        ));
        Ok(CalibrateSummary {
            views: fit.reports,
            rms_px: fit.rms_px,
            notes: fit.notes,
            stages,
        })
    }

    /// The stem of a file name (`000003` of `000003.png`).
    fn stem(path: &Path) -> String {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    pub(super) fn stereo(options: &StereoCalibOptions) -> Result<CalibrateSummary> {
        let start = Instant::now();
        let board = &options.board;
        let ir_files = bodyseg_io::image_files(&options.ir, "IR board images")?;
        let color_files = bodyseg_io::image_files(&options.color, "colour board images")?;
        for (dir, files) in [(&options.ir, &ir_files), (&options.color, &color_files)] {
            if files.is_empty() {
                bail!("{}: no PNG or JPEG images", dir.display());
            }
        }
        let name = match &options.name {
            Some(n) => n.clone(),
            None => camera_name_of(&options.ir)?,
        };
        let ir_views = detect(&ir_files, board, BoardZ::AwayFromCamera)?;
        let color_views = detect(&color_files, board, BoardZ::AwayFromCamera)?;
        let ir_size = common_size(&ir_views)?;
        let color_size = common_size(&color_views)?;
        let mut stages = vec![Stage::new(
            "detect",
            start.elapsed(),
            format!(
                "{} board in {} of {} IR and {} of {} colour images",
                board.size_text(),
                ir_views.iter().filter(|v| v.corners.is_some()).count(),
                ir_views.len(),
                color_views.iter().filter(|v| v.corners.is_some()).count(),
                color_views.len()
            ),
        )];
        let mut notes = Vec::new();
        let t = Instant::now();
        let mut sensor = |dir: &Path,
                          views: &[View],
                          file: &Option<PathBuf>,
                          size: [u32; 2],
                          what: &str|
         -> Result<Intrinsics> {
            match file {
                Some(path) => read_intrinsics_file(path, size),
                None => {
                    let fit = fit_sensor(dir, views, board)?;
                    notes.push(format!(
                        "{what} intrinsics calibrated from {}: {}, RMS {:.3} px",
                        dir.display(),
                        describe(&fit.intrinsics),
                        fit.rms_px
                    ));
                    Ok(fit.intrinsics)
                }
            }
        };
        let depth = sensor(
            &options.ir,
            &ir_views,
            &options.ir_intrinsics,
            ir_size,
            "IR",
        )?;
        let color = sensor(
            &options.color,
            &color_views,
            &options.color_intrinsics,
            color_size,
            "colour",
        )?;
        // Pairs: the same stem in both folders, the board found in both.
        let mut pairs = Vec::new();
        let mut paired_files = Vec::new();
        let mut reports = Vec::new();
        let mut unpaired = 0usize;
        for ir in &ir_views {
            let Some(color) = color_views.iter().find(|c| stem(&c.file) == stem(&ir.file)) else {
                unpaired += 1;
                continue;
            };
            match (&ir.corners, &color.corners) {
                (Some(a), Some(b)) => {
                    pairs.push((a.clone(), b.clone()));
                    paired_files.push(ir.file.clone());
                }
                _ => {
                    notes.push(format!(
                        "{} / {}: the {} board is not found in both, pair skipped",
                        ir.file.display(),
                        color.file.display(),
                        board.size_text()
                    ));
                    reports.push(ViewReport {
                        file: ir.file.clone(),
                        rms_px: None,
                    });
                }
            }
        }
        unpaired += color_views
            .iter()
            .filter(|c| !ir_views.iter().any(|ir| stem(&ir.file) == stem(&c.file)))
            .count();
        if unpaired > 0 {
            notes.push(format!(
                "{} without a partner of the same name in the other folder, ignored",
                plural(unpaired, "image", "images")
            ));
        }
        if pairs.is_empty() {
            bail!(
                "{} and {}: no pair of IR and colour images of the same name both show the \
                 {} board",
                options.ir.display(),
                options.color.display(),
                board.size_text()
            );
        }
        let fit = fit_stereo(board, &depth, &color, &pairs, !options.fix_intrinsics)
            .context("stereo calibration")?;
        let (depth, color) = (fit.first, fit.second);
        if !options.fix_intrinsics {
            notes.push(format!(
                "intrinsics refined with colour-from-depth: IR {}, colour {}",
                describe(&depth),
                describe(&color)
            ));
        }
        // Per pair: RMS of both sensors' corners with the IR view's board pose and the
        // fitted colour-from-depth.
        for (file, (ir_corners, color_corners)) in paired_files.iter().zip(&pairs) {
            let (depth_from_board, _) = board_pose(board, &depth, ir_corners)?;
            let color_from_board = fit.second_from_first.compose(&depth_from_board);
            let a =
                bodyseg_calib::reprojection_rms_px(board, &depth, &depth_from_board, ir_corners);
            let b =
                bodyseg_calib::reprojection_rms_px(board, &color, &color_from_board, color_corners);
            reports.push(ViewReport {
                file: file.clone(),
                rms_px: Some(((a * a + b * b) / 2.0).sqrt()),
            });
        }
        reports.sort_by(|a, b| a.file.cmp(&b.file));
        let cfd = fit.second_from_first;
        let t_m = cfd.translation_m();
        stages.push(Stage::new(
            "fit",
            t.elapsed(),
            format!(
                "colour-from-depth from {}: baseline {:.1} mm, RMS reprojection error {:.3} px",
                plural(pairs.len(), "pair", "pairs"),
                1e3 * (t_m[0] * t_m[0] + t_m[1] * t_m[1] + t_m[2] * t_m[2]).sqrt(),
                fit.rms_px
            ),
        ));
        let mut camera = RgbdCamera::new(name, depth, color);
        camera.color_from_depth = cfd;
        let rig = Rig {
            cameras: vec![camera],
        };
        stages.push(write_rig(&rig, &options.out)?);
        Ok(CalibrateSummary {
            views: reports,
            rms_px: fit.rms_px,
            notes,
            stages,
        })
    }

    /// Writes `rig` to `out` atomically; the stage line.
    fn write_rig(rig: &Rig, out: &Path) -> Result<Stage> {
        let t = Instant::now();
        write_text(out, &rig_to_toml_string(rig)?)?;
        Ok(Stage::new("write", t.elapsed(), out.display().to_string()))
    }

    /// The default camera name: the folder holding the IR folder (`calib/cam0/ir` → `cam0`).
    fn camera_name_of(ir: &Path) -> Result<String> {
        let absolute = ir
            .canonicalize()
            .with_context(|| format!("{}: cannot resolve the folder", ir.display()))?;
        absolute
            .parent()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .filter(|n| !n.is_empty())
            .with_context(|| {
                format!(
                    "{}: no parent folder to name the camera after; give --name",
                    ir.display()
                )
            })
    }

    /// The first existing `<dir>/<base>.png|.jpg|.jpeg`.
    fn floor_file(dir: &Path, base: &str) -> Option<PathBuf> {
        bodyseg_io::first_existing_file(
            &["png", "jpg", "jpeg"].map(|e| dir.join(format!("{base}.{e}"))),
        )
    }

    pub(super) fn world(options: &WorldCalibOptions) -> Result<CalibrateSummary> {
        let start = Instant::now();
        let board = &options.board;
        let mut rig = Rig::default();
        for path in &options.rigs {
            rig.cameras.extend(read_rig_toml(path)?.cameras);
        }
        rig.validate()
            .context("the cameras of the --rig files together")?;
        bodyseg_io::require_folder(&options.floor, "floor views")?;
        let mut reports = Vec::new();
        let mut notes = Vec::new();
        let (mut sum_sq, mut count) = (0.0, 0usize);
        for camera in &mut rig.cameras {
            let dir = options.floor.join(&camera.name);
            let ir = floor_file(&dir, "ir");
            let color = floor_file(&dir, "color");
            if ir.is_none() && color.is_none() {
                bail!(
                    "camera {}: no floor view: expected {} or {} (or .jpg)",
                    camera.name,
                    dir.join("ir.png").display(),
                    dir.join("color.png").display()
                );
            }
            // Per sensor: the sensor's intrinsics, its pose relative to the depth sensor,
            // and the corners found.
            let mut observations: Vec<(Intrinsics, Pose, Vec<[f64; 2]>, PathBuf)> = Vec::new();
            for (file, intrinsics, sensor_from_depth) in [
                (&ir, camera.depth, Pose::identity()),
                (&color, camera.color, camera.color_from_depth),
            ] {
                let Some(file) = file else { continue };
                let image = read_gray(file)?;
                if [image.width, image.height] != [intrinsics.width, intrinsics.height] {
                    bail!(
                        "{}: image is {}x{}, camera {}'s sensor is {}x{}",
                        file.display(),
                        image.width,
                        image.height,
                        camera.name,
                        intrinsics.width,
                        intrinsics.height
                    );
                }
                match find_board_corners(&image, board, BoardZ::TowardCamera)
                    .with_context(|| file.display().to_string())?
                {
                    Some(corners) => {
                        observations.push((intrinsics, sensor_from_depth, corners, file.clone()))
                    }
                    None => notes.push(format!(
                        "{}: no {} board found, view skipped",
                        file.display(),
                        board.size_text()
                    )),
                }
            }
            if observations.is_empty() {
                bail!(
                    "camera {}: the {} floor board is not found in {}",
                    camera.name,
                    board.size_text(),
                    [&ir, &color]
                        .into_iter()
                        .flatten()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(" nor ")
                );
            }
            let depth_from_world = world_pose(board, &observations)?;
            camera.world_from_depth = depth_from_world.inverse();
            for (intrinsics, sensor_from_depth, corners, file) in &observations {
                let e = bodyseg_calib::reprojection_rms_px(
                    board,
                    intrinsics,
                    &sensor_from_depth.compose(&depth_from_world),
                    corners,
                );
                sum_sq += e * e * corners.len() as f64;
                count += corners.len();
                reports.push(ViewReport {
                    file: file.clone(),
                    rms_px: Some(e),
                });
            }
        }
        let rms_px = (sum_sq / count.max(1) as f64).sqrt();
        let mut stages = vec![Stage::new(
            "fit",
            start.elapsed(),
            format!(
                "{} placed on the {} floor board, RMS reprojection error {rms_px:.3} px",
                plural(rig.cameras.len(), "camera", "cameras"),
                board.size_text()
            ),
        )];
        stages.push(write_rig(&rig, &options.out)?);
        Ok(CalibrateSummary {
            views: reports,
            rms_px,
            notes,
            stages,
        })
    }

    /// `depth_from_world` of one camera from its sensors' views of the floor board.
    fn world_pose(
        board: &Board,
        observations: &[(Intrinsics, Pose, Vec<[f64; 2]>, PathBuf)],
    ) -> Result<Pose> {
        // solvePnP on each sensor alone; the first (IR when it sees the board) starts the
        // joint fit of every sensor's corners.
        let mut estimates = Vec::new();
        for (intrinsics, sensor_from_depth, corners, file) in observations {
            let (sensor_from_world, _) = board_pose(board, intrinsics, corners)
                .with_context(|| file.display().to_string())?;
            estimates.push(sensor_from_depth.inverse().compose(&sensor_from_world));
        }
        tracing::debug!(?estimates, "depth_from_world per sensor");
        let views: Vec<SensorCorners<'_>> = observations
            .iter()
            .map(
                |(intrinsics, sensor_from_depth, corners, _)| SensorCorners {
                    intrinsics,
                    sensor_from_reference: *sensor_from_depth,
                    corners_px: corners,
                },
            )
            .collect();
        Ok(refine_board_pose(board, &views, &estimates[0])?)
    }
}
