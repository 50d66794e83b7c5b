//! [`BoxesConfig`]: every knob of the box finder, with units and defaults.

use serde::{Deserialize, Serialize};

/// Errors of the box finder.
#[derive(Debug, thiserror::Error)]
pub enum PeopleError {
    /// A configuration field is out of range.
    #[error("boxes.{field} {problem}")]
    InvalidConfig {
        /// The field's name.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// The input cloud is inconsistent (NaN coordinate, arrays of different lengths).
    /// The cause is in the message, not in `source()`, so an error chain prints it once.
    #[error("input cloud: {0}")]
    InvalidCloud(bodyseg_core::CloudError),
    /// `mode = "file"` was asked of the finder: file boxes are read, not found.
    #[error("boxes.mode = \"file\": boxes are read from boxes/<frame>.json, not found in a cloud")]
    FileMode,
}

impl From<bodyseg_core::CloudError> for PeopleError {
    fn from(e: bodyseg_core::CloudError) -> Self {
        PeopleError::InvalidCloud(e)
    }
}

/// Where the boxes come from (ALGORITHM.md §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxMode {
    /// Body-labelled points clustered and split on heads (default).
    #[default]
    Labels,
    /// No labels: ground plane removed, the rest clustered and split on head-height maxima
    /// (Munaro et al.'s ground-based people detector, without its image classifier).
    Geometry,
    /// Read per frame from `boxes/<stem>.json` (the pipeline does this, not this crate).
    File,
}

impl BoxMode {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            BoxMode::Labels => "labels",
            BoxMode::Geometry => "geometry",
            BoxMode::File => "file",
        }
    }
}

/// The box finder's configuration (`[boxes]` in the pipeline's TOML). Lengths in metres,
/// heights above the floor (labels mode: z = 0; geometry mode: the fitted ground plane).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoxesConfig {
    /// Where boxes come from: `labels`, `geometry` or `file`. Default `labels`.
    pub mode: BoxMode,
    /// Edge of the voxels points are averaged into before clustering, metres: 5 cm keeps
    /// a forearm (≈ 8 cm thick) connected and a frame of three Kinect v2 cameras under
    /// 5 ms (the bench). In [0.01, 0.5]. Default 0.05.
    pub voxel_m: f32,
    /// A voxel with fewer points is ignored: flying pixels (depth samples strewn between
    /// a person and the background, a few per voxel) rather than a surface (a 5 cm voxel
    /// of a surface at 4 m holds ≈ 15 points per Kinect v2 camera). Lower it for sparse
    /// clouds (a back-projection stride > 1, a downsampled file). In [1, 10⁶]. Default 4.
    pub min_voxel_points: u32,
    /// Two voxels closer than this belong to the same person, metres: above the holes a
    /// parser leaves between parts, below the gap between people standing apart. Must be
    /// > `voxel_m`, at most 10 × `voxel_m` and 1 m. Default 0.12.
    pub person_gap_m: f32,
    /// A person has at least this many voxels (0.1 m² of surface at 5 cm); smaller
    /// clusters are parser noise. In [1, 10⁶]. Default 40.
    pub min_voxels: usize,
    /// A person's top is at least this high above the floor, metres (a crouching adult
    /// is ≈ 1.1 m). In (0, 3]. Default 0.9.
    pub min_height_m: f32,
    /// Geometry mode: a person's top is at least this high, metres, instead of
    /// `min_height_m`. Without labels, what stands up to ≈ 1 m in a workcell looks like a
    /// crouching person from above: a robot's shoulder joint on its pedestal (0.97 m in
    /// bodyseg-synth), a storage box (up to 0.9 m), a table with things on it; crouching
    /// adults are ≈ 1.05 m and up. Lower it to find people sitting on the floor. In
    /// (0, 3] and < `max_height_m`. Default 1.0.
    pub geometry_min_height_m: f32,
    /// A person's top is at most this high, metres. Must be > `min_height_m` and
    /// `geometry_min_height_m`, at most 3. Default 2.3.
    pub max_height_m: f32,
    /// A person's lowest voxel is at most this high, metres: people stand on the floor
    /// (a reaching arm or a hand-held object does not). In [0, 3]. Default 0.45.
    pub max_bottom_m: f32,
    /// A person is at most this wide (longer horizontal side of the box without margin),
    /// metres: two spread arms. In (0, 5]. Default 1.6.
    pub max_width_m: f32,
    /// Two heads (or torsos) whose centres are closer than this horizontally are one,
    /// metres: below the head distance of two people passing an object (≈ 0.6 m), above
    /// a head-to-hand distance when hands are on the hips. Geometry mode keeps a lower
    /// top closer than this (down to 0.25 m) when nothing higher joins it within a
    /// head's height: two heads leaning together. In (0, 2]. Default 0.4.
    pub head_separation_m: f32,
    /// Labels mode: a head holds at least this many voxels (half a head's surface,
    /// ≈ 0.06 m², is ≈ 25 voxels at 5 cm); smaller head-labelled patches are parser noise.
    /// In [1, 10⁶]. Default 4.
    pub min_head_voxels: usize,
    /// Added on every side of a cluster's horizontal extent and above its top, metres
    /// (bodyseg-synth's true boxes use 0.05). In [0, 1]. Default 0.05.
    pub box_margin_m: f32,
    /// A point within this height of the floor is floor, metres: geometry mode removes
    /// it with the ground plane; labels mode ignores body-labelled ones (a parser's feet
    /// bleed onto the floor). Kinect v2 depth noise at 4 m is ≈ 1.5 cm. In (0, 0.5].
    /// Default 0.05.
    pub ground_tol_m: f32,
    /// Geometry mode: the ground plane's normal is within this angle of +z, degrees
    /// (clouds are z up). In (0, 90). Default 15.
    pub max_ground_tilt_deg: f32,
    /// Geometry mode: RANSAC iterations of the ground-plane fit (fixed seed:
    /// deterministic). In [1, 100 000]. Default 200.
    pub ransac_iterations: usize,
    /// Geometry mode: 90% of the voxels within 0.2 m below a head's top (and closer than
    /// `head_separation_m`) lie within this horizontal distance of the top, metres: a
    /// head is ≈ 0.1 m in radius (voxel centroids add up to half a voxel), the sloping
    /// links below a robot arm's joint reach farther. Tops higher than 1.5 m get 0.1 m
    /// more, on 75% of the voxels (only people reach there in a workcell: hair, a tilted
    /// head, a neighbour's hand on it). In (0, 0.5]. Default 0.15.
    pub max_head_radius_m: f32,
    /// Geometry mode: a person's points lie within this horizontal distance of their head,
    /// metres (a hand pointing sideways ≈ 0.85 m): what touches them farther out (a robot
    /// arm, a table) is cut off. In (0, 3]. Default 0.9.
    pub max_reach_m: f32,
    /// Geometry mode: horizontal radius of the column below a head that must hold the
    /// person's body, metres (neck, torso and at least one leg lie within ≈ 0.2 m of the
    /// head's vertical, even when leaning or walking). In (0, 1]. Default 0.2.
    pub column_radius_m: f32,
    /// Geometry mode: fraction of the 10 cm height slices between the floor and the
    /// head that must hold a voxel within `column_radius_m` of the head: a person is a
    /// continuous column; a robot arm's elbow or a raised hand is not. In [0, 1].
    /// Default 0.7.
    pub min_column_fill: f32,
    /// Geometry mode: use the points' colours, where the cloud has them, in the split
    /// between people and what is nobody's (a robot): the robot's part spreads cheaply
    /// only through its own colours (those it wears more than the people there) and pays
    /// to step into a person's, so a sleeve or a hand reaching along a robot link stays
    /// its owner's. false = positions only. Default true. (Key `colour_split`, the former
    /// spelling, is read too.)
    #[serde(alias = "colour_split")]
    pub color_split: bool,
}

impl Default for BoxesConfig {
    fn default() -> Self {
        BoxesConfig {
            mode: BoxMode::Labels,
            voxel_m: 0.05,
            min_voxel_points: 4,
            person_gap_m: 0.12,
            min_voxels: 40,
            min_height_m: 0.9,
            geometry_min_height_m: 1.0,
            max_height_m: 2.3,
            max_bottom_m: 0.45,
            max_width_m: 1.6,
            head_separation_m: 0.4,
            min_head_voxels: 4,
            box_margin_m: 0.05,
            ground_tol_m: 0.05,
            max_ground_tilt_deg: 15.0,
            ransac_iterations: 200,
            max_head_radius_m: 0.15,
            max_reach_m: 0.9,
            column_radius_m: 0.2,
            min_column_fill: 0.7,
            color_split: true,
        }
    }
}

impl BoxesConfig {
    /// Whether box finding reads the points' colours (geometry mode with `color_split`):
    /// then a pipeline samples them from the colour images.
    pub fn uses_colors(&self) -> bool {
        self.mode == BoxMode::Geometry && self.color_split
    }

    /// The lowest top a person may have in this mode, metres: `geometry_min_height_m` in
    /// geometry mode, else `min_height_m`.
    pub fn min_top_m(&self) -> f32 {
        if self.mode == BoxMode::Geometry {
            self.geometry_min_height_m
        } else {
            self.min_height_m
        }
    }

    /// Checks every field's range; the error names the field (`boxes.voxel_m must be in
    /// [0.01, 0.5] metres, got 0`). The upper bounds keep every loop short: the finder's
    /// neighbour graph stores each pair of voxels closer than `person_gap_m` (≈
    /// (`person_gap_m` / `voxel_m`)² neighbours per voxel of a surface, hence at most 10 ×
    /// `voxel_m`), and the head search reads every cell within `head_separation_m` of
    /// each top (hence `voxel_m` >= 0.01 and `head_separation_m` <= 2). Lengths beyond a room's or a person's size find nothing
    /// more: `head_separation_m = 1000` took minutes.
    ///
    /// # Errors
    /// [`PeopleError::InvalidConfig`] for the first field out of range.
    pub fn validate(&self) -> Result<(), PeopleError> {
        fn bad(field: &'static str, problem: String) -> Result<(), PeopleError> {
            Err(PeopleError::InvalidConfig { field, problem })
        }
        // (field, value, lowest, lowest allowed itself, highest), metres.
        let lengths = [
            ("voxel_m", self.voxel_m, MIN_VOXEL_M, true, MAX_VOXEL_M),
            (
                "person_gap_m",
                self.person_gap_m,
                0.0,
                false,
                MAX_PERSON_GAP_M,
            ),
            ("min_height_m", self.min_height_m, 0.0, false, MAX_HEIGHT_M),
            (
                "geometry_min_height_m",
                self.geometry_min_height_m,
                0.0,
                false,
                MAX_HEIGHT_M,
            ),
            ("max_height_m", self.max_height_m, 0.0, false, MAX_HEIGHT_M),
            ("max_bottom_m", self.max_bottom_m, 0.0, true, MAX_HEIGHT_M),
            ("max_width_m", self.max_width_m, 0.0, false, MAX_WIDTH_M),
            (
                "head_separation_m",
                self.head_separation_m,
                0.0,
                false,
                MAX_HEAD_SEPARATION_M,
            ),
            ("box_margin_m", self.box_margin_m, 0.0, true, MAX_MARGIN_M),
            (
                "ground_tol_m",
                self.ground_tol_m,
                0.0,
                false,
                MAX_GROUND_TOL_M,
            ),
            (
                "max_head_radius_m",
                self.max_head_radius_m,
                0.0,
                false,
                MAX_HEAD_RADIUS_M,
            ),
            ("max_reach_m", self.max_reach_m, 0.0, false, MAX_REACH_M),
            (
                "column_radius_m",
                self.column_radius_m,
                0.0,
                false,
                MAX_COLUMN_RADIUS_M,
            ),
        ];
        for (field, v, low, low_ok, high) in lengths {
            let above = if low_ok { v >= low } else { v > low };
            if !(v.is_finite() && above && v <= high) {
                let open = if low_ok { '[' } else { '(' };
                return bad(
                    field,
                    format!("must be in {open}{low}, {high}] metres, got {v}"),
                );
            }
        }
        if self.person_gap_m <= self.voxel_m || self.person_gap_m > MAX_GAP_VOXELS * self.voxel_m {
            return bad(
                "person_gap_m",
                format!(
                    "must be > boxes.voxel_m ({}) and at most {MAX_GAP_VOXELS} times it, got {}",
                    self.voxel_m, self.person_gap_m
                ),
            );
        }
        for (lowest, low) in [
            ("min_height_m", self.min_height_m),
            ("geometry_min_height_m", self.geometry_min_height_m),
        ] {
            if self.max_height_m <= low {
                return bad(
                    "max_height_m",
                    format!(
                        "must be a finite number > boxes.{lowest} ({low}), got {}",
                        self.max_height_m
                    ),
                );
            }
        }
        if !(self.max_ground_tilt_deg > 0.0 && self.max_ground_tilt_deg < 90.0) {
            return bad(
                "max_ground_tilt_deg",
                format!("must be in (0, 90), got {}", self.max_ground_tilt_deg),
            );
        }
        if !(0.0..=1.0).contains(&self.min_column_fill) {
            return bad(
                "min_column_fill",
                format!("must be in [0, 1], got {}", self.min_column_fill),
            );
        }
        for (field, v, max) in [
            ("min_voxels", self.min_voxels, MAX_COUNT),
            ("min_head_voxels", self.min_head_voxels, MAX_COUNT),
            (
                "ransac_iterations",
                self.ransac_iterations,
                MAX_RANSAC_ITERATIONS,
            ),
            (
                "min_voxel_points",
                self.min_voxel_points as usize,
                MAX_COUNT,
            ),
        ] {
            if !(1..=max).contains(&v) {
                return bad(field, format!("must be in [1, {max}], got {v}"));
            }
        }
        Ok(())
    }
}

/// Smallest `voxel_m`, metres: below a Kinect v2's point spacing at 2 m (≈ 3.5 mm per
/// pixel, so a 1 cm voxel holds a few points), and it bounds the head search's cells per
/// top ((2 · `head_separation_m` / `voxel_m`)²: 400² at the limits, a few seconds a frame).
pub(crate) const MIN_VOXEL_M: f32 = 0.01;
/// Largest `voxel_m`, metres: a head is ≈ 0.2 m wide; coarser voxels merge people.
pub(crate) const MAX_VOXEL_M: f32 = 0.5;
/// Largest `person_gap_m`, metres: people standing apart are farther than this.
pub(crate) const MAX_PERSON_GAP_M: f32 = 1.0;
/// Largest `person_gap_m` / `voxel_m`: the neighbour graph keeps every pair of voxels
/// closer than the gap, ≈ (gap / voxel)² per voxel of a surface; at 50 (1 cm voxels, 0.5 m
/// gap) a frame took 6 GB and over a minute. Default 2.4.
pub(crate) const MAX_GAP_VOXELS: f32 = 10.0;
/// Highest `min_height_m`, `geometry_min_height_m`, `max_height_m` and `max_bottom_m`,
/// metres: a room's height (a person 1.8 km tall is a unit error).
pub(crate) const MAX_HEIGHT_M: f32 = 3.0;
/// Largest `max_width_m`, metres: a room's width, not a person's.
pub(crate) const MAX_WIDTH_M: f32 = 5.0;
/// Largest `head_separation_m`, metres: two heads this far apart are two people.
pub(crate) const MAX_HEAD_SEPARATION_M: f32 = 2.0;
/// Largest `box_margin_m`, metres.
pub(crate) const MAX_MARGIN_M: f32 = 1.0;
/// Largest `ground_tol_m`, metres: above it, a person's feet and shins are floor.
pub(crate) const MAX_GROUND_TOL_M: f32 = 0.5;
/// Largest `max_head_radius_m`, metres: twice a head's radius and more.
pub(crate) const MAX_HEAD_RADIUS_M: f32 = 0.5;
/// Largest `max_reach_m`, metres: farther than any arm reaches.
pub(crate) const MAX_REACH_M: f32 = 3.0;
/// Largest `column_radius_m`, metres.
pub(crate) const MAX_COLUMN_RADIUS_M: f32 = 1.0;
/// Largest count (`min_voxels`, `min_head_voxels`, `min_voxel_points`): more than any
/// frame holds.
pub(crate) const MAX_COUNT: usize = 1_000_000;
/// Largest `ransac_iterations`: 100 000 take ≈ 0.6 s a frame.
pub(crate) const MAX_RANSAC_ITERATIONS: usize = 100_000;

#[cfg(test)]
mod tests {
    use super::*;
    use serde::de::value::{Error, MapDeserializer};

    /// The configuration read from the boolean keys `fields` (the others default).
    fn from_bools(fields: &[(&'static str, bool)]) -> Result<BoxesConfig, Error> {
        BoxesConfig::deserialize(MapDeserializer::new(fields.iter().copied()))
    }

    #[test]
    fn the_color_split_is_read_under_both_spellings() {
        assert!(BoxesConfig::default().color_split);
        for key in ["color_split", "colour_split"] {
            let cfg = from_bools(&[(key, false)]).expect(key);
            assert!(!cfg.color_split, "{key}");
            let geometry = BoxesConfig {
                mode: BoxMode::Geometry,
                ..cfg
            };
            assert!(!geometry.uses_colors(), "{key}");
        }
        // Unknown keys are still refused.
        assert!(from_bools(&[("colur_split", false)]).is_err());
    }

    /// Values that made the finder hang or take gigabytes are refused, naming the field
    /// and its range.
    #[test]
    fn ranges_bound_every_loop() {
        let err = |cfg: BoxesConfig| cfg.validate().expect_err("invalid").to_string();
        let d = BoxesConfig::default;
        assert_eq!(
            err(BoxesConfig {
                head_separation_m: 1000.0,
                ..d()
            }),
            "boxes.head_separation_m must be in (0, 2] metres, got 1000"
        );
        assert_eq!(
            err(BoxesConfig {
                voxel_m: 0.001,
                ..d()
            }),
            "boxes.voxel_m must be in [0.01, 0.5] metres, got 0.001"
        );
        assert_eq!(
            err(BoxesConfig {
                voxel_m: 0.01,
                person_gap_m: 0.5,
                ..d()
            }),
            "boxes.person_gap_m must be > boxes.voxel_m (0.01) and at most 10 times it, got 0.5"
        );
        assert_eq!(
            err(BoxesConfig {
                max_height_m: 1800.0,
                ..d()
            }),
            "boxes.max_height_m must be in (0, 3] metres, got 1800"
        );
        assert_eq!(
            err(BoxesConfig {
                ransac_iterations: 10_000_000,
                ..d()
            }),
            "boxes.ransac_iterations must be in [1, 100000], got 10000000"
        );
        assert!(
            err(BoxesConfig {
                max_reach_m: f32::INFINITY,
                ..d()
            })
            .starts_with("boxes.max_reach_m must be in (0, 3] metres")
        );
        // The limits themselves are valid.
        let limits = BoxesConfig {
            voxel_m: MIN_VOXEL_M,
            person_gap_m: MAX_GAP_VOXELS * MIN_VOXEL_M,
            head_separation_m: MAX_HEAD_SEPARATION_M,
            max_height_m: MAX_HEIGHT_M,
            ransac_iterations: MAX_RANSAC_ITERATIONS,
            ..d()
        };
        assert!(limits.validate().is_ok(), "{:?}", limits.validate());
    }

    #[test]
    fn geometry_mode_has_its_own_lowest_top_checked_against_the_highest() {
        let labels = BoxesConfig::default();
        let geometry = BoxesConfig {
            mode: BoxMode::Geometry,
            ..BoxesConfig::default()
        };
        assert_eq!(labels.min_top_m(), labels.min_height_m);
        assert_eq!(geometry.min_top_m(), geometry.geometry_min_height_m);
        assert!(geometry.validate().is_ok());
        let err = |cfg: BoxesConfig| cfg.validate().expect_err("invalid").to_string();
        assert_eq!(
            err(BoxesConfig {
                geometry_min_height_m: 0.0,
                ..geometry.clone()
            }),
            "boxes.geometry_min_height_m must be in (0, 3] metres, got 0"
        );
        assert_eq!(
            err(BoxesConfig {
                geometry_min_height_m: 2.5,
                ..geometry
            }),
            "boxes.max_height_m must be a finite number > boxes.geometry_min_height_m (2.5), got 2.3"
        );
    }
}
