//! bodyseg-view: every stage of a run as a [Rerun](https://rerun.io) recording (`.rrd`).
//!
//! Place in the pipeline: beside it. The frame loop of `bodyseg run` / `convert` (or
//! `bodyseg view`, from a finished run's files) hands each frame's stages to a
//! [`FrameSink`] as a [`ViewFrame`] of borrowed data; the [`ViewWriter`] (feature `rerun`)
//! logs them and drops them, so the file streams frame by frame:
//!
//! ```text
//! Rig (once)                        → cameras: Pinhole + Transform3D, static
//! ViewFrame (colour files, depth, 2D labels, projected / refined clouds, clusters, boxes, scores)
//!                                   → images, Points3D, Boxes3D, Scalars on the `frame` timeline
//! ```
//!
//! Without the `rerun` feature the crate holds only the types and the entity paths
//! ([`paths`]); no Rerun code is built.
//!
//! # Conventions
//! - World frame: right-handed, z up (ALGORITHM.md §0), logged as `RIGHT_HAND_Z_UP` on
//!   `world`. Camera frames: OpenCV optical (x right, y down, z forward), Rerun's pinhole
//!   default (`RDF`).
//! - Rerun's pinhole has no lens distortion: the images are shown as recorded (distorted)
//!   on an ideal pinhole of the same focal length and principal point.
//! - Colour: the recording's PNG or JPEG files as they are (`EncodedImage`, decoded by
//!   the viewer) when the frame carries them, else the decoded pixels (`Image`).
//! - Depth: the raw `u16` values with Rerun's `meter` = the camera's `depth_scale` (raw
//!   units per metre); `depth_shift_mm` is not applied.
//! - Class ids: our on-disk label ids (0..7, [`bodyseg_core::Class`]) with our names and
//!   palette in an `AnnotationContext` on `world`; unknown points (id 255) are logged apart
//!   (`…_unknown`, class id 255), and id 255 in images is annotated `unknown`.
//! - Clouds: the projected and the refined cloud share their points, gathered once into
//!   one positions array ordered so that each entity is a slice of it (`order.rs`).
//! - Timelines: `frame` = the frame's index among the recording's frames (sequence);
//!   `time` = its time stamp, when the recording has a `stamps.csv`.

pub mod paths;

#[cfg(feature = "rerun")]
mod encoder;
#[cfg(feature = "rerun")]
mod ipc;
#[cfg(feature = "rerun")]
mod manifest;
#[cfg(feature = "rerun")]
mod order;
#[cfg(feature = "rerun")]
mod rows;
#[cfg(feature = "rerun")]
mod sink;
#[cfg(feature = "rerun")]
mod writer;

#[cfg(feature = "rerun")]
pub use writer::ViewWriter;

use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabelImage, PersonBox, RgbImage};
use std::path::PathBuf;

/// One camera's images of a frame, in the rig's camera order; any may be missing.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraView<'a> {
    /// The colour image, decoded (logged when there is no [`CameraView::color_file`]).
    pub color: Option<&'a RgbImage>,
    /// The colour image file as stored: logged as it is (an encoded image the viewer
    /// decodes), in place of [`CameraView::color`].
    pub color_file: Option<ColorFileView<'a>>,
    /// The raw depth image (depth sensor pixels; unit: the camera's `depth_scale`).
    pub depth: Option<DepthView<'a>>,
    /// The 2D parser's labels (colour sensor pixels).
    pub parsed: Option<&'a LabelImage>,
    /// The refined labels drawn back into the colour image (`labels/`).
    pub refined: Option<&'a LabelImage>,
}

/// A colour image file as stored (PNG or JPEG bytes), borrowed.
#[derive(Clone, Copy, Debug)]
pub struct ColorFileView<'a> {
    /// The file's bytes.
    pub bytes: &'a [u8],
    /// Its format.
    pub format: ImageFileFormat,
}

/// The format of an image file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFileFormat {
    /// PNG (`image/png`).
    Png,
    /// JPEG (`image/jpeg`).
    Jpeg,
}

/// A raw depth image, borrowed.
#[derive(Clone, Copy, Debug)]
pub struct DepthView<'a> {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Raw values, row-major; 0 = no measurement.
    pub raw: &'a [u16],
}

/// A labelled cloud, borrowed: positions and labels of the same length.
#[derive(Clone, Copy, Debug)]
pub struct CloudView<'a> {
    /// Point positions, metres, world frame.
    pub positions_m: &'a [Vec3],
    /// One label per point.
    pub labels: &'a [Label],
}

/// One frame's stages, as [`FrameSink::write_frame`] takes them.
#[derive(Clone, Debug, Default)]
pub struct ViewFrame<'a> {
    /// The frame's stem (file name without extension).
    pub stem: &'a str,
    /// One entry per camera of the rig, in rig order (or none at all).
    pub cameras: Vec<CameraView<'a>>,
    /// The projected cloud (the labels as projected, before refinement).
    pub projected: Option<CloudView<'a>>,
    /// The refined cloud (what `clouds/<frame>.ply` holds).
    pub refined: Option<CloudView<'a>>,
    /// Per point of the refined cloud, `(person index, cluster id)`; `None` = noise.
    /// Logged only by a `ViewWriter` made `with_clusters(true)` (feature `rerun`).
    pub clusters: Option<&'a [Option<(u32, u32)>]>,
    /// The person boxes.
    pub boxes: Option<&'a [PersonBox]>,
    /// Scores of the frame, as `(name, value)`; the name is a path under `scores/`
    /// (`M-R-N/biou`, `M-R-N/iou/head`).
    pub scores: Vec<(String, f64)>,
}

/// Where a run's frames go as they are processed (the `.rrd` writer, or a test's
/// collector). Called from any worker thread, in any frame order.
pub trait FrameSink: Send + Sync {
    /// Logs one frame.
    ///
    /// # Errors
    /// The frame does not fit the sink (unknown stem, sizes), or writing fails.
    fn write_frame(&self, frame: &ViewFrame<'_>) -> Result<(), ViewError>;

    /// Whether the sink logs [`ViewFrame::clusters`]; when not, the caller need not list
    /// them (12 bytes a point, built during the refinement).
    fn wants_clusters(&self) -> bool {
        true
    }
}

/// Everything that can go wrong while writing a view.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The frame is not one of the recording's frames given to the writer.
    #[error("frame {stem}: not among the recording's frames")]
    UnknownFrame {
        /// The stem.
        stem: String,
    },
    /// A frame has another number of cameras than the rig.
    #[error("frame {stem}: {got} cameras, the rig has {want}")]
    CameraCount {
        /// The frame.
        stem: String,
        /// Cameras in the frame.
        got: usize,
        /// Cameras in the rig.
        want: usize,
    },
    /// A cloud's positions and labels differ in length.
    #[error("frame {stem}: {layer} cloud has {positions} points but {labels} labels")]
    CloudLength {
        /// The frame.
        stem: String,
        /// Which cloud (`projected`, `refined`, `clusters`).
        layer: &'static str,
        /// Number of positions.
        positions: usize,
        /// Number of labels (or cluster entries).
        labels: usize,
    },
    /// An image's pixel buffer does not match its size.
    #[error(
        "frame {stem}, camera {camera}: {what} image has {got} values, {width}x{height} wants {want}"
    )]
    ImageSize {
        /// The frame.
        stem: String,
        /// The camera's name.
        camera: String,
        /// Which image (`colour`, `depth`, `labels`, `refined labels`).
        what: &'static str,
        /// Values present.
        got: usize,
        /// Values wanted.
        want: usize,
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// The time stamps file cannot be read or parsed.
    #[error("time stamps, line {line}: {reason}: {path}")]
    Stamps {
        /// 1-based line number (0 for the whole file).
        line: usize,
        /// What is wrong.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// The Rerun SDK failed (creating the file, logging, flushing).
    #[error("rerun: {message}: {path}")]
    Rerun {
        /// The SDK's message.
        message: String,
        /// The `.rrd` file.
        path: PathBuf,
    },
}

/// The time stamps of a recording's frames from a `stamps.csv`'s text (nanoseconds since
/// the Unix epoch), sorted by stem. Two layouts are read: `stem,nanoseconds` per line, and
/// the one `bodyseg import ros2` writes, `frame,camera,depth_stamp_ns,colour_stamp_ns` per
/// frame and camera, where a frame's time is its cameras' earliest depth stamp. `#`
/// comments and a header line (its first field `stem` or `frame`) are skipped.
///
/// # Errors
/// [`ViewError::Stamps`] for a line without a comma or with a bad number (the line named).
pub fn parse_stamps(text: &str, path: &std::path::Path) -> Result<Vec<(String, i64)>, ViewError> {
    let mut by_stem = std::collections::BTreeMap::<String, i64>::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty()
            || line.starts_with('#')
            || (i == 0 && (line.starts_with("stem,") || line.starts_with("frame,")))
        {
            continue;
        }
        let bad = |reason: String| ViewError::Stamps {
            line: i + 1,
            reason,
            path: path.to_path_buf(),
        };
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        // `stem,ns` or `frame,camera,depth_ns,colour_ns`: the stamp is the second field,
        // or the third when the second is a camera name.
        let ns = match fields[..] {
            [_, ns] => ns,
            [_, _, depth_ns, _] => depth_ns,
            _ => {
                return Err(bad(
                    "expected `stem,nanoseconds` or `frame,camera,depth_stamp_ns,colour_stamp_ns`"
                        .into(),
                ));
            }
        };
        let ns: i64 = ns
            .parse()
            .map_err(|e| bad(format!("nanoseconds {ns:?}: {e}")))?;
        let t = by_stem.entry(fields[0].to_string()).or_insert(ns);
        *t = (*t).min(ns);
    }
    Ok(by_stem.into_iter().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn stamps_parse_and_name_the_bad_line() {
        let ok = parse_stamps("stem,ns\n# c\nb,20\na, 10\n", Path::new("s.csv"));
        assert_eq!(
            ok.ok(),
            Some(vec![("a".to_string(), 10), ("b".to_string(), 20)])
        );
        let err = parse_stamps("a,1\nb;2\n", Path::new("s.csv"))
            .err()
            .map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some(
                "time stamps, line 2: expected `stem,nanoseconds` or \
                 `frame,camera,depth_stamp_ns,colour_stamp_ns`: s.csv"
            )
        );
        assert!(parse_stamps("a,x\n", Path::new("s.csv")).is_err());
        // What `bodyseg import ros2` writes: the earliest depth stamp of a frame's cameras.
        let ros = parse_stamps(
            "frame,camera,depth_stamp_ns,colour_stamp_ns\n000000,a,105,107\n000000,b,100,109\n000001,a,205,206\n",
            Path::new("stamps.csv"),
        );
        assert_eq!(
            ros.ok(),
            Some(vec![
                ("000000".to_string(), 100),
                ("000001".to_string(), 205)
            ])
        );
    }
}
