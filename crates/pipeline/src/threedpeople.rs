//! The 3DPeople dataset (Pumarola et al., "3DPeople: Modeling the Geometry of Dressed
//! Humans", ICCV 2019) read as labelled point clouds, one per view (subject, sequence,
//! camera, frame), for `bodyseg convert --format 3dpeople`.
//!
//! # Layout
//! As the dataset's own visualisation notebook (`vis_dataset.ipynb` in
//! github.com/albertpumarola/3DPeople-Dataset) reads it:
//! ```text
//! ROOT/rgb/<subject>/<sequence>/<camera>/<outfit>/<frame>.jpg    e.g. woman17/02_04_jump/camera01/
//!                                                                 wpskin08_..._background1928/0001.jpg
//! ROOT/depth_mat/<subject>/<sequence>/<camera>/depth.mat         one file per camera, one variable per frame
//! ROOT/segmentation_body/<subject>/<sequence>/<camera>/<frame>.png
//! ```
//! The real data puts the colour images one folder deeper, in a folder named after the
//! outfit and background; images directly in the camera folder are accepted too.
//! A view exists when its colour image does ([`list_3dpeople_views`]); a missing depth or
//! segmentation file is the reader's error, so a batch reports that view as bad.
//!
//! # Assumptions (not documented by the dataset; each configurable or cheap to change)
//! - **Depth variable.** `depth.mat` holds one 2-D matrix per frame; the notebook takes
//!   the variables whose names start with `depth`, in name order. Frame `0007` reads the
//!   variable `depth` + optional `_` + digits whose number is 7 (`depth_0007`,
//!   `depth_7`, `depth7`); a frame whose stem is not a number reads `depth_<stem>`.
//! - **Depth units and validity.** Values times [`ThreeDPeopleCamera::depth_scale_m`]
//!   (default 1: metres) are depths along the optical axis (or along the ray, with
//!   [`ThreeDPeopleCamera::depth_is_ray_distance`]). A value ≤ 0, +∞, or ≥
//!   [`ThreeDPeopleCamera::max_depth_m`] (default 100 m; Blender writes 1e10 for empty
//!   pixels) is no measurement; NaN and −∞ are errors.
//!   Unverified: the notebook's skeleton plot has a standing person's joints at
//!   z ≈ 10–17, which reads as decimetres; if `depth.mat` shares that unit, set
//!   `depth_scale_m = 0.1`.
//! - **Palette** ([`THREEDPEOPLE_PALETTE`]): background (153, 153, 153) and 14 parts,
//!   as used by public code that trains on 3DPeople's `segmentation_body` (no official
//!   table was found). Hands go to lower arms, feet to lower legs. Part edges hold
//!   anti-aliased in-between colours: a colour within
//!   [`ThreeDPeopleCamera::palette_tolerance`] (per channel) of a palette colour takes
//!   its class, any other colour is [`Label::UNKNOWN`] (ignored as ground truth by eval),
//!   neither an error nor background.
//! - **Intrinsics**: fx = fy = 700, cx = 320, cy = 240 at 640×480, no distortion (what the
//!   dataset's users calibrate with, e.g. posepile's 3DPeople importer); depth,
//!   segmentation and colour images are aligned and the same size.
//!
//! # Conventions
//! - Pixel (u, v) = (column, row), integer values at pixel centres; the camera frame is
//!   OpenCV's (x right, y down, z forward): `p_camera = z · ((u − cx)/fx, (v − cy)/fy, 1)`.
//! - The cloud is in a z-up world frame with the camera at the origin looking along +y:
//!   `p_world = (x_camera, z_camera, −y_camera)` (x right, y forward, z up; a rotation).
//! - Origins are (camera 0, row-major pixel index `v · width + u`); points are in
//!   row-major pixel order; `colors` holds the colour image's pixel.

use anyhow::{Context, Result, anyhow, bail, ensure};
use bodyseg_calib::Intrinsics;
use bodyseg_core::{Class, Label, LabeledCloud, PointOrigin, RgbImage};
use bodyseg_io::{list_folder, read_mat_matrix, read_mat_variable_names, read_rgb_image};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// 3DPeople's `segmentation_body` palette: part name, RGB colour, bodyseg class.
pub(crate) const THREEDPEOPLE_PALETTE: [(&str, [u8; 3], Class); 15] = [
    ("bg", [153, 153, 153], Class::Background),
    ("Head", [128, 64, 0], Class::Head),
    ("RUpArm", [128, 0, 128], Class::UpperArms),
    ("RForeArm", [128, 128, 255], Class::LowerArms),
    ("RHand", [255, 128, 128], Class::LowerArms),
    ("LUpArm", [0, 0, 255], Class::UpperArms),
    ("LForeArm", [128, 128, 0], Class::LowerArms),
    ("LHand", [0, 128, 0], Class::LowerArms),
    ("torso", [128, 0, 0], Class::Torso),
    ("RThigh", [128, 255, 128], Class::UpperLegs),
    ("RLowLeg", [255, 255, 128], Class::LowerLegs),
    ("RFoot", [255, 0, 255], Class::LowerLegs),
    ("LThigh", [0, 128, 128], Class::UpperLegs),
    ("LLowLeg", [0, 0, 128], Class::LowerLegs),
    ("LFoot", [255, 128, 0], Class::LowerLegs),
];

/// Largest usable [`ThreeDPeopleCamera::palette_tolerance`]: two palette colours differ
/// by at least 64 in some channel, so a tolerance below 32 never matches two of them.
pub(crate) const MAX_PALETTE_TOLERANCE: u8 = 31;

/// One view (subject, sequence, camera, frame) of a 3DPeople dataset.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct ThreeDPeopleView {
    /// Subject folder (`woman17`).
    pub subject: String,
    /// Sequence folder (`02_04_jump`).
    pub sequence: String,
    /// Camera folder (`camera01`).
    pub camera: String,
    /// Frame: the colour image's file stem (`0001`).
    pub frame: String,
    /// The colour image (exists when listed).
    pub rgb_path: PathBuf,
    /// `depth_mat/<subject>/<sequence>/<camera>/depth.mat` (may be missing).
    pub depth_path: PathBuf,
    /// `segmentation_body/<subject>/<sequence>/<camera>/<frame>.png` (may be missing).
    pub segmentation_path: PathBuf,
}

impl ThreeDPeopleView {
    /// Unique output stem, a relative path with `/` separators:
    /// `<subject>/<sequence>/<camera>/<frame>` (`woman17/02_04_jump/camera01/0001`). Its
    /// parts are folder and file names of the data set, so it is filesystem-safe; the
    /// caller creates the parent folders. Stems sort in [`list_3dpeople_views`]' order.
    pub fn stem(&self) -> String {
        format!(
            "{}/{}/{}/{}",
            self.subject, self.sequence, self.camera, self.frame
        )
    }
}

/// How to read a 3DPeople view: intrinsics of the aligned depth, segmentation and colour
/// images, depth units and validity, palette matching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThreeDPeopleCamera {
    /// Intrinsics of the aligned images (distortion, if set, is undistorted). Default:
    /// 640×480, fx = fy = 700, cx = 320, cy = 240, no distortion.
    pub intrinsics: Intrinsics,
    /// Metres per `depth.mat` unit. Default 1 (metres).
    pub depth_scale_m: f64,
    /// Depths at or beyond this, metres, are no measurement (Blender writes 1e10 where
    /// nothing was hit). Default 100.
    pub max_depth_m: f64,
    /// True when a depth is the distance along the pixel's ray rather than along the
    /// optical axis (z). Default false.
    pub depth_is_ray_distance: bool,
    /// Per-channel difference up to which a segmentation colour takes a palette colour's
    /// class (anti-aliased part edges); other colours are unknown. At most
    /// 31 (two palette colours differ by at least 64 in some channel, so a tolerance below
    /// 32 never matches two of them). Default 16.
    pub palette_tolerance: u8,
}

impl Default for ThreeDPeopleCamera {
    fn default() -> Self {
        ThreeDPeopleCamera::pinhole(640, 480, 700.0, 700.0, 320.0, 240.0)
    }
}

impl ThreeDPeopleCamera {
    /// Distortion-free intrinsics (image size in pixels; focal lengths and principal
    /// point in pixels, pixel centres at integers), the other settings at their defaults.
    pub fn pinhole(width: u32, height: u32, fx: f64, fy: f64, cx: f64, cy: f64) -> Self {
        ThreeDPeopleCamera {
            intrinsics: Intrinsics::pinhole(width, height, fx, fy, cx, cy),
            depth_scale_m: 1.0,
            max_depth_m: 100.0,
            depth_is_ray_distance: false,
            palette_tolerance: 16,
        }
    }

    /// Checks every field; the error names it (`fx must be finite and > 0, got 0`).
    pub fn validate(&self) -> Result<()> {
        self.intrinsics.validate()?;
        ensure!(
            self.depth_scale_m.is_finite() && self.depth_scale_m > 0.0,
            "depth_scale_m must be finite and > 0, got {}",
            self.depth_scale_m
        );
        ensure!(
            self.max_depth_m > 0.0,
            "max_depth_m must be > 0, got {}",
            self.max_depth_m
        );
        ensure!(
            self.palette_tolerance <= MAX_PALETTE_TOLERANCE,
            "palette_tolerance must be at most {MAX_PALETTE_TOLERANCE} (half the smallest difference between two palette colours), got {}",
            self.palette_tolerance
        );
        Ok(())
    }
}

/// Every view under `root` (a 3DPeople folder holding `rgb/`, `depth_mat/`,
/// `segmentation_body/`), sorted by subject, sequence, camera, frame (names in byte
/// order). Colour images are `.jpg`, `.jpeg` or `.png` files in a camera folder or in a
/// folder inside it (the real data's outfit folder); other files are ignored.
///
/// # Errors
/// Naming the folder: `root/rgb` is missing or a folder cannot be listed, or one camera
/// has two colour images of the same frame (two outfit folders).
pub fn list_3dpeople_views(root: &Path) -> Result<Vec<ThreeDPeopleView>> {
    let rgb_root = root.join("rgb");
    let mut views = Vec::new();
    for subject in subfolders(&rgb_root, "3DPeople rgb")? {
        let subject_dir = rgb_root.join(&subject);
        for sequence in subfolders(&subject_dir, "subject")? {
            let sequence_dir = subject_dir.join(&sequence);
            for camera in subfolders(&sequence_dir, "sequence")? {
                let camera_dir = sequence_dir.join(&camera);
                let relative = Path::new(&subject).join(&sequence).join(&camera);
                let depth_path = root.join("depth_mat").join(&relative).join("depth.mat");
                let segmentation_dir = root.join("segmentation_body").join(&relative);
                for (frame, rgb_path) in camera_frames(&camera_dir)? {
                    views.push(ThreeDPeopleView {
                        segmentation_path: segmentation_dir.join(format!("{frame}.png")),
                        subject: subject.clone(),
                        sequence: sequence.clone(),
                        camera: camera.clone(),
                        frame,
                        rgb_path,
                        depth_path: depth_path.clone(),
                    });
                }
            }
        }
    }
    Ok(views)
}

/// The names of the folders in `dir`, sorted.
fn subfolders(dir: &Path, what: &str) -> Result<Vec<String>> {
    Ok(list_folder(dir, what)?
        .into_iter()
        .filter(|e| e.is_folder)
        .map(|e| e.name)
        .collect())
}

/// The frame stem of a colour image file name, `None` for other files.
fn image_stem(name: &str) -> Option<&str> {
    let (stem, ext) = name.rsplit_once('.')?;
    let is_image = ["jpg", "jpeg", "png"]
        .iter()
        .any(|e| ext.eq_ignore_ascii_case(e));
    (is_image && !stem.is_empty()).then_some(stem)
}

/// The colour images of one camera folder, by frame, sorted.
fn camera_frames(camera_dir: &Path) -> Result<BTreeMap<String, PathBuf>> {
    let mut frames: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut add = |dir: &Path, name: &str| -> Result<()> {
        let Some(stem) = image_stem(name) else {
            return Ok(());
        };
        let path = dir.join(name);
        if let Some(first) = frames.insert(stem.to_string(), path.clone()) {
            bail!(
                "{}: two colour images of frame {stem}: {} and {}",
                camera_dir.display(),
                first.display(),
                path.display()
            );
        }
        Ok(())
    };
    for entry in list_folder(camera_dir, "camera")? {
        if entry.is_folder {
            let outfit_dir = camera_dir.join(&entry.name);
            for inner in list_folder(&outfit_dir, "outfit")? {
                if !inner.is_folder {
                    add(&outfit_dir, &inner.name)?;
                }
            }
        } else {
            add(camera_dir, &entry.name)?;
        }
    }
    Ok(frames)
}

/// Reads one view as a labelled point cloud (see the module documentation for the
/// frames, units, palette and what counts as a measurement): every valid depth pixel is
/// a point, in row-major order.
///
/// # Errors
/// One line naming the file: `camera` is invalid; a file is missing or undecodable; the
/// segmentation, colour image or depth matrix is not `camera`'s size; `depth.mat` has no
/// variable for the frame, is MAT v7.3, or holds a NaN or −∞ depth (the pixel is named).
pub fn read_3dpeople_view(
    view: &ThreeDPeopleView,
    camera: &ThreeDPeopleCamera,
) -> Result<LabeledCloud> {
    camera
        .validate()
        .context("3DPeople camera settings are invalid")?;
    let depth = read_depth(view, camera)?;
    let segmentation = read_rgb_image(&view.segmentation_path)?;
    check_size(
        &segmentation,
        &view.segmentation_path,
        "segmentation",
        camera,
    )?;
    let color = read_rgb_image(&view.rgb_path)?;
    check_size(&color, &view.rgb_path, "colour image", camera)?;

    let k = &camera.intrinsics;
    let width = k.width as usize;
    let mut positions_m = Vec::new();
    let mut labels = Vec::new();
    let mut colors = Vec::new();
    let mut origins = Vec::new();
    for (index, &raw) in depth.values.iter().enumerate() {
        let (u, v) = (index % width, index / width);
        if raw.is_nan() || raw == f64::NEG_INFINITY {
            bail!(
                "{}: {} pixel (u {u}, v {v}) is {raw}",
                view.depth_path.display(),
                depth.variable
            );
        }
        let distance_m = raw * camera.depth_scale_m;
        if !(distance_m > 0.0 && distance_m < camera.max_depth_m) {
            continue; // No measurement (0, +∞, the renderer's far value).
        }
        let Some([x_n, y_n, _]) = k.unproject(u as f64, v as f64) else {
            continue; // No ray: undistortion diverged (only with strong distortion).
        };
        let z_m = if camera.depth_is_ray_distance {
            distance_m / (1.0 + x_n * x_n + y_n * y_n).sqrt()
        } else {
            distance_m
        };
        // Camera (x right, y down, z forward) → world (x right, y forward, z up).
        positions_m.push([(x_n * z_m) as f32, z_m as f32, (-y_n * z_m) as f32]);
        labels.push(palette_label(
            pixel(&segmentation, index),
            camera.palette_tolerance,
        ));
        colors.push(pixel(&color, index));
        origins.push(PointOrigin {
            camera: 0,
            pixel: u32::try_from(index).expect("validate() bounds width * height by u32"),
        });
    }
    Ok(LabeledCloud {
        positions_m,
        labels,
        colors: Some(colors),
        origins,
    })
}

/// The depth matrix of one view and the variable it came from.
struct ViewDepth {
    variable: String,
    /// Row-major, `width * height` values.
    values: Vec<f64>,
}

fn read_depth(view: &ThreeDPeopleView, camera: &ThreeDPeopleCamera) -> Result<ViewDepth> {
    let path = &view.depth_path;
    let names = read_mat_variable_names(path)?;
    let variable = depth_variable(&names, &view.frame).ok_or_else(|| {
        let depth_names: Vec<&str> = names
            .iter()
            .map(String::as_str)
            .filter(|n| n.starts_with("depth"))
            .take(4)
            .collect();
        anyhow!(
            "{}: no depth variable for frame {} (expected depth_{}; depth variables: {})",
            path.display(),
            view.frame,
            view.frame,
            if depth_names.is_empty() {
                "none".to_string()
            } else {
                depth_names.join(", ")
            }
        )
    })?;
    let matrix = read_mat_matrix(path, &variable)?;
    let k = &camera.intrinsics;
    if (matrix.cols, matrix.rows) != (k.width as usize, k.height as usize) {
        bail!(
            "{}: {variable} is {}x{}, the camera is {}x{}",
            path.display(),
            matrix.cols,
            matrix.rows,
            k.width,
            k.height
        );
    }
    Ok(ViewDepth {
        variable,
        values: matrix.values,
    })
}

/// The variable of `names` that holds frame `frame`'s depth (module documentation).
fn depth_variable(names: &[String], frame: &str) -> Option<String> {
    let Ok(number) = frame.parse::<u64>() else {
        let want = format!("depth_{frame}");
        return names.iter().find(|n| **n == want).cloned();
    };
    names
        .iter()
        .find(|name| {
            let Some(rest) = name.strip_prefix("depth") else {
                return false;
            };
            let digits = rest.strip_prefix('_').unwrap_or(rest);
            !digits.is_empty()
                && digits.bytes().all(|b| b.is_ascii_digit())
                && digits.parse::<u64>() == Ok(number)
        })
        .cloned()
}

fn check_size(
    image: &RgbImage,
    path: &Path,
    what: &str,
    camera: &ThreeDPeopleCamera,
) -> Result<()> {
    let k = &camera.intrinsics;
    if (image.width, image.height) != (k.width, k.height) {
        bail!(
            "{}: {what} is {}x{}, the camera is {}x{}",
            path.display(),
            image.width,
            image.height,
            k.width,
            k.height
        );
    }
    Ok(())
}

/// The RGB of pixel `index` (row-major) of an image whose size was checked.
fn pixel(image: &RgbImage, index: usize) -> [u8; 3] {
    let i = 3 * index;
    [image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]]
}

/// The label of a segmentation colour: the class of the palette colour within
/// `tolerance` in every channel, else unknown.
fn palette_label(rgb: [u8; 3], tolerance: u8) -> Label {
    THREEDPEOPLE_PALETTE
        .iter()
        .find(|(_, color, _)| {
            color
                .iter()
                .zip(rgb)
                .all(|(&c, p)| c.abs_diff(p) <= tolerance)
        })
        .map_or(Label::UNKNOWN, |&(_, _, class)| Label::from(class))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn palette_colors_are_far_enough_apart_for_the_largest_tolerance() {
        let mut smallest = u8::MAX;
        for (i, (_, a, _)) in THREEDPEOPLE_PALETTE.iter().enumerate() {
            for (_, b, _) in &THREEDPEOPLE_PALETTE[i + 1..] {
                let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max();
                smallest = smallest.min(d.unwrap_or(0));
            }
        }
        assert_eq!(smallest, 64);
        assert!(2 * u16::from(MAX_PALETTE_TOLERANCE) < u16::from(smallest));
    }

    #[test]
    fn palette_maps_hands_and_feet_and_leaves_blends_unknown() {
        assert_eq!(palette_label([255, 128, 128], 0), Class::LowerArms.into());
        assert_eq!(palette_label([255, 128, 0], 0), Class::LowerLegs.into());
        assert_eq!(palette_label([153, 153, 153], 0), Label::BACKGROUND);
        assert_eq!(palette_label([133, 4, 3], 16), Class::Torso.into());
        assert_eq!(palette_label([133, 4, 3], 4), Label::UNKNOWN);
        assert_eq!(palette_label([128, 32, 0], 16), Label::UNKNOWN);
        let sides: Vec<Class> = THREEDPEOPLE_PALETTE.iter().map(|p| p.2).collect();
        for class in Class::ALL {
            let parts = sides.iter().filter(|&&c| c == class).count();
            let want = match class {
                Class::Background | Class::Head | Class::Torso => 1,
                Class::UpperArms | Class::UpperLegs => 2,
                Class::LowerArms | Class::LowerLegs => 4,
            };
            assert_eq!(parts, want, "{class}");
        }
    }

    #[test]
    fn depth_variable_matches_the_frame_number() {
        let names: Vec<String> = ["info", "depth_0001", "depth_0010", "depth7", "depthx"]
            .map(String::from)
            .to_vec();
        assert_eq!(
            depth_variable(&names, "0010").as_deref(),
            Some("depth_0010")
        );
        assert_eq!(depth_variable(&names, "1").as_deref(), Some("depth_0001"));
        assert_eq!(depth_variable(&names, "0007").as_deref(), Some("depth7"));
        assert_eq!(depth_variable(&names, "0002"), None);
        let named = vec!["depth_a".to_string()];
        assert_eq!(depth_variable(&named, "a").as_deref(), Some("depth_a"));
    }

    #[test]
    fn validate_names_the_field() {
        let mut bad = ThreeDPeopleCamera::default();
        bad.intrinsics.fx = 0.0;
        let tolerant = ThreeDPeopleCamera {
            palette_tolerance: MAX_PALETTE_TOLERANCE + 1,
            ..ThreeDPeopleCamera::default()
        };
        for (camera, field) in [(bad, "fx"), (tolerant, "palette_tolerance")] {
            let message = camera.validate().map_err(|e| e.to_string());
            assert!(
                message.as_ref().is_err_and(|m| m.contains(field)),
                "{message:?}"
            );
        }
        assert!(ThreeDPeopleCamera::default().validate().is_ok());
    }
}
