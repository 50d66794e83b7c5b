//! The recording layout (FORMATS.md "Recording"), in one place: a [`Recording`] opened for
//! reading (its rig, its frames, the path of every image, the images read and checked
//! against the rig's sensor sizes) and a [`RecordingWriter`] that creates one.
//!
//! ```text
//! REC/rig.toml
//! REC/<camera>/<layer>/<stem>.png      layer: color (also .jpg, .jpeg), depth, parsing,
//!                                      labels, depth_labels, depth_person (see Layer)
//! REC/boxes/<stem>.json
//! ```
//!
//! Every path is built by [`Layout`], which checks camera names and frame stems
//! (letters, digits, `_`, `-`, `.`; not `.` or `..`): a name from `rig.toml` or the command line never leads out of the
//! recording folder.

use anyhow::{Context, Result, bail};
use bodyseg_calib::{RgbdCamera, Rig};
use bodyseg_core::{LabelImage, PersonBoxes, RgbImage};
use bodyseg_io::DepthImage;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The rig file of a recording, relative to its folder.
const RIG_FILE: &str = "rig.toml";
/// The folder of the per-frame person boxes, relative to the recording's folder.
const BOXES_FOLDER: &str = "boxes";

/// One kind of per-camera image of a recording: a folder `REC/<camera>/<layer>/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Layer {
    /// `color/`: 8-bit RGB, PNG or JPEG, the colour sensor's size.
    Color,
    /// `depth/`: 16-bit PNG, raw depth (millimetres for Kinect data), the depth sensor's
    /// size; 0 = no measurement.
    Depth,
    /// `parsing/`: predicted 2D labels (8-bit class ids, 255 = none), colour sensor.
    Parsing,
    /// `labels/`: ground-truth 2D labels (8-bit class ids), colour sensor.
    Labels,
    /// `depth_labels/`: ground-truth label of every depth pixel, depth sensor.
    DepthLabels,
    /// `depth_person/`: ground-truth person id of every depth pixel (0 = none), depth
    /// sensor.
    DepthPerson,
}

/// Which of a camera's two sensors an image comes from (and so has the size of).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sensor {
    /// The colour sensor.
    Color,
    /// The depth (IR) sensor.
    Depth,
}

impl Layer {
    /// Every layer, in the order of FORMATS.md.
    pub const ALL: [Layer; 6] = [
        Layer::Color,
        Layer::Depth,
        Layer::Parsing,
        Layer::Labels,
        Layer::DepthLabels,
        Layer::DepthPerson,
    ];

    /// The layer's folder name under a camera's folder.
    pub fn folder(self) -> &'static str {
        match self {
            Layer::Color => "color",
            Layer::Depth => "depth",
            Layer::Parsing => "parsing",
            Layer::Labels => "labels",
            Layer::DepthLabels => "depth_labels",
            Layer::DepthPerson => "depth_person",
        }
    }

    /// The sensor whose size the layer's images have.
    pub fn sensor(self) -> Sensor {
        match self {
            Layer::Color | Layer::Parsing | Layer::Labels => Sensor::Color,
            Layer::Depth | Layer::DepthLabels | Layer::DepthPerson => Sensor::Depth,
        }
    }

    /// File extensions of the layer's images, the preferred first.
    fn extensions(self) -> &'static [&'static str] {
        match self {
            Layer::Color => &["png", "jpg", "jpeg"],
            _ => &["png"],
        }
    }

    /// What an image of the layer is, in error messages.
    fn what(self) -> &'static str {
        match self {
            Layer::Color => "colour image",
            Layer::Depth => "depth image",
            Layer::Parsing | Layer::Labels => "label image",
            Layer::DepthLabels => "ground-truth label image",
            Layer::DepthPerson => "person id image",
        }
    }
}

/// Whether `name` may name an entry of a recording's folder: one or more of
/// `A-Z a-z 0-9 _ - .`, and not `.` or `..`.
fn is_valid_name(name: &str) -> bool {
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
    !name.is_empty() && name != "." && name != ".." && name.chars().all(allowed)
}

/// Checks a camera name before it becomes part of a path ([`is_valid_name`]): it names a
/// folder of the recording, so it cannot lead out of it.
///
/// # Errors
/// The name is empty, holds another character (a path separator, a space, ...) or is
/// `.` / `..`; the message names it.
pub(crate) fn check_camera_name(name: &str) -> Result<()> {
    if !is_valid_name(name) {
        bail!(
            "camera {name:?}: a camera name names its folder of the recording: use letters, \
             digits, '_', '-' and '.' only"
        );
    }
    Ok(())
}

/// Checks a frame stem before it becomes part of a path: the file stem of a frame's
/// images, not a path ([`is_valid_name`]).
///
/// # Errors
/// As [`check_camera_name`].
pub(crate) fn check_stem(stem: &str) -> Result<()> {
    if !is_valid_name(stem) {
        bail!(
            "frame {stem:?}: give the file stem of a frame (e.g. 000012), not a path: \
             letters, digits, '_', '-' and '.' only"
        );
    }
    Ok(())
}

/// Checks the name of a folder that becomes part of an output path (a recording of a
/// dataset in `bodyseg convert`: `OUT/<name>/clouds/...`): [`is_valid_name`].
///
/// # Errors
/// As [`check_camera_name`]; the message names `what` and the name.
pub(crate) fn check_folder_name(what: &str, name: &str) -> Result<()> {
    if !is_valid_name(name) {
        bail!(
            "{what} {name:?}: its name becomes a folder of the output: rename it to letters, \
             digits, '_', '-' and '.' only"
        );
    }
    Ok(())
}

/// Checks a `/`-separated path relative to an output folder (a batch's
/// `clouds/<frame>.ply`, `<recording>/boxes/<frame>.json`): every component a valid name
/// ([`is_valid_name`]), so the path stays inside the folder.
///
/// # Errors
/// A component is empty, `.`, `..` or holds another character; the message names the
/// path.
pub(crate) fn check_relative_path(relative: &str) -> Result<()> {
    if !relative.split('/').all(is_valid_name) {
        bail!(
            "output {relative:?}: every part of an output path must be letters, digits, '_', \
             '-' and '.' (not '.' or '..'): a name from an input file would lead out of the \
             output folder"
        );
    }
    Ok(())
}

/// The paths of a recording folder: the one function that joins a camera name, a layer
/// and a frame stem into a path, after checking the names. No I/O except, for colour, the
/// look-up of which extension exists.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    root: PathBuf,
}

impl Layout {
    /// The layout of the recording (or recording-like output folder) at `root`.
    pub(crate) fn new(root: &Path) -> Layout {
        Layout {
            root: root.to_path_buf(),
        }
    }

    fn camera_folder(&self, camera: &str) -> Result<PathBuf> {
        check_camera_name(camera)?;
        Ok(self.root.join(camera))
    }

    fn layer_folder(&self, camera: &str, layer: Layer) -> Result<PathBuf> {
        Ok(self.camera_folder(camera)?.join(layer.folder()))
    }

    /// `REC/<camera>/<layer>/<stem>.<ext>`: for colour the first of `.png`, `.jpg`,
    /// `.jpeg` that exists (`.png` when none does, for the error message).
    pub(crate) fn image_path(&self, camera: &str, layer: Layer, stem: &str) -> Result<PathBuf> {
        check_stem(stem)?;
        let folder = self.layer_folder(camera, layer)?;
        let candidates: Vec<PathBuf> = layer
            .extensions()
            .iter()
            .map(|ext| folder.join(format!("{stem}.{ext}")))
            .collect();
        let first = candidates[0].clone();
        if candidates.len() == 1 {
            return Ok(first);
        }
        Ok(bodyseg_io::first_existing_file(&candidates).unwrap_or(first))
    }

    fn boxes_path(&self, stem: &str) -> Result<PathBuf> {
        check_stem(stem)?;
        Ok(self.root.join(BOXES_FOLDER).join(format!("{stem}.json")))
    }

    /// `<root>/<camera>/parsing_preview/<stem>.png`: `bodyseg parse`'s palette preview
    /// beside its `parsing/` image (no layer of a recording).
    pub(crate) fn parsing_preview_path(&self, camera: &str, stem: &str) -> Result<PathBuf> {
        check_stem(stem)?;
        Ok(self
            .camera_folder(camera)?
            .join("parsing_preview")
            .join(format!("{stem}.png")))
    }
}

/// The frames of a recording ([`Recording::frames`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameList {
    /// Stems (sorted) whose depth image every camera has: the frames.
    pub complete: Vec<String>,
    /// Stems (sorted) that some cameras have a depth image for and others not, with the
    /// cameras (rig order) that lack it. Not frames; listed so that a caller can warn.
    pub incomplete: Vec<(String, Vec<String>)>,
}

/// A recording folder opened for reading: `rig.toml` read and validated, every camera's
/// folder present. Frames are listed with [`Recording::frames`] and their images read
/// with the `read_*` methods, each checked against the rig's sensor size.
#[derive(Clone, Debug)]
pub struct Recording {
    layout: Layout,
    rig: Rig,
}

impl Recording {
    /// Opens the recording at `root`: reads `root/rig.toml` and checks that every camera
    /// has a valid name and a folder.
    ///
    /// # Errors
    /// `root` is not a folder; `rig.toml` is missing or invalid; a camera's name is not a
    /// valid folder name (letters, digits, `_`, `-`, `.`; not `.` or `..`) or its folder is missing (the error names both).
    pub fn open(root: &Path) -> Result<Recording> {
        bodyseg_io::require_folder(root, "recording")?;
        let rig = bodyseg_calib::read_rig_toml(&root.join(RIG_FILE))?;
        let layout = Layout {
            root: root.to_path_buf(),
        };
        for camera in &rig.cameras {
            let folder = layout
                .camera_folder(&camera.name)
                .context("rig.toml")
                .with_context(|| root.display().to_string())?;
            bodyseg_io::require_folder(&folder, "camera")
                .with_context(|| format!("camera {} of rig.toml", camera.name))?;
        }
        Ok(Recording { layout, rig })
    }

    /// The recording's folder.
    pub fn root(&self) -> &Path {
        &self.layout.root
    }

    /// Whether `folder` holds a recording (a `rig.toml`).
    pub fn is_recording(folder: &Path) -> bool {
        folder.join(RIG_FILE).is_file()
    }

    /// The recording's `rig.toml`.
    pub fn rig_path(&self) -> PathBuf {
        self.layout.root.join(RIG_FILE)
    }

    /// The rig of `rig.toml`.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The camera names, rig order.
    pub fn cameras(&self) -> impl Iterator<Item = &str> {
        self.rig.cameras.iter().map(|c| c.name.as_str())
    }

    /// The path of `camera`'s image of `layer` for frame `stem` (colour: the `.png`,
    /// `.jpg` or `.jpeg` that exists).
    ///
    /// # Errors
    /// `camera` or `stem` is not a valid name (letters, digits, `_`, `-`, `.`; not `.` or `..`).
    pub fn image_path(&self, camera: &str, layer: Layer, stem: &str) -> Result<PathBuf> {
        self.layout.image_path(camera, layer, stem)
    }

    /// Whether every camera of the rig has a folder of `layer` (e.g. recorded predictions,
    /// ground truth).
    pub fn has_layer(&self, layer: Layer) -> bool {
        self.rig.cameras.iter().all(|c| {
            self.layout
                .layer_folder(&c.name, layer)
                .is_ok_and(|f| f.is_dir())
        })
    }

    /// The cameras of the rig (in rig order) without a folder of `layer`.
    pub fn cameras_lacking(&self, layer: Layer) -> Vec<&str> {
        self.rig
            .cameras
            .iter()
            .filter(|c| {
                !self
                    .layout
                    .layer_folder(&c.name, layer)
                    .is_ok_and(|f| f.is_dir())
            })
            .map(|c| c.name.as_str())
            .collect()
    }

    /// The person boxes file of frame `stem`: `REC/boxes/<stem>.json`.
    ///
    /// # Errors
    /// `stem` is not a valid name.
    pub fn boxes_path(&self, stem: &str) -> Result<PathBuf> {
        self.layout.boxes_path(stem)
    }

    /// Reads the person boxes of frame `stem` (`REC/boxes/<stem>.json`).
    ///
    /// # Errors
    /// `stem` is not a valid name; the file cannot be read or is not boxes JSON.
    pub fn read_boxes(&self, stem: &str) -> Result<PersonBoxes> {
        Ok(bodyseg_io::read_boxes(&self.boxes_path(stem)?)?)
    }

    /// The recording's frames: the stems of `<camera>/depth/*.png` that every camera has
    /// (hidden files and names that are not valid stems are no frames), and those only
    /// some cameras have.
    ///
    /// # Errors
    /// A camera's depth folder is missing or cannot be listed (the error names it).
    pub fn frames(&self) -> Result<FrameList> {
        let mut per_camera: Vec<BTreeSet<String>> = Vec::new();
        for camera in &self.rig.cameras {
            let folder = self.layout.layer_folder(&camera.name, Layer::Depth)?;
            let entries = bodyseg_io::list_folder(&folder, "depth folder")
                .with_context(|| format!("camera {} of rig.toml", camera.name))?;
            let stems = entries
                .into_iter()
                .filter(|e| !e.is_folder)
                .filter_map(|e| {
                    let stem = e.name.strip_suffix(".png")?;
                    if stem.starts_with('.') {
                        return None;
                    }
                    if check_stem(stem).is_err() {
                        tracing::warn!(
                            file = %folder.join(&e.name).display(),
                            "not a frame: its stem is not a valid frame name"
                        );
                        return None;
                    }
                    Some(stem.to_string())
                })
                .collect();
            per_camera.push(stems);
        }
        let mut lacking: BTreeMap<String, Vec<String>> = BTreeMap::new();
        let all: BTreeSet<&String> = per_camera.iter().flatten().collect();
        for stem in all {
            for (camera, stems) in self.rig.cameras.iter().zip(&per_camera) {
                if !stems.contains(stem) {
                    lacking
                        .entry(stem.clone())
                        .or_default()
                        .push(camera.name.clone());
                }
            }
        }
        let complete = per_camera
            .first()
            .map(|first| {
                first
                    .iter()
                    .filter(|s| !lacking.contains_key(*s))
                    .cloned()
                    .collect()
            })
            .unwrap_or_default();
        Ok(FrameList {
            complete,
            incomplete: lacking.into_iter().collect(),
        })
    }

    /// Camera `index` of the rig.
    fn camera(&self, index: usize) -> Result<&RgbdCamera> {
        self.rig.cameras.get(index).with_context(|| {
            format!(
                "camera index {index}: the rig has {} cameras",
                self.rig.cameras.len()
            )
        })
    }

    /// The depth image of camera `index` for frame `stem` (16-bit, the depth sensor's
    /// size), with its path.
    ///
    /// # Errors
    /// The file is missing, is not a 16-bit PNG, or has another size than the rig's
    /// depth sensor (the error names the camera, the file and both sizes).
    pub fn read_depth(&self, index: usize, stem: &str) -> Result<(DepthImage, PathBuf)> {
        self.read_image(index, Layer::Depth, stem, bodyseg_io::read_depth_png, |i| {
            (i.width, i.height)
        })
    }

    /// The colour image of camera `index` for frame `stem` (PNG or JPEG, the colour
    /// sensor's size), with its path.
    ///
    /// # Errors
    /// As [`Recording::read_depth`].
    pub fn read_color(&self, index: usize, stem: &str) -> Result<(RgbImage, PathBuf)> {
        self.read_image(index, Layer::Color, stem, bodyseg_io::read_rgb_image, |i| {
            (i.width, i.height)
        })
    }

    /// The colour image file of camera `index` for frame `stem` as stored (PNG or JPEG
    /// bytes, not decoded; its size from the header, checked against the colour sensor's),
    /// with its path.
    ///
    /// # Errors
    /// As [`Recording::read_depth`]; corrupt pixel data is not detected (nothing is
    /// decoded).
    pub fn read_color_file(
        &self,
        index: usize,
        stem: &str,
    ) -> Result<(bodyseg_io::ColorFile, PathBuf)> {
        self.read_image(
            index,
            Layer::Color,
            stem,
            bodyseg_io::read_color_file,
            |i| (i.width, i.height),
        )
    }

    /// A label image (8-bit class ids, 255 = none) of camera `index` for frame `stem`:
    /// `layer` is [`Layer::Parsing`], [`Layer::Labels`] (colour sensor size) or
    /// [`Layer::DepthLabels`] (depth sensor size); with its path.
    ///
    /// # Errors
    /// `layer` holds no class ids; as [`Recording::read_depth`], and a pixel that is no
    /// class id (the error names it).
    pub fn read_labels(
        &self,
        index: usize,
        layer: Layer,
        stem: &str,
    ) -> Result<(LabelImage, PathBuf)> {
        if matches!(layer, Layer::Color | Layer::Depth | Layer::DepthPerson) {
            bail!("{}/ holds no label images", layer.folder());
        }
        self.read_image(index, layer, stem, bodyseg_io::read_label_png, |i| {
            (i.width, i.height)
        })
    }

    /// The image of `layer` of camera `index` for frame `stem`, read by `read` and checked
    /// against its sensor's size (`size`: width, height in pixels), with its path. Read
    /// errors name the camera (and ground truth, for [`Layer::DepthLabels`]).
    fn read_image<T, E: std::error::Error + Send + Sync + 'static>(
        &self,
        index: usize,
        layer: Layer,
        stem: &str,
        read: impl FnOnce(&Path) -> Result<T, E>,
        size: impl FnOnce(&T) -> (u32, u32),
    ) -> Result<(T, PathBuf)> {
        let camera = self.camera(index)?;
        let path = self.image_path(&camera.name, layer, stem)?;
        let image = read(&path).with_context(|| match layer {
            Layer::DepthLabels => format!("camera {}: ground truth", camera.name),
            _ => format!("camera {}", camera.name),
        })?;
        check_size(camera, &path, layer, size(&image))?;
        Ok((image, path))
    }
}

/// `camera cam0: PATH: WHAT is WxH, rig.toml says [SENSOR]WxH` when an image of `layer`
/// has another size than its sensor.
fn check_size(camera: &RgbdCamera, path: &Path, layer: Layer, got: (u32, u32)) -> Result<()> {
    let (want, sensor) = match layer.sensor() {
        Sensor::Depth => ((camera.depth.width, camera.depth.height), ""),
        Sensor::Color => (
            (camera.color.width, camera.color.height),
            // A label image's size is the colour sensor's, which the reader may not expect.
            if matches!(layer, Layer::Parsing | Layer::Labels) {
                "the colour sensor is "
            } else {
                ""
            },
        ),
    };
    if got != want {
        bail!(
            "camera {}: {}: {} is {}x{}, rig.toml says {sensor}{}x{}",
            camera.name,
            path.display(),
            layer.what(),
            got.0,
            got.1,
            want.0,
            want.1
        );
    }
    Ok(())
}

/// A recording being written ([`RecordingWriter::create`]): `rig.toml`, the folders, and
/// each frame's images and boxes at the paths [`Recording`] reads. Files are written
/// atomically; frames may be written from several threads.
#[derive(Clone, Debug)]
pub struct RecordingWriter {
    layout: Layout,
    rig: Rig,
}

impl RecordingWriter {
    /// Starts a recording in the folder `root` (created if missing): writes `rig` as
    /// `rig.toml` and creates `boxes/` and, for every camera, the folders of `layers`.
    ///
    /// # Errors
    /// A camera's name is not a valid folder name; a file or folder cannot be written.
    pub fn create(root: &Path, rig: &Rig, layers: &[Layer]) -> Result<RecordingWriter> {
        let layout = Layout {
            root: root.to_path_buf(),
        };
        bodyseg_io::create_folder(root)?;
        bodyseg_calib::write_rig_toml(rig, &root.join(RIG_FILE))?;
        bodyseg_io::create_folder(&root.join(BOXES_FOLDER))?;
        for camera in &rig.cameras {
            for &layer in layers {
                bodyseg_io::create_folder(&layout.layer_folder(&camera.name, layer)?)?;
            }
        }
        Ok(RecordingWriter {
            layout,
            rig: rig.clone(),
        })
    }

    /// The recording's folder.
    pub fn root(&self) -> &Path {
        &self.layout.root
    }

    /// The width and height of camera `index`'s images of `layer`, and its name.
    fn size(&self, index: usize, layer: Layer) -> Result<(&str, u32, u32)> {
        let camera = self.rig.cameras.get(index).with_context(|| {
            format!(
                "camera index {index}: the rig has {} cameras",
                self.rig.cameras.len()
            )
        })?;
        let sensor = match layer.sensor() {
            Sensor::Color => &camera.color,
            Sensor::Depth => &camera.depth,
        };
        Ok((&camera.name, sensor.width, sensor.height))
    }

    /// The path an image of `layer` of camera `index` for frame `stem` is written to
    /// (`.png`).
    fn png_path(&self, index: usize, layer: Layer, stem: &str) -> Result<(PathBuf, u32, u32)> {
        let (name, w, h) = self.size(index, layer)?;
        check_stem(stem)?;
        let path = self
            .layout
            .layer_folder(name, layer)?
            .join(format!("{stem}.png"));
        Ok((path, w, h))
    }

    /// Writes camera `index`'s colour image of frame `stem` (`color/<stem>.png`, 8-bit
    /// RGB, `rgb` row-major at the colour sensor's size).
    ///
    /// # Errors
    /// `rgb` does not fit the sensor's size; writing fails.
    pub fn write_color(&self, index: usize, stem: &str, rgb: &[u8]) -> Result<()> {
        let (path, w, h) = self.png_path(index, Layer::Color, stem)?;
        Ok(bodyseg_io::write_rgb_png(&path, w, h, rgb)?)
    }

    /// Where camera `index`'s image of `layer` for frame `stem` is written, with the file
    /// extension `extension` (`png`; `jpg` for a colour image passed through).
    ///
    /// # Errors
    /// `index` is not a camera of the rig; the camera's name or `stem` is not a valid name.
    pub fn image_path(
        &self,
        index: usize,
        layer: Layer,
        stem: &str,
        extension: &str,
    ) -> Result<PathBuf> {
        let (name, _, _) = self.size(index, layer)?;
        check_stem(stem)?;
        Ok(self
            .layout
            .layer_folder(name, layer)?
            .join(format!("{stem}.{extension}")))
    }

    /// Writes camera `index`'s colour image of frame `stem` as the JPEG `jpeg`
    /// (`color/<stem>.jpg`, e.g. a camera's own compressed image, passed through), and
    /// removes a `color/<stem>.png` left from an earlier write, which readers would take
    /// first. The caller checks the JPEG's size.
    ///
    /// # Errors
    /// Writing fails.
    pub fn write_color_jpeg(&self, index: usize, stem: &str, jpeg: &[u8]) -> Result<()> {
        let path = self.image_path(index, Layer::Color, stem, "jpg")?;
        bodyseg_io::write_bytes_atomic(&path, jpeg)?;
        let png = path.with_extension("png");
        if png.is_file() {
            std::fs::remove_file(&png)
                .with_context(|| format!("{}: cannot remove the older image", png.display()))?;
        }
        Ok(())
    }

    /// Writes camera `index`'s depth image of frame `stem` (`depth/<stem>.png`, 16-bit,
    /// the depth sensor's size).
    ///
    /// # Errors
    /// `depth_mm` does not fit the sensor's size; writing fails.
    pub fn write_depth(&self, index: usize, stem: &str, depth_mm: &[u16]) -> Result<()> {
        let (path, width, height) = self.png_path(index, Layer::Depth, stem)?;
        let image = DepthImage {
            width,
            height,
            depth_mm: depth_mm.to_vec(),
        };
        Ok(bodyseg_io::write_depth_png(&path, &image)?)
    }

    /// Writes camera `index`'s 8-bit image of `layer` (parsing, labels, depth_labels,
    /// depth_person: class or person ids, row-major at the layer's sensor size) of frame
    /// `stem`.
    ///
    /// # Errors
    /// `layer` is colour or depth; `ids` does not fit the sensor's size; writing fails.
    pub fn write_ids(&self, index: usize, layer: Layer, stem: &str, ids: &[u8]) -> Result<()> {
        if matches!(layer, Layer::Color | Layer::Depth) {
            bail!("{}/ holds no 8-bit id images", layer.folder());
        }
        let (path, w, h) = self.png_path(index, layer, stem)?;
        Ok(bodyseg_io::write_gray8_png(&path, w, h, ids)?)
    }

    /// Writes the person boxes of frame `stem` (`boxes/<stem>.json`).
    ///
    /// # Errors
    /// Writing fails.
    pub fn write_boxes(&self, stem: &str, boxes: &PersonBoxes) -> Result<()> {
        Ok(bodyseg_io::write_boxes(
            &self.layout.boxes_path(stem)?,
            boxes,
        )?)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn layout() -> Layout {
        Layout {
            root: PathBuf::from("rec"),
        }
    }

    #[test]
    fn paths_follow_the_recording_layout() {
        let l = layout();
        let path = |layer| l.image_path("cam0", layer, "000012").expect("valid names");
        assert_eq!(path(Layer::Depth), Path::new("rec/cam0/depth/000012.png"));
        assert_eq!(
            path(Layer::Parsing),
            Path::new("rec/cam0/parsing/000012.png")
        );
        assert_eq!(
            path(Layer::DepthLabels),
            Path::new("rec/cam0/depth_labels/000012.png")
        );
        assert_eq!(
            path(Layer::DepthPerson),
            Path::new("rec/cam0/depth_person/000012.png")
        );
        // No colour file exists: the .png, for the error message.
        assert_eq!(path(Layer::Color), Path::new("rec/cam0/color/000012.png"));
        assert_eq!(
            l.boxes_path("000003").expect("valid"),
            Path::new("rec/boxes/000003.json")
        );
        let folders: Vec<&str> = Layer::ALL.iter().map(|l| l.folder()).collect();
        assert_eq!(
            folders,
            [
                "color",
                "depth",
                "parsing",
                "labels",
                "depth_labels",
                "depth_person"
            ]
        );
    }

    #[test]
    fn names_that_would_leave_the_folder_are_refused() {
        for good in ["000012", "cam0", "a.b-c_D", "1700000000.123"] {
            assert!(
                check_stem(good).is_ok() && check_camera_name(good).is_ok(),
                "{good}"
            );
        }
        for bad in ["", ".", "..", "a/b", "..\\x", "/abs", "a b", "ü", "x\0"] {
            let e = format!("{:#}", check_stem(bad).expect_err("refused"));
            assert!(e.contains("file stem") && e.contains("frame"), "{e}");
        }
        let l = layout();
        let e = format!(
            "{:#}",
            l.image_path("../etc", Layer::Depth, "000001")
                .expect_err("refused")
        );
        assert!(e.starts_with("camera \"../etc\""), "{e}");
        assert!(l.image_path("cam0", Layer::Depth, "../../x").is_err());
        assert!(l.boxes_path("..").is_err());
        for good in [
            "clouds/000001.ply",
            "rec_a/boxes/1.json",
            "labels/cam0/x.png",
        ] {
            assert!(check_relative_path(good).is_ok(), "{good}");
        }
        for bad in [
            "",
            "/abs/x.ply",
            "clouds/../../x.ply",
            "clouds//x.ply",
            "labels/kamera_ä/1.png",
            "a\0b",
            "./x",
        ] {
            let e = format!("{:#}", check_relative_path(bad).expect_err(bad));
            assert!(e.contains("lead out of the output folder"), "{e}");
        }
        assert!(check_folder_name("recording", "kamera_ä").is_err());
        assert!(check_folder_name("recording", "rec-1.a").is_ok());
    }

    /// The rig of the `single` preset (three Kinect v2-like cameras), for tests.
    pub(crate) fn rig() -> Rig {
        let preset = bodyseg_synth::preset("single").expect("preset");
        bodyseg_synth::Synth::new(preset, 1)
            .expect("synth")
            .true_rig()
            .clone()
    }

    /// A temporary folder with a recording of [`rig`] with `layers` begun in `rec/`: the
    /// folder, the recording's root, the rig and the writer.
    fn new_recording(layers: &[Layer]) -> (tempfile::TempDir, PathBuf, Rig, RecordingWriter) {
        let dir = tempfile::tempdir().expect("temp dir");
        let root = dir.path().join("rec");
        let rig = rig();
        let writer = RecordingWriter::create(&root, &rig, layers).expect("create");
        (dir, root, rig, writer)
    }

    #[test]
    fn a_passed_through_jpeg_replaces_an_older_png() {
        let (_dir, root, rig, writer) = new_recording(&[Layer::Color, Layer::Depth]);
        let color = root.join(&rig.cameras[0].name).join("color");
        assert_eq!(
            writer
                .image_path(0, Layer::Color, "000000", "jpg")
                .expect("path"),
            color.join("000000.jpg")
        );
        assert!(writer.image_path(9, Layer::Color, "000000", "jpg").is_err());
        assert!(writer.image_path(0, Layer::Color, "../x", "jpg").is_err());
        let rgb = vec![7u8; 3 * rig.cameras[0].color.num_pixels()];
        writer.write_color(0, "000000", &rgb).expect("png");
        assert!(color.join("000000.png").is_file());
        let jpeg = b"\xff\xd8 the bytes as they are".to_vec();
        writer.write_color_jpeg(0, "000000", &jpeg).expect("jpeg");
        assert!(!color.join("000000.png").exists(), "the older PNG is gone");
        assert_eq!(std::fs::read(color.join("000000.jpg")).expect("read"), jpeg);
    }

    #[test]
    fn a_written_recording_reads_back_with_its_frames_and_size_checks() {
        let (_dir, root, rig, writer) = new_recording(&[Layer::Depth, Layer::Parsing]);
        let depth = |i: usize| vec![1000u16 + i as u16; rig.cameras[i].depth.num_pixels()];
        for i in 0..rig.cameras.len() {
            writer.write_depth(i, "000000", &depth(i)).expect("depth");
        }
        // Frame 000001 only for the first camera: not a frame, listed as incomplete.
        writer.write_depth(0, "000001", &depth(0)).expect("depth");
        let ids = vec![0u8; rig.cameras[0].color.num_pixels()];
        writer
            .write_ids(0, Layer::Parsing, "000000", &ids)
            .expect("parsing");
        assert!(writer.write_ids(0, Layer::Depth, "000000", &ids).is_err());
        assert!(writer.write_color(0, "000000", &[0; 3]).is_err(), "size");

        let rec = Recording::open(&root).expect("open");
        assert_eq!(rec.rig(), &rig);
        let names: Vec<String> = rec.cameras().map(str::to_string).collect();
        let frames = rec.frames().expect("frames");
        assert_eq!(frames.complete, ["000000"]);
        assert_eq!(
            frames.incomplete,
            [("000001".to_string(), names[1..].to_vec())]
        );
        assert!(rec.has_layer(Layer::Parsing) && rec.has_layer(Layer::Depth));
        assert!(!rec.has_layer(Layer::DepthLabels));
        let (d, path) = rec.read_depth(1, "000000").expect("depth");
        assert_eq!(d.depth_mm, depth(1));
        assert_eq!(path, root.join(&names[1]).join("depth/000000.png"));
        let (labels, _) = rec
            .read_labels(0, Layer::Parsing, "000000")
            .expect("parsing");
        assert_eq!(labels.num_pixels(), ids.len());
        assert!(rec.read_labels(0, Layer::Depth, "000000").is_err());
        let e = format!(
            "{:#}",
            rec.read_labels(1, Layer::Parsing, "000000")
                .expect_err("none")
        );
        assert!(e.contains("parsing/000000.png"), "{e}");

        // An image of another size than the rig's sensor: both sizes named.
        let small = DepthImage {
            width: 4,
            height: 2,
            depth_mm: vec![0; 8],
        };
        bodyseg_io::write_depth_png(&path, &small).expect("write");
        let e = format!("{:#}", rec.read_depth(1, "000000").expect_err("size"));
        assert!(
            e.contains("depth image is 4x2, rig.toml says 512x424") && e.contains(&names[1]),
            "{e}"
        );
    }

    #[test]
    fn opening_checks_camera_names_and_folders() {
        let (_dir, root, mut rig, _) = new_recording(&[Layer::Depth]);
        let missing = root.join(&rig.cameras[2].name);
        std::fs::remove_dir_all(&missing).expect("remove");
        let e = format!("{:#}", Recording::open(&root).expect_err("missing"));
        assert!(e.contains("camera folder is missing"), "{e}");

        rig.cameras[2].name = "../outside".into();
        assert!(RecordingWriter::create(&root, &rig, &[Layer::Depth]).is_err());
        bodyseg_calib::write_rig_toml(&rig, &root.join(RIG_FILE)).expect("rig");
        let e = format!("{:#}", Recording::open(&root).expect_err("bad name"));
        assert!(e.contains("camera \"../outside\""), "{e}");
    }
}
