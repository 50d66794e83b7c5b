//! Labelled point clouds, stored as a struct of arrays.

use crate::class::Label;
use crate::math::{Vec3, is_finite};

/// Where a point came from: the camera and the depth pixel that measured it.
/// `(camera, pixel)` is the key that ties a predicted point to its ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PointOrigin {
    /// Camera index in rig order.
    pub camera: u8,
    /// Row-major index of the pixel in that camera's depth image (`v * width + u`).
    pub pixel: u32,
}

/// Why a cloud is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CloudError {
    /// Two of the per-point arrays have different lengths.
    #[error("cloud has {want} points but {got} {field}")]
    LengthMismatch {
        /// Name of the array whose length is off.
        field: &'static str,
        /// Its length.
        got: usize,
        /// The number of positions.
        want: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a NaN or infinite coordinate")]
    NonFinite {
        /// Index of the first such point.
        index: usize,
    },
}

/// A point cloud with one label per point, world frame.
///
/// Struct of arrays: `positions_m[i]`, `labels[i]`, `origins[i]` (and `colors[i]` when
/// present) describe point `i`. The order is meaningful (FORMATS.md: cameras in rig order,
/// pixels row-major) and every stage after projection keeps it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabeledCloud {
    /// Point positions, world frame, metres.
    pub positions_m: Vec<Vec3>,
    /// Per-point label.
    pub labels: Vec<Label>,
    /// Optional per-point camera colour (RGB).
    pub colors: Option<Vec<[u8; 3]>>,
    /// Per-point origin (camera, depth pixel). A cloud read from a file that has no
    /// origin stores camera 0 and the point's index as pixel.
    pub origins: Vec<PointOrigin>,
}

impl LabeledCloud {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions_m.len()
    }

    /// True when the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.positions_m.is_empty()
    }

    /// Checks that the arrays agree in length and every coordinate is finite.
    pub fn validate(&self) -> Result<(), CloudError> {
        let want = self.positions_m.len();
        let check = |field, got| {
            if got == want {
                Ok(())
            } else {
                Err(CloudError::LengthMismatch { field, got, want })
            }
        };
        check("labels", self.labels.len())?;
        check("origins", self.origins.len())?;
        if let Some(c) = &self.colors {
            check("colors", c.len())?;
        }
        // Every stage that takes a cloud checks it, so this scan runs several times per
        // frame: chunks without an early exit (a branch-free `&` that vectorises), the
        // index searched only in a chunk that has a bad point.
        const CHUNK: usize = 1024;
        for (c, chunk) in self.positions_m.chunks(CHUNK).enumerate() {
            let all_finite = chunk.iter().fold(true, |ok, &p| ok & is_finite(p));
            if !all_finite {
                let offset = chunk.iter().position(|&p| !is_finite(p)).unwrap_or(0);
                return Err(CloudError::NonFinite {
                    index: c * CHUNK + offset,
                });
            }
        }
        Ok(())
    }

    /// A copy of this cloud with other labels (same points, same order).
    pub fn with_labels(&self, labels: Vec<Label>) -> LabeledCloud {
        debug_assert_eq!(labels.len(), self.len());
        // Field by field: `..self.clone()` would copy the old labels too, only to drop them.
        LabeledCloud {
            positions_m: self.positions_m.clone(),
            labels,
            colors: self.colors.clone(),
            origins: self.origins.clone(),
        }
    }
}

/// The output of the refinement stage: the input's points in the input's order, with
/// refined labels (never unknown), and per point the DBSCAN cluster it fell in (for
/// figures; `None` = noise or outside every box).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinedCloud {
    /// The refined cloud.
    pub cloud: LabeledCloud,
    /// Per point: `(person index, cluster id within that person)` of the first box that
    /// clustered it, or `None`.
    pub clusters: Vec<Option<(u32, u32)>>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::class::Class;

    #[test]
    fn validate_reports_nan_and_length_mismatch() {
        let mut c = LabeledCloud {
            positions_m: vec![[0.0; 3], [1.0, f32::NAN, 0.0]],
            labels: vec![Label::from(Class::Head); 2],
            colors: None,
            origins: vec![
                PointOrigin {
                    camera: 0,
                    pixel: 0
                };
                2
            ],
        };
        assert_eq!(c.validate(), Err(CloudError::NonFinite { index: 1 }));
        // Beyond the first chunk of the scan, and the first bad point of several.
        let mut far = LabeledCloud {
            positions_m: vec![[0.5; 3]; 5000],
            labels: vec![Label::UNKNOWN; 5000],
            origins: vec![
                PointOrigin {
                    camera: 0,
                    pixel: 0
                };
                5000
            ],
            colors: None,
        };
        far.positions_m[3000][2] = f32::INFINITY;
        far.positions_m[4000][0] = f32::NAN;
        assert_eq!(far.validate(), Err(CloudError::NonFinite { index: 3000 }));
        c.positions_m[1][1] = 0.0;
        assert_eq!(c.validate(), Ok(()));
        c.labels.pop();
        assert!(matches!(
            c.validate(),
            Err(CloudError::LengthMismatch {
                field: "labels",
                ..
            })
        ));
    }
}
