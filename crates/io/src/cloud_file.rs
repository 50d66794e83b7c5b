//! A point cloud file as it was read, before the caller decides what its labels and its
//! layout mean: [`CloudFile`] (PLY or PCD, by extension: `read_cloud_file`).
//!
//! The readers no longer insist on bodyseg's class ids: a cloud without a `label` field
//! (trimesh's, a scanner's) reads with every label unknown and [`FileLabels::Absent`]; a
//! `label` field holding other ids (PCL's `PointXYZRGBL` segment ids) reads the same way
//! with [`FileLabels::Foreign`]. A caller that needs labels refuses those
//! ([`CloudFile::into_class_labels`], or its own message); one that does not (geometry-mode
//! boxes) goes on.

use crate::IoError;
use bodyseg_core::LabeledCloud;
use std::path::Path;

/// What the file's `label` field holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FileLabels {
    /// bodyseg's class ids (0..=6, 255 = unknown), read into the cloud's labels.
    Classes,
    /// No `label` field: every label is unknown.
    Absent,
    /// A `label` field with a value that is no class id: not ours (PCL's segment ids), so
    /// every label is unknown (a segment id 3 is not an upper arm).
    Foreign {
        /// The first point (PCD) or vertex (PLY) whose label is no class id, 0-based.
        index: usize,
        /// Its value, as text.
        value: String,
    },
}

/// An organised cloud's image grid (PCD `HEIGHT` > 1; PLY `obj_info num_cols` /
/// `num_rows`): point `i` of [`CloudFile::cloud`] lies at grid cell
/// `origins[i].pixel = v · width + u`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CloudGrid {
    /// Columns (`WIDTH`, `num_cols`).
    pub width: u32,
    /// Rows (`HEIGHT`, `num_rows`).
    pub height: u32,
    /// Every cell's colour, row-major, the cells of invalid (NaN) points included where
    /// the file keeps their colour (PCL's PCD does; a PLY has no vertex there: black).
    /// `None` when the file has no colour.
    pub colors: Option<Vec<[u8; 3]>>,
}

/// A cloud file as read.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudFile {
    /// The points with a finite position, in file order; labels unknown unless
    /// [`FileLabels::Classes`].
    pub cloud: LabeledCloud,
    /// What the `label` field held.
    pub labels: FileLabels,
    /// The grid of an organised cloud; `None` for an unorganised one.
    pub grid: Option<CloudGrid>,
}

impl CloudFile {
    /// The cloud, when its labels are bodyseg's class ids or absent (then unknown, as
    /// PCD readers always took them).
    ///
    /// # Errors
    /// [`IoError::ForeignLabels`] for [`FileLabels::Foreign`], naming the point and the
    /// fix.
    /// `element` names a point in the message: `point` (PCD) or `vertex` (PLY).
    pub fn into_class_labels(
        self,
        element: &'static str,
        path: &Path,
    ) -> Result<LabeledCloud, IoError> {
        match self.labels {
            FileLabels::Foreign { index, value } => Err(IoError::ForeignLabels {
                element,
                index,
                value,
                path: path.to_path_buf(),
            }),
            FileLabels::Classes | FileLabels::Absent => Ok(self.cloud),
        }
    }
}
