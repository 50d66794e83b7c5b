//! The world frame of a cloud given as a file (`boxes --cloud`, `import cloud`): its floor
//! found in any orientation ([`bodyseg_people::find_floor`]) or given (`--ground`,
//! `--up`), and what to tell the user when there is none, or no person.

use crate::stage::Stage;
use bodyseg_core::LabeledCloud;
use bodyseg_core::math::{RigidTransform, Vec3};
use bodyseg_people::{Floor, FloorHint, FloorSource};
use std::time::Instant;

// The plausible median distances are the sanity checks' (one range for every warning
// about a cloud's unit).
use crate::sanity::{
    MAX_MEDIAN_DISTANCE_M as MAX_PLAUSIBLE_MEDIAN_M,
    MIN_MEDIAN_DISTANCE_M as MIN_PLAUSIBLE_MEDIAN_M,
};

/// Where a cloud's world frame comes from.
pub(crate) struct CloudFrame {
    /// The floor, found or given; `None` when none was found.
    pub floor: Option<Floor>,
    /// The transform into the floor's world frame (z up, floor at z = 0); `None` when the
    /// cloud's own frame is used: it is z up already (its floor found within
    /// `max_tilt_deg` of level), or no floor was found.
    pub world_from_cloud: Option<RigidTransform>,
    /// The stage line ("floor").
    pub stage: Stage,
}

/// Finds (or takes) the floor of `positions` (the cloud's frame, metres) and decides the
/// frame boxes are found in. A floor found by the search within `max_tilt_deg` of the
/// cloud's +z leaves the cloud as it is (bodyseg's own clouds are z up: their boxes stay
/// exactly what they were); a given floor (`--ground`, `--up`) or a tilted one gives the
/// floor's frame. No floor found: a warning naming the likely cause; the cloud as it is.
/// `what` names the cloud in messages.
///
/// # Errors
/// `--ground` is not a plane.
pub(crate) fn cloud_frame(
    positions: &[Vec3],
    hint: &FloorHint,
    max_tilt_deg: f32,
    what: &str,
) -> anyhow::Result<CloudFrame> {
    let start = Instant::now();
    let floor = bodyseg_people::find_floor(positions, hint)
        .map_err(|e| anyhow::anyhow!("--ground: {e}"))?;
    let Some(floor) = floor else {
        tracing::warn!(
            "{what}: no floor found (no large plane that the points stand on); likely cause: {}. \
             Boxes are looked for with the cloud's z as up; give the floor with --ground a,b,c,d \
             or --up AXIS",
            likely_cause(positions, false)
        );
        return Ok(CloudFrame {
            floor: None,
            world_from_cloud: None,
            stage: Stage::new(
                "floor",
                start.elapsed(),
                "none found: the cloud's z is up".into(),
            ),
        });
    };
    let given = hint.ground.is_some() || hint.up.is_some();
    let level = floor.tilt_from_z_deg() <= max_tilt_deg;
    let world_from_cloud = (given || !level).then(|| floor.world_from_cloud());
    let n = floor.normal;
    let how = match floor.source {
        FloorSource::Found => format!("found, {} voxels", floor.support_voxels),
        FloorSource::Given => "given (--ground)".into(),
        FloorSource::Lowest => "no plane along --up: the lowest points' level".into(),
    };
    let frame = if world_from_cloud.is_some() {
        "boxes in the floor's frame (z up, floor at z = 0)"
    } else {
        "the cloud's z is up: boxes in its frame"
    };
    let detail = format!(
        "normal ({:.3}, {:.3}, {:.3}) in the cloud's frame, {:.2} m from its origin ({how}); {frame}",
        n[0], n[1], n[2], floor.offset_m
    );
    Ok(CloudFrame {
        floor: Some(floor),
        world_from_cloud,
        stage: Stage::new("floor", start.elapsed(), detail),
    })
}

/// `cloud` with its positions mapped by `t` (labels, colours, origins kept).
pub(crate) fn transformed(cloud: &LabeledCloud, t: &RigidTransform) -> LabeledCloud {
    LabeledCloud {
        positions_m: cloud.positions_m.iter().map(|&p| t.apply(p)).collect(),
        ..cloud.clone()
    }
}

/// The likely reason a cloud shows no floor or no person, for warnings: an implausible
/// unit (the median distance from the origin), else no floor in view, else people cut
/// off or not standing on the floor found.
pub(crate) fn likely_cause(positions: &[Vec3], floor_found: bool) -> String {
    let mut d: Vec<f32> = positions
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
        .collect();
    let median = if d.is_empty() {
        None
    } else {
        let k = d.len() / 2;
        Some(*d.select_nth_unstable_by(k, f32::total_cmp).1)
    };
    match median {
        None => "the cloud has no points".into(),
        Some(m) if m > MAX_PLAUSIBLE_MEDIAN_M => format!(
            "the median point is {m:.0} m from the origin: a cloud in millimetres (or \
             centimetres) instead of metres? bodyseg reads metres"
        ),
        Some(m) if m < MIN_PLAUSIBLE_MEDIAN_M => format!(
            "the median point is {m:.3} m from the origin: a cloud in a unit larger than \
             metres, or no room around the people?"
        ),
        Some(_) if !floor_found => "a camera's view with no floor in it (people seen above \
             their feet), or too few points on the floor"
            .into(),
        Some(_) => "nobody in the cloud, people cut off by the view or too sparse, or not \
             standing on the floor found (check it with --preview; give the floor with \
             --ground or --up)"
            .into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_likely_cause_names_the_unit_first() {
        let mm = vec![[0.0, 0.0, 3000.0]; 5];
        assert!(likely_cause(&mm, true).contains("millimetres"));
        let tiny = vec![[0.0, 0.0, 0.003]; 5];
        assert!(likely_cause(&tiny, true).contains("larger than metres"));
        let room = vec![[0.0, 0.0, 3.0]; 5];
        assert!(likely_cause(&room, false).contains("no floor in it"));
        assert!(likely_cause(&room, true).contains("nobody"));
        assert!(likely_cause(&[], true).contains("no points"));
    }
}
