//! What both finders share: the voxels' clusters, the person candidates cut from them,
//! and the size filters and box fit every candidate goes through ([`person_box`]).

use crate::config::BoxesConfig;
use crate::find::ground::Plane;
use crate::fit::{fit_box, principal_yaw};
use crate::voxel::{VoxelGraph, Voxels};
use bodyseg_core::PersonBox;
use bodyseg_core::math::Vec3;

/// A person's trunk holds at least this many voxels for the box's yaw to be fitted on it,
/// ≈ 0.03 m² of trunk surface at 5 cm voxels: fewer (a person seen mostly through their
/// limbs, a torso the parser missed) and the yaw follows all their voxels.
pub(crate) const MIN_TORSO_VOXELS: usize = 12;

/// Extra length, metres, of a voxel-graph step from one person into another (a hand
/// touching someone's head, trunk or neck) in both modes' splits: more than an arm's
/// length (≈ 0.7 m), so a hand touching another person stays nearer its own shoulder
/// along the graph than that person's head.
pub(crate) const CONTACT_PENALTY_M: f32 = 1.0;

/// The clusters of the voxels where `keep` is true (the graph's components) that have at
/// least `min_voxels` voxels, in order of their first voxel: the smaller ones are parser
/// noise or clutter, never a person.
pub(crate) fn clusters(graph: &VoxelGraph, keep: &[bool], min_voxels: usize) -> Vec<Vec<u32>> {
    let mut out = graph.components(keep);
    out.retain(|c| c.len() >= min_voxels);
    out
}

/// Index of each voxel's points (compressed rows).
pub(crate) struct VoxelPoints {
    start: Vec<u32>,
    points: Vec<u32>,
}

impl VoxelPoints {
    pub(crate) fn new(v: &Voxels) -> VoxelPoints {
        let n = v.centers.len();
        let mut start = vec![0u32; n + 1];
        for &k in &v.point_voxel {
            start[k as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut points = vec![0u32; v.points.len()];
        for (&p, &k) in v.points.iter().zip(&v.point_voxel) {
            points[fill[k as usize] as usize] = p;
            fill[k as usize] += 1;
        }
        VoxelPoints { start, points }
    }

    fn of(&self, voxel: u32) -> &[u32] {
        &self.points[self.start[voxel as usize] as usize..self.start[voxel as usize + 1] as usize]
    }
}

/// A cloud as the finders fit boxes in it: its voxels, their points, and the ground.
pub(crate) struct VoxelCloud<'a> {
    /// Voxel centres, world frame, metres.
    centers: &'a [Vec3],
    /// Each voxel's points (indices into `positions`).
    index: VoxelPoints,
    /// The cloud's points, world frame, metres.
    positions: &'a [Vec3],
    /// The floor boxes stand on (labels mode: z = 0; geometry mode: the fitted plane).
    ground: Plane,
}

impl<'a> VoxelCloud<'a> {
    /// `voxels` of the points `positions`, standing on `ground`.
    pub(crate) fn new(voxels: &'a Voxels, positions: &'a [Vec3], ground: Plane) -> Self {
        VoxelCloud {
            centers: &voxels.centers,
            index: VoxelPoints::new(voxels),
            positions,
            ground,
        }
    }

    /// The lowest and highest of `voxels` above the ground.
    fn span(&self, voxels: &[u32]) -> HeightSpan {
        let (mut lo_m, mut hi_m) = (f32::INFINITY, f32::NEG_INFINITY);
        for &v in voxels {
            let h = self.ground.height(self.centers[v as usize]);
            lo_m = lo_m.min(h);
            hi_m = hi_m.max(h);
        }
        HeightSpan { lo_m, hi_m }
    }
}

/// How high a candidate's lowest and highest voxel centres are above the ground, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HeightSpan {
    /// The lowest voxel's height.
    pub lo_m: f32,
    /// The highest voxel's height.
    pub hi_m: f32,
}

/// One person candidate: its voxels and what orients its box.
pub(crate) struct Candidate<'a> {
    /// The box's id, should it be kept.
    pub id: u32,
    /// Its voxels.
    pub voxels: &'a [u32],
    /// Its trunk's voxels (labels mode: those labelled torso; geometry mode: hips to chest
    /// beside the head), whose principal horizontal axis is the box's yaw when there are at
    /// least [`MIN_TORSO_VOXELS`] of them.
    pub trunk: &'a [u32],
    /// The box's yaw, radians, when the finder knows it better than any trunk (geometry
    /// mode's two heads of one cluster close together).
    pub facing: Option<f32>,
}

/// Checks one person candidate against the size limits and fits its box around its raw
/// points, or `None` when it is no person: too few voxels (`min_voxels`), a top too low
/// (`min_top_m`) or too high (`max_height_m`), floating, too wide (`max_width_m`).
///
/// A person stands on the floor: a candidate whose lowest voxel is higher than
/// `max_bottom_m` floats (a reaching arm, a hand-held object), unless `may_float` says
/// otherwise of its [`HeightSpan`] (labels mode: a labelled body whose legs the cameras
/// miss); `may_float` is asked only of such a candidate.
///
/// The box's yaw is the candidate's `facing` where given, else the principal horizontal
/// axis of its `trunk` voxels when there are at least [`MIN_TORSO_VOXELS`] of them, else of
/// all its voxels: the trunk (shoulders and hips wider than deep) follows the facing
/// direction, which the true boxes are aligned with, while a pointing, reaching or
/// handing-over arm turns the axis of the whole body towards itself. Trunk alone, not with
/// the legs: they stride along the facing direction while hips and shoulders lie across
/// it, so together they have no clear axis.
pub(crate) fn person_box(
    cloud: &VoxelCloud,
    candidate: &Candidate,
    cfg: &BoxesConfig,
    may_float: impl FnOnce(HeightSpan) -> bool,
) -> Option<PersonBox> {
    let group = candidate.voxels;
    if group.len() < cfg.min_voxels {
        return None;
    }
    let span = cloud.span(group);
    let floating = span.lo_m > cfg.max_bottom_m && !may_float(span);
    if span.hi_m < cfg.min_top_m() || span.hi_m > cfg.max_height_m || floating {
        tracing::trace!(
            voxels = group.len(),
            lo_h = span.lo_m,
            hi_h = span.hi_m,
            "candidate dropped: height"
        );
        return None;
    }
    let centers = cloud.centers;
    let xy_of = |v: &u32| [centers[*v as usize][0], centers[*v as usize][1]];
    let yaw_from = if candidate.trunk.len() >= MIN_TORSO_VOXELS {
        candidate.trunk
    } else {
        group
    };
    let yaw = candidate
        .facing
        .unwrap_or_else(|| principal_yaw(&yaw_from.iter().map(xy_of).collect::<Vec<_>>()));
    let mut xy = Vec::new();
    let mut top = f32::NEG_INFINITY;
    for &v in group {
        for &p in cloud.index.of(v) {
            let p = cloud.positions[p as usize];
            xy.push([p[0], p[1]]);
            top = top.max(p[2]);
        }
    }
    let id = candidate.id;
    let unmargined = fit_box(id, &xy, yaw, 0.0, 1.0, 0.0);
    let width = 2.0 * unmargined.half_extents_m[0].max(unmargined.half_extents_m[1]);
    if width > cfg.max_width_m {
        tracing::trace!(voxels = group.len(), width, "candidate dropped: width");
        return None;
    }
    let c = unmargined.center_m;
    Some(fit_box(
        id,
        &xy,
        yaw,
        cloud.ground.z_at(c[0], c[1]),
        top,
        cfg.box_margin_m,
    ))
}

/// Voxel centres (world frame, metres) with their heights above the ground plane, metres,
/// both indexed by voxel (geometry mode).
#[derive(Clone, Copy)]
pub(crate) struct VoxelHeights<'a> {
    /// Voxel centres.
    pub centers: &'a [Vec3],
    /// Each voxel's height above the ground.
    pub heights: &'a [f32],
}

/// One cluster as geometry mode walks it: its voxels, the graph among the kept voxels,
/// and where each voxel is.
#[derive(Clone, Copy)]
pub(crate) struct Cluster<'a> {
    /// The neighbour graph among the kept voxels.
    pub graph: &'a VoxelGraph,
    /// Per voxel, whether it is kept (above the floor, dense, not too high).
    pub keep: &'a [bool],
    /// The cluster's voxels, ascending.
    pub members: &'a [u32],
    /// Every voxel's centre and height.
    pub at: VoxelHeights<'a>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::voxelize;
    use std::cell::Cell;

    /// One point per 5 cm voxel of a 0.2 m × 0.2 m column from height `lo_m` to `hi_m`.
    fn column(lo_m: f32, hi_m: f32) -> Vec<Vec3> {
        let layers = ((hi_m - lo_m) / 0.05).round() as u32;
        let mut out = Vec::new();
        for k in 0..layers {
            for i in 0..4 {
                for j in 0..4 {
                    let at = |n: u32| 0.05 * n as f32 + 0.025;
                    out.push([at(i), at(j), lo_m + at(k)]);
                }
            }
        }
        out
    }

    /// `person_box` of the whole `points` as one candidate (labels mode's defaults, floor
    /// z = 0), and the spans `may_float` was asked about, answering `floats`.
    fn judge(points: &[Vec3], floats: bool) -> (Option<PersonBox>, Vec<HeightSpan>) {
        let v = voxelize(points.iter().enumerate().map(|(i, &p)| (i, p, 2)), 0.05);
        let cloud = VoxelCloud::new(&v, points, Plane::FLOOR);
        let all: Vec<u32> = (0..v.centers.len() as u32).collect();
        let candidate = Candidate {
            id: 7,
            voxels: &all,
            trunk: &[],
            facing: None,
        };
        let asked = Cell::new(Vec::new());
        let found = person_box(&cloud, &candidate, &BoxesConfig::default(), |span| {
            let mut spans = asked.take();
            spans.push(span);
            asked.set(spans);
            floats
        });
        (found, asked.take())
    }

    #[test]
    fn a_floating_candidate_is_a_person_only_when_its_finder_says_so() {
        // Standing, 1.75 m tall: a box from the floor, and nobody asked whether it floats.
        let (found, asked) = judge(&column(0.0, 1.75), false);
        let b = found.expect("a standing person");
        assert_eq!(b.id, 7);
        // Bottom on the floor, top 5 cm (the margin) above the highest point (f32 sums).
        assert!((b.center_m[2] - b.half_extents_m[2]).abs() < 1e-5, "{b:?}");
        let top = b.center_m[2] + b.half_extents_m[2];
        assert!((top - (1.725 + 0.05)).abs() < 1e-5, "{b:?}");
        assert!(asked.is_empty());
        // The same body from 0.7 m up: dropped unless the finder vouches for it, which is
        // asked once, with its lowest and highest voxel.
        let floating = column(0.7, 1.75);
        let (found, asked) = judge(&floating, false);
        assert!(found.is_none());
        assert_eq!(asked.len(), 1);
        assert!((asked[0].lo_m - 0.725).abs() < 1e-5 && (asked[0].hi_m - 1.725).abs() < 1e-5);
        let (found, _) = judge(&floating, true);
        let b = found.expect("a person whose legs are hidden");
        // Its box still stands on the floor.
        assert!((b.center_m[2] - b.half_extents_m[2]).abs() < 1e-5, "{b:?}");
        // Too low a top is no person whatever the finder says.
        assert!(judge(&column(0.5, 0.85), true).0.is_none());
    }
}
