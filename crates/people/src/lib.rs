//! bodyseg-people: person boxes, finding each person in the fused cloud.
//!
//! Place in the pipeline: `LabeledCloud → PersonBoxes` (ALGORITHM.md §4), between the
//! label projection (bodyseg-project) and the refinement (bodyseg-refine), which works
//! inside each box. [`find_boxes`] runs one of two finders, chosen by
//! [`BoxesConfig::mode`]:
//! - **labels** (default): points with a body label (1–6), except those on the floor (a
//!   parser's feet bleed onto it), are averaged into voxels (`voxel_m`; voxels with
//!   fewer than `min_voxel_points` points are dropped) and clustered (Euclidean, gap `person_gap_m`); a cluster holding two or
//!   more separate heads (or, failing that, torsos) is split between them along the voxel
//!   graph (multi-source Dijkstra; a step between parts not joined in a body, such as a
//!   hand on someone's head, costs an arm's length more), so two people touching hands
//!   get two boxes and an arm reaching someone stays its owner's; clusters
//!   too small, too low, too tall, floating or too wide are dropped.
//! - **geometry** (no labels): a RANSAC ground plane (Fischler & Bolles 1981) is removed
//!   with sparse voxels (flying pixels), the rest clustered; heads are maxima of the
//!   top-view height map at least `geometry_min_height_m` high and `head_separation_m` apart
//!   (closer, down to 0.25 m, when the lower one is a separate peak: two heads leaning
//!   together) that are as large as a head (not a hand held out) and compact (a head, not
//!   a robot arm's joint; only what is connected to the top within a head's height
//!   counts, so a neighbour's shoulder or hand beside the head does not) and have a
//!   continuous column of points below them down to the ground (the lower legs within a
//!   leg's reach: a crouch), in the spirit of the ground-based people detector of Munaro et al. (ICRA
//!   2012, "Tracking people within groups with RGB-D data", without its HOG classifier);
//!   a cluster is split along the voxel graph (multi-source Dijkstra; leaving a head
//!   sideways at its height costs a contact, as only a hand or an arm touches a head
//!   there) between its heads and what no person can own (voxels beyond arm's reach of every head, or low and
//!   beyond the legs: a robot's pedestal, a box), so a robot arm touching a person is
//!   claimed from its base (with the points' colours, what is nobody's spreads slowly into
//!   a person's colours, and each person into colours only another person wears: a sleeve
//!   stays its owner's); each person keeps what lies within arm's reach of the head
//!   (below the hips: within a leg's reach), and the same size filters apply.
//!
//! The `file` mode (boxes read from `boxes/<stem>.json`) is the pipeline's: it reads files.
//!
//! A box is the person's points' horizontal extent along their principal horizontal axis
//! (its yaw; labels mode takes the axis of the torso-labelled voxels alone, as the trunk
//! follows the facing direction whichever way the arms point; geometry mode that of the
//! trunk, hips to chest beside the head, or for two people of one cluster whose heads are
//! closer than 0.6 m the line between their heads) plus `box_margin_m` on each
//! side, from the floor up to the top plus `box_margin_m` — the shape of bodyseg-synth's
//! true boxes, which are aligned with the facing direction. [`box_iou`] scores a box
//! against another exactly, [`match_boxes`] a frame's found boxes against its true ones.
//!
//! # Conventions
//! - Input clouds are in a z-up frame in metres (bodyseg's world frame). Labels mode takes
//!   the floor at z = 0; geometry mode fits the ground plane (any height, tilted up to
//!   `max_ground_tilt_deg`).
//! - Boxes: world frame, metres, yaw about +z in radians (bodyseg-core's [`PersonBox`]).
//! - Deterministic: the same cloud gives the same boxes (fixed RANSAC seed; ids in order
//!   of each person's first voxel, voxels in order of their first point).

mod config;
mod find;
mod fit;
pub mod floor;
mod matching;
mod voxel;

pub use config::{BoxMode, BoxesConfig, PeopleError};
pub use find::find_boxes;
pub use fit::box_iou;
pub use floor::{Floor, FloorHint, FloorHintError, FloorSource, Up, find_floor};
pub use matching::{FrameMatch, MATCH_IOU, match_boxes};

#[doc(no_inline)]
pub use bodyseg_core::{PersonBox, PersonBoxes};
