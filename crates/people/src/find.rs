//! The two box finders (ALGORITHM.md §4), one module per concern:
//! - [`labels`]: labels mode (clusters of body-labelled voxels split between heads);
//! - geometry mode: [`geometry`] chains [`ground`] (the RANSAC ground plane), [`heads`]
//!   (head-height maxima over a body's column) and [`split`] (a cluster divided between
//!   its people and what no person can own), with [`color`] (the points' colours in
//!   that split);
//! - [`candidates`]: what both share — clusters, person candidates, the size filters and
//!   the box fit.
//!
//! Dependencies run one way (`a → b`: `a` uses `b`): `geometry` → `split` → `heads` →
//! `candidates` → `ground`; `geometry` and `split` → `color` → `ground`; `labels` →
//! `candidates`, `ground`.

mod candidates;
mod color;
mod geometry;
pub(crate) mod ground;
mod heads;
mod labels;
mod split;

use crate::config::{BoxMode, BoxesConfig, PeopleError};
use bodyseg_core::{LabeledCloud, PersonBoxes};

/// Finds the person boxes of `cloud` (world frame, z up) as `cfg.mode` says; ids are
/// 0, 1, ... in order of each person's first voxel (deterministic).
///
/// # Errors
/// [`PeopleError::InvalidConfig`] when `cfg` is out of range, [`PeopleError::InvalidCloud`]
/// when the cloud is inconsistent, [`PeopleError::FileMode`] for `mode = "file"`.
pub fn find_boxes(cloud: &LabeledCloud, cfg: &BoxesConfig) -> Result<PersonBoxes, PeopleError> {
    cfg.validate()?;
    cloud.validate()?;
    let boxes = match cfg.mode {
        BoxMode::Labels => labels::labels_mode(cloud, cfg),
        BoxMode::Geometry => geometry::geometry_mode(
            &cloud.positions_m,
            cloud.colors.as_deref().filter(|_| cfg.uses_colors()),
            cfg,
        ),
        BoxMode::File => return Err(PeopleError::FileMode),
    };
    Ok(PersonBoxes {
        frame: String::new(),
        boxes,
        world_from_cloud: None,
    })
}
