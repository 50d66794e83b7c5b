//! `RefineConfig`: every knob of the refinement, with units and defaults.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// Errors of the refinement stage.
#[derive(Debug, thiserror::Error)]
pub enum RefineError {
    /// A configuration field is out of range.
    #[error("refine.{field} {problem}")]
    InvalidConfig {
        /// The field's name.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// The input cloud is inconsistent (NaN coordinate, arrays of different lengths).
    /// The cause is in the message and deliberately not exposed as `source()`, so an
    /// error chain (`{:#}`) prints it once.
    #[error("input cloud: {0}")]
    InvalidCloud(bodyseg_core::CloudError),
    /// A person box is unusable.
    #[error("person box: {reason}")]
    InvalidBox {
        /// What is wrong with it.
        reason: String,
    },
    /// `vote = "multi_view"` without the vote's labels, or with a list of another length.
    #[error(
        "refine.vote = \"multi_view\" needs the multi-view vote's labels, one per point ({got} for {want} points): only bodyseg run / convert, which have every camera's images, can run it"
    )]
    VoteLabels {
        /// Labels given (0 when none).
        got: usize,
        /// Points of the cloud.
        want: usize,
    },
    /// `foreign_color_density` > 0 on a cloud without camera colors.
    #[error(
        "refine.foreign_color_density = {density} needs the points' camera colors, and this cloud has none (a PLY's red, green, blue are read unless bodyseg wrote them as its class palette): set it to 0, or give a cloud with camera colors"
    )]
    NoColors {
        /// The configured density.
        density: f32,
    },
    /// A length that sets a grid's cells is finer than the cloud's coordinates resolve.
    #[error(
        "refine.{field} = {value_m} m is finer than this cloud's coordinates resolve: the cloud's extent is {extent_m} m, over which f32 coordinates step by up to {min_m} m (extent / 2^23); use at least that"
    )]
    TooFine {
        /// The field's name.
        field: &'static str,
        /// Its value, metres.
        value_m: f32,
        /// The cloud's largest extent along an axis, metres.
        extent_m: f32,
        /// The smallest value this cloud allows, metres.
        min_m: f32,
    },
    /// Label probabilities given, but not one per point.
    #[error("label probabilities: {got} for {want} points (one per point expected)")]
    LabelProbs {
        /// Probabilities given.
        got: usize,
        /// Points of the cloud.
        want: usize,
    },
}

impl From<bodyseg_core::CloudError> for RefineError {
    fn from(e: bodyseg_core::CloudError) -> Self {
        RefineError::InvalidCloud(e)
    }
}

/// How the best body tree is searched (ALGORITHM.md §5.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TreeMode {
    /// The paper's reading: root = largest torso cluster, slots filled breadth-first with
    /// the largest adjacent unused cluster of the slot's label.
    #[default]
    Paper,
    /// The valid tree that covers the most points: every torso cluster is tried as the
    /// root, and the head, the two arm chains (upper arm, lower arm) and the two leg chains
    /// are chosen together to maximise the points of the tree's nodes, instead of filling
    /// the slots one by one with the largest cluster.
    Coverage,
}

/// How the graph's *inside* and *intersect* edges are measured (ALGORITHM.md §5.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraphMode {
    /// The paper's bounding spheres (centroid and radius).
    #[default]
    Spheres,
    /// Actual point gaps: two clusters touch when a point of one lies within
    /// `contact_gap_m` of a point of the other; A lies inside B when they touch, A is no
    /// larger and at least `contact_inside_fraction` of A's points lie within
    /// `contact_gap_m` of B's.
    Contact,
}

/// How the N step relabels noise points (ALGORITHM.md §5.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseMode {
    /// The paper: the label of the nearest clustered point.
    #[default]
    Nearest,
    /// A vote of the `noise_k` nearest clustered points within `eps_m`, each weighted by
    /// its distance, plus the point's own (parser) label weighted by `noise_self_weight`;
    /// with no clustered point within `eps_m`, its own label (unknown: the nearest
    /// clustered point's).
    Weighted,
    /// As `weighted`, with the parser's probability of each point's label (the softmax of
    /// that label at the point's color pixel): doubtful labels (`noise_doubt_ratio`) are
    /// left out of the clustering and relabelled by N, and the own label counts
    /// `noise_self_weight` × its probability, so a label the parser was unsure of yields to
    /// its neighbours and a sure one holds. The
    /// probabilities come from the caller ([`crate::PointEvidence::label_probs`]); a point
    /// without one (recorded label images carry none, a label changed by the multi-view
    /// vote) counts 1, as in `weighted`.
    Probability,
}

/// Whether the multi-view consistency vote runs before the steps (the paper's "future
/// work"; ALGORITHM.md §3 "Multi-view" and §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VoteMode {
    /// The paper: the steps start from the projected labels.
    #[default]
    Off,
    /// Every configuration but Reference starts from the labels of the projection's
    /// multi-view vote (a point seen by several color cameras takes the label most of
    /// them agree on; `bodyseg_project::FrameProjector::vote_labels`), which the caller
    /// hands to [`crate::refine_variants_with`]. Reference stays the projected labels.
    MultiView,
}

/// Which refinement steps run: the paper's five configurations and the rest of the
/// combinations. Written as `"reference"` or letters joined by `-`: `"M-R-N"`, `"m,n"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Steps {
    /// The projected cloud untouched: no boxes, no outlier removal, no steps.
    Reference,
    /// Per-person processing and the fuse, with the named steps.
    Run {
        /// M: merge clusters lying inside a cluster of another label.
        merge: bool,
        /// R: remove clusters not connected to the best body tree.
        remove: bool,
        /// N: noise points take the label of the nearest clustered point.
        noise: bool,
    },
}

impl Steps {
    /// The whole algorithm, the default.
    pub const MRN: Steps = Steps::Run {
        merge: true,
        remove: true,
        noise: true,
    };

    /// The five configurations of the paper's tables, in table order.
    pub const PAPER: [Steps; 5] = [
        Steps::Reference,
        Steps::Run {
            merge: true,
            remove: false,
            noise: false,
        },
        Steps::Run {
            merge: false,
            remove: false,
            noise: true,
        },
        Steps::Run {
            merge: true,
            remove: false,
            noise: true,
        },
        Steps::MRN,
    ];
}

impl Steps {
    /// True when N runs (never in `Reference`).
    pub fn noise(&self) -> bool {
        matches!(self, Steps::Run { noise: true, .. })
    }
}

impl Default for Steps {
    fn default() -> Self {
        Steps::MRN
    }
}

impl fmt::Display for Steps {
    /// The paper's names: `Reference`, `M`, `N`, `M-N`, `M-R-N`; `none` for no step.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Steps::Reference => f.write_str("Reference"),
            Steps::Run {
                merge,
                remove,
                noise,
            } => {
                let names: Vec<&str> = [(merge, "M"), (remove, "R"), (noise, "N")]
                    .into_iter()
                    .filter_map(|(on, n)| on.then_some(n))
                    .collect();
                if names.is_empty() {
                    f.write_str("none")
                } else {
                    f.write_str(&names.join("-"))
                }
            }
        }
    }
}

impl FromStr for Steps {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        if t == "reference" || t == "ref" {
            return Ok(Steps::Reference);
        }
        if t == "none" {
            return Ok(Steps::Run {
                merge: false,
                remove: false,
                noise: false,
            });
        }
        let (mut merge, mut remove, mut noise) = (false, false, false);
        for part in t.split(['-', ',', ' ']).filter(|p| !p.is_empty()) {
            match part {
                "m" | "merge" => merge = true,
                "r" | "remove" => remove = true,
                "n" | "noise" => noise = true,
                other => {
                    return Err(format!(
                        "unknown step '{other}' in '{s}': use 'reference', 'none' or letters m, r, n joined by '-' (e.g. M-R-N)"
                    ));
                }
            }
        }
        if !(merge || remove || noise) {
            return Err(format!("no step named in '{s}'"));
        }
        Ok(Steps::Run {
            merge,
            remove,
            noise,
        })
    }
}

impl Serialize for Steps {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for Steps {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// Configuration of the clustering refinement (ALGORITHM.md §5). TOML section `[refine]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RefineConfig {
    /// DBSCAN radius, metres. Default 0.05 (the paper's value on Kinect data).
    pub eps_m: f32,
    /// DBSCAN core threshold: points within eps, the point itself included. Default 40.
    pub min_points: usize,
    /// Distance added between points of different labels, metres. Default `inf`: labels
    /// never mix, DBSCAN runs per label.
    pub label_penalty_m: f32,
    /// Slack of the "inside" test, a fraction of the container's radius (`graph =
    /// "spheres"` only; the contact graph uses `contact_inside_fraction`). Default 0.
    pub inside_tolerance: f32,
    /// Best body tree search: `paper` (default) or `coverage`.
    pub tree: TreeMode,
    /// How clusters are judged adjacent / inside one another: `spheres` (default, the
    /// paper) or `contact` (actual point gaps, `contact_gap_m`).
    pub graph: GraphMode,
    /// Contact mode: two clusters touch when their closest points are at most this far
    /// apart, metres. Default 0.1 (twice the default `eps_m`: bands of unknown points along
    /// depth edges separate touching parts by a few cm; 0.05 cut real hands off the body
    /// on the tuning recording, handover seed 7).
    pub contact_gap_m: f32,
    /// Contact mode: cluster A lies inside a cluster B no smaller than A when at least this
    /// fraction of A's points have a point of B within `contact_gap_m` (A is immersed in
    /// B, e.g. one camera's other label for a surface the others see). In (0, 1].
    /// Default 0.9.
    pub contact_inside_fraction: f32,
    /// How N relabels noise: `nearest` (default, the paper), `weighted` or `probability`.
    pub noise: NoiseMode,
    /// `noise = "weighted"` or `"probability"` only: the number of nearest clustered
    /// points that vote. Default 16.
    pub noise_k: usize,

    /// `noise = "weighted"` or `"probability"` only: weight of the point's own label, in
    /// voters lying on the point (a voter at distance d weighs `1 / (1 + (d / eps_m)²)`);
    /// 0 = ignore it and give a point with no voter the nearest clustered point's label, as
    /// the paper. Unknown never votes. With `noise = "probability"` it is scaled by the
    /// parser's probability of the point's label. Default 1.0.
    pub noise_self_weight: f32,
    /// `noise = "probability"`: a label is doubtful when its parser probability is below
    /// this fraction of the median probability of that label over the person's points
    /// ([`crate::doubtful_as_unknown`]); a doubtful point takes no part in the clustering —
    /// it is noise, and N relabels it by the vote of the sure points around it (its own
    /// label weighing `noise_self_weight` × its probability) — so M and R work on labels
    /// the parser was sure of. Steps without N leave it its own label. In [0, 1); 0 = off.
    /// Default 0.7 (chosen with the bundled model on recordings outside the benchmark; 1.0
    /// makes half of every part doubtful and R then cuts limbs off).
    pub noise_doubt_ratio: f32,
    /// `noise = "probability"`: the doubtful points are relabelled by a wider vote, of
    /// about `noise_doubt_k` clustered points within this distance, metres
    /// ([`crate::reassign_doubted_wide`]); 0 = as the other noise points (`noise_k` within
    /// `eps_m`). Default 0. The improved configuration uses 0.15 with `noise_doubt_k` 256:
    /// a doubted point lies mostly on a strip along a part boundary, and the sure points
    /// across a limb's width say better which side it belongs to than the few nearest.
    pub noise_doubt_radius_m: f32,
    /// `noise = "probability"` with `noise_doubt_radius_m > 0`: about how many clustered
    /// points vote for a doubtful point. Default 256.
    pub noise_doubt_k: usize,
    /// R: a cluster joined to the body tree through noise points the parser labelled body
    /// (doubted labels, sparse DBSCAN noise; cells of `eps_m` touching) is not cut off
    /// ([`crate::restore_bridged`]). Default false (the paper: only the clusters' own
    /// contacts count).
    pub remove_through_noise: bool,
    /// `off` (default, the paper) or `multi_view`: the steps start from the labels of
    /// the multi-view consistency vote instead of the projected ones (Reference is the
    /// projected labels either way). Needs the projection's depth and label images, so
    /// only `bodyseg run` / `convert` can run it, not `bodyseg refine` on a cloud file.
    pub vote: VoteMode,
    /// After the steps, lower-leg points at most this high above the floor (the median
    /// height of the person's lowest background points) become background, metres; 0 =
    /// off (default, the paper). Not run in Reference ([`crate::floor::floor_contact`]).
    pub floor_contact_m: f32,
    /// After the steps (and floor contact), every body-labelled point takes the body label
    /// most body-labelled points within this radius carry, metres ([`crate::smooth_labels`]:
    /// islands of another part too small for M, ragged part boundaries); 0 = off (default,
    /// the paper). Not run in Reference.
    pub smooth_radius_m: f32,
    /// Steps to run: `reference`, `M`, `N`, `M-N`, `M-R-N` (default) or any other mix.
    pub steps: Steps,
    /// Keep the labels of body points outside every box (default false: they are outliers
    /// and become background, as in the paper).
    pub keep_outside_boxes: bool,
    /// Let background clusters act as containers in M, except for lower-leg clusters,
    /// which the floor always holds (default false: a floor's bounding sphere swallows leg
    /// fragments). The improved configuration sets it with the contact graph: a body
    /// label on a patch of background surface (a wall, the robot, the floor beside a
    /// foot) goes to the background.
    pub merge_into_background: bool,
    /// After the steps, an upper- or lower-arm point whose color is rare on the person's
    /// head and torso — less than this fraction of either's points share its chromaticity
    /// (±0.02) — is an object the person holds or touches (a parcel, a robot link), not an
    /// arm: background ([`crate::color::drop_foreign_arms`]). Needs the cloud's camera
    /// colors. In [0, 1); 0 = off (default, the paper). Gloves and sleeves of another
    /// color than the shirt are lost with it.
    #[serde(alias = "foreign_colour_density")]
    pub foreign_color_density: f32,
}

impl Default for RefineConfig {
    fn default() -> Self {
        RefineConfig {
            eps_m: 0.05,
            min_points: 40,
            label_penalty_m: f32::INFINITY,
            inside_tolerance: 0.0,
            tree: TreeMode::Paper,
            graph: GraphMode::Spheres,
            contact_gap_m: 0.1,
            contact_inside_fraction: 0.9,
            noise: NoiseMode::Nearest,
            noise_k: 16,
            noise_self_weight: 1.0,
            noise_doubt_ratio: 0.7,
            noise_doubt_radius_m: 0.0,
            noise_doubt_k: 256,
            remove_through_noise: false,
            vote: VoteMode::Off,
            floor_contact_m: 0.0,
            smooth_radius_m: 0.0,
            steps: Steps::MRN,
            keep_outside_boxes: false,
            merge_into_background: false,
            foreign_color_density: 0.0,
        }
    }
}

/// Largest radius or gap of the refinement, metres: every search radius is about a body
/// part (eps 5 cm, contact 10 cm, votes 15 cm), and a person fits in 2.5 m; a radius of
/// kilometres is a typo, and it would make the grids' searches walk every cell.
pub const MAX_RADIUS_M: f32 = 5.0;

/// Largest count of the refinement (`min_points`, `noise_doubt_k`): far beyond any
/// neighbourhood of a person's points, so that a typo fails at load.
pub const MAX_COUNT: usize = 1_000_000;

/// Largest `noise_k`: the narrow vote keeps its voters in a sorted list (insertions cost
/// up to `noise_k` each), and 1024 points within eps is far beyond any cloud's density.
pub const MAX_NOISE_K: usize = 1024;

/// A grid length must be at least the cloud's extent over this (2^23: the steps of f32
/// coordinates across that extent).
const RESOLUTION_STEPS: f32 = 8_388_608.0;

impl RefineConfig {
    /// Checks every field's range; the error names the field.
    pub fn validate(&self) -> Result<(), RefineError> {
        let bad = |field, problem: String| Err(RefineError::InvalidConfig { field, problem });
        let radius = |field, v: f32, zero_ok: bool| {
            let low_ok = if zero_ok { v >= 0.0 } else { v > 0.0 };
            if v.is_finite() && low_ok && v <= MAX_RADIUS_M {
                Ok(())
            } else {
                let low = if zero_ok { "[0" } else { "(0" };
                bad(
                    field,
                    format!("must be in {low}, {MAX_RADIUS_M}] metres, got {v}"),
                )
            }
        };
        let count = |field, v: usize, max: usize| {
            if (1..=max).contains(&v) {
                Ok(())
            } else {
                bad(field, format!("must be in [1, {max}], got {v}"))
            }
        };
        let non_negative = |field, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                bad(field, format!("must be a finite number >= 0, got {v}"))
            }
        };
        let below_one = |field, v: f32| {
            if (0.0..1.0).contains(&v) {
                Ok(())
            } else {
                bad(field, format!("must be in [0, 1), got {v}"))
            }
        };
        radius("eps_m", self.eps_m, false)?;
        count("min_points", self.min_points, MAX_COUNT)?;
        if self.label_penalty_m.is_nan() || self.label_penalty_m < 0.0 {
            return bad(
                "label_penalty_m",
                format!(
                    "must be >= 0 (inf keeps labels apart), got {}",
                    self.label_penalty_m
                ),
            );
        }
        non_negative("inside_tolerance", self.inside_tolerance)?;
        radius("contact_gap_m", self.contact_gap_m, false)?;
        if !(self.contact_inside_fraction > 0.0 && self.contact_inside_fraction <= 1.0) {
            return bad(
                "contact_inside_fraction",
                format!("must be in (0, 1], got {}", self.contact_inside_fraction),
            );
        }
        count("noise_k", self.noise_k, MAX_NOISE_K)?;
        non_negative("noise_self_weight", self.noise_self_weight)?;
        below_one("noise_doubt_ratio", self.noise_doubt_ratio)?;
        radius("noise_doubt_radius_m", self.noise_doubt_radius_m, true)?;
        count("noise_doubt_k", self.noise_doubt_k, MAX_COUNT)?;
        below_one("foreign_color_density", self.foreign_color_density)?;
        radius("floor_contact_m", self.floor_contact_m, true)?;
        radius("smooth_radius_m", self.smooth_radius_m, true)?;
        Ok(())
    }

    /// Checks the lengths that set the size of a grid's cells against a cloud whose
    /// largest extent along an axis is `extent_m` (after [`RefineConfig::validate`]): each
    /// in use must be at least `extent_m / 2^23`, the step of f32 coordinates across that
    /// extent. Below it the neighbourhoods cannot be told apart from rounding, and the
    /// grids would need more cells per axis than their keys hold.
    pub fn validate_for_extent(&self, extent_m: f32) -> Result<(), RefineError> {
        let min_m = extent_m / RESOLUTION_STEPS;
        let lengths = [
            ("eps_m", self.eps_m),
            (
                "contact_gap_m",
                if self.graph == GraphMode::Contact {
                    self.contact_gap_m
                } else {
                    f32::INFINITY
                },
            ),
            (
                "noise_doubt_radius_m",
                if self.noise == NoiseMode::Probability && self.noise_doubt_radius_m > 0.0 {
                    self.noise_doubt_radius_m
                } else {
                    f32::INFINITY
                },
            ),
            (
                "smooth_radius_m",
                if self.smooth_radius_m > 0.0 {
                    self.smooth_radius_m
                } else {
                    f32::INFINITY
                },
            ),
        ];
        match lengths.into_iter().find(|&(_, v)| v < min_m) {
            Some((field, value_m)) => Err(RefineError::TooFine {
                field,
                value_m,
                extent_m,
                min_m,
            }),
            None => Ok(()),
        }
    }

    /// The DBSCAN parameters of this configuration.
    pub fn dbscan_params(&self) -> crate::DbscanParams {
        crate::DbscanParams {
            eps_m: self.eps_m,
            min_points: self.min_points,
            label_penalty_m: self.label_penalty_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_parse_and_print_the_papers_names() {
        for s in Steps::PAPER {
            assert_eq!(s.to_string().parse::<Steps>(), Ok(s));
        }
        assert_eq!("m,r,n".parse::<Steps>(), Ok(Steps::MRN));
        assert_eq!(Steps::PAPER[3].to_string(), "M-N");
        assert!("m-x".parse::<Steps>().is_err());
        assert!("".parse::<Steps>().is_err());
    }

    #[test]
    fn the_old_spelling_of_foreign_color_density_still_reads() {
        let old: RefineConfig = toml::from_str("foreign_colour_density = 0.02").unwrap_or_default();
        let new: RefineConfig = toml::from_str("foreign_color_density = 0.03").unwrap_or_default();
        assert_eq!(old.foreign_color_density, 0.02);
        assert_eq!(new.foreign_color_density, 0.03);
        // Written with the new name.
        let text = toml::to_string(&old).unwrap_or_default();
        assert!(text.contains("foreign_color_density = 0.02"), "{text}");
    }

    #[test]
    fn validation_names_the_field() {
        let c = RefineConfig {
            eps_m: -1.0,
            ..Default::default()
        };
        let e = c
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.starts_with("refine.eps_m must be"), "{e}");
        let c = RefineConfig {
            min_points: 0,
            ..Default::default()
        };
        assert!(c.validate().is_err());
        let message = |c: RefineConfig| {
            c.validate()
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default()
        };
        let e = message(RefineConfig {
            contact_gap_m: 0.0,
            ..Default::default()
        });
        assert!(e.starts_with("refine.contact_gap_m must be"), "{e}");
        let e = message(RefineConfig {
            noise_k: 0,
            ..Default::default()
        });
        assert!(e.starts_with("refine.noise_k must be"), "{e}");
        let e = message(RefineConfig {
            noise_self_weight: f32::NAN,
            ..Default::default()
        });
        assert!(e.starts_with("refine.noise_self_weight must be"), "{e}");
        // The shared range checks name each of their fields.
        for (field, c) in [
            (
                "inside_tolerance",
                RefineConfig {
                    inside_tolerance: -0.1,
                    ..Default::default()
                },
            ),
            (
                "noise_doubt_ratio",
                RefineConfig {
                    noise_doubt_ratio: 1.0,
                    ..Default::default()
                },
            ),
            (
                "noise_doubt_radius_m",
                RefineConfig {
                    noise_doubt_radius_m: f32::INFINITY,
                    ..Default::default()
                },
            ),
            (
                "foreign_color_density",
                RefineConfig {
                    foreign_color_density: -0.01,
                    ..Default::default()
                },
            ),
            (
                "floor_contact_m",
                RefineConfig {
                    floor_contact_m: -1.0,
                    ..Default::default()
                },
            ),
            (
                "smooth_radius_m",
                RefineConfig {
                    smooth_radius_m: f32::NAN,
                    ..Default::default()
                },
            ),
        ] {
            let e = message(c);
            assert!(
                e.starts_with(&format!("refine.{field} must be")),
                "{field}: {e}"
            );
        }
        assert!(RefineConfig::default().validate().is_ok());
    }
}
