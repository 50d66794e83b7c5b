//! Geometry mode: voxels → RANSAC ground plane removed → clusters → heads ([`find_heads`])
//! → each cluster split between its heads and what no person can own ([`split_people`])
//! → size filters → boxes on the ground plane. Labels are not used; colours, where given,
//! only in the split.

use crate::config::BoxesConfig;
use crate::find::candidates::{Candidate, Cluster, VoxelCloud, VoxelHeights, clusters, person_box};
use crate::find::color::voxel_chroma;
use crate::find::ground::{fit_ground, lowest_floor, xy_dist};
use crate::find::heads::find_heads;
use crate::find::split::split_people;
use crate::fit::principal_yaw;
use crate::voxel::{VoxelGraph, voxelize};
use bodyseg_core::PersonBox;
use bodyseg_core::math::Vec3;

/// Two people of one cluster whose heads are closer than this horizontally, metres (less
/// than an arm's length: touching, not just near), get boxes aligned with the line between
/// their heads ([`close_pair_yaw`]): that close they face each other or stand shoulder to
/// shoulder, and each hides the other's front, so their trunks' axes are unreliable.
const CLOSE_PAIR_M: f32 = 0.6;

/// Geometry mode's trunk ([`trunk_voxels`]) from this fraction of the head's height up
/// (the hips are at ≈ 0.53 of a person's height; the hands hanging at the sides are
/// below ≈ 0.4).
const TRUNK_LOW_FRACTION: f32 = 0.5;
/// ... up to this fraction (the shoulders' top is at ≈ 0.82–0.85, the neck above).
const TRUNK_HIGH_FRACTION: f32 = 0.85;
/// ... within this distance of the head's vertical, metres (half a shoulder width, ≈ 0.2
/// m, and the voxels' centroids).
const TRUNK_RADIUS_M: f32 = 0.25;

/// Geometry mode: voxels → RANSAC ground plane removed → clusters → heads (height
/// maxima with a continuous column below) → split between heads and what no person can
/// own ([`split_people`]) → size filters → boxes on the ground plane. Labels are not used;
/// `colors` (per point, sRGB), where given, only in the split.
pub(crate) fn geometry_mode(
    positions: &[Vec3],
    colors: Option<&[[u8; 3]]>,
    cfg: &BoxesConfig,
) -> Vec<PersonBox> {
    let all = voxelize(
        positions.iter().enumerate().map(|(i, &p)| (i, p, 0)),
        cfg.voxel_m,
    );
    let ground = fit_ground(
        &all.centers,
        cfg.ground_tol_m,
        cfg.max_ground_tilt_deg,
        cfg.ransac_iterations,
    )
    .unwrap_or_else(|| lowest_floor(&all.centers));
    let heights: Vec<f32> = all.centers.iter().map(|&p| ground.height(p)).collect();
    let keep: Vec<bool> = heights
        .iter()
        .zip(&all.counts)
        .map(|(&h, &n)| {
            h > cfg.ground_tol_m
                && h < cfg.max_height_m + cfg.person_gap_m
                && n >= cfg.min_voxel_points
        })
        .collect();
    let graph = VoxelGraph::new(&all.centers, cfg.person_gap_m, &keep);
    let scene = VoxelCloud::new(&all, positions, ground);
    let at = VoxelHeights {
        centers: &all.centers,
        heights: &heights,
    };
    let chroma = colors.map(|c| voxel_chroma(&all, c));
    let mut boxes = Vec::new();
    for members in clusters(&graph, &keep, cfg.min_voxels) {
        let cluster = Cluster {
            graph: &graph,
            keep: &keep,
            members: &members,
            at,
        };
        let heads = find_heads(&cluster, cfg);
        if heads.is_empty() {
            continue;
        }
        for (head, group) in split_people(&cluster, &heads, chroma.as_deref(), cfg) {
            let trunk = trunk_voxels(&group, head, at);
            let candidate = Candidate {
                id: boxes.len() as u32,
                voxels: &group,
                trunk: &trunk,
                facing: close_pair_yaw(head, &heads, &all.centers),
            };
            // Without labels nothing tells a body whose legs are hidden from something
            // held up: whatever floats is dropped.
            if let Some(b) = person_box(&scene, &candidate, cfg, |_| false) {
                boxes.push(b);
            }
        }
    }
    tracing::debug!(
        boxes = boxes.len(),
        voxels = all.centers.len(),
        "geometry mode"
    );
    boxes
}

/// Geometry mode: the voxels of `group` that are most likely its trunk, whose principal
/// horizontal axis gives the box's yaw as labels mode's torso does ([`person_box`]):
/// those between [`TRUNK_LOW_FRACTION`] and [`TRUNK_HIGH_FRACTION`] of the head's height
/// (hips to chest) within [`TRUNK_RADIUS_M`] of its vertical. Arms hanging at the sides
/// are across the facing direction, as the shoulders and hips; a reaching or pointing
/// arm leaves the radius; the legs, striding along the facing direction, are below.
fn trunk_voxels(group: &[u32], head: u32, at: VoxelHeights) -> Vec<u32> {
    let VoxelHeights { centers, heights } = at;
    let (top, top_h) = (centers[head as usize], heights[head as usize]);
    let (lo, hi) = (TRUNK_LOW_FRACTION * top_h, TRUNK_HIGH_FRACTION * top_h);
    group
        .iter()
        .copied()
        .filter(|&j| {
            let (c, h) = (centers[j as usize], heights[j as usize]);
            h >= lo && h <= hi && xy_dist(c, top) <= TRUNK_RADIUS_M
        })
        .collect()
}

/// Geometry mode: the yaw of the line from `head` to the nearest other head of its cluster
/// (`heads`), in (-π/2, π/2], when the two are closer than [`CLOSE_PAIR_M`]
/// horizontally: then it is the box's yaw instead of the trunk's axis (see there).
fn close_pair_yaw(head: u32, heads: &[u32], centers: &[Vec3]) -> Option<f32> {
    let c = centers[head as usize];
    let (d, o) = heads
        .iter()
        .filter(|&&h| h != head)
        .map(|&h| (xy_dist(centers[h as usize], c), centers[h as usize]))
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    // The axis through the two heads, as the trunk's is found (in (-π/2, π/2]).
    (d < CLOSE_PAIR_M).then(|| principal_yaw(&[[c[0], c[1]], [o[0], o[1]]]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_close_pair_s_yaw_is_the_line_between_their_heads_as_an_axis() {
        // Heads: 0 at the origin, 1 down-left 0.42 m away, 2 far to the right.
        let centers = [[0.0, 0.0, 1.8], [-0.3, -0.3, 1.6], [2.0, 0.0, 1.7]];
        let quarter = std::f32::consts::FRAC_PI_4;
        // From 0 towards 1 is -3π/4: the same axis as π/4, which principal_yaw would give.
        let yaw = close_pair_yaw(0, &[0, 1, 2], &centers).expect("a close pair");
        assert!((yaw - quarter).abs() < 1e-6, "{yaw}");
        let yaw = close_pair_yaw(1, &[0, 1, 2], &centers).expect("a close pair");
        assert!((yaw - quarter).abs() < 1e-6, "{yaw}");
        // Alone, or with the nearest other head 1.7 m away: the trunk gives the yaw.
        assert_eq!(close_pair_yaw(2, &[0, 1, 2], &centers), None);
        assert_eq!(close_pair_yaw(0, &[0], &centers), None);
    }
}
