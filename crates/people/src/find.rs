//! The two box finders: labels mode and geometry mode (ALGORITHM.md §4).

use crate::config::{BoxMode, BoxesConfig, PeopleError};
use crate::fit::{fit_box, principal_yaw};
use crate::voxel::{VoxelGraph, Voxels, voxelize};
use bodyseg_core::math::{CHROMA_BINS, Vec3, chroma_bin, near_chroma_bins, srgb_to_linear};
use bodyseg_core::{Class, LabeledCloud, PersonBox, PersonBoxes};
use rustc_hash::{FxHashMap, FxHashSet};

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
        BoxMode::Labels => labels_mode(cloud, cfg),
        BoxMode::Geometry => geometry_mode(
            &cloud.positions_m,
            cloud.colors.as_deref().filter(|_| cfg.uses_colors()),
            cfg,
        ),
        BoxMode::File => return Err(PeopleError::FileMode),
    };
    Ok(PersonBoxes {
        frame: String::new(),
        boxes,
    })
}

/// Ground plane `n·p + d = 0`, `n` unit with `n.z > 0`: height of `p` is `n·p + d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plane {
    n: Vec3,
    d: f32,
}

impl Plane {
    /// The floor of bodyseg's world frame, z = 0.
    const FLOOR: Plane = Plane {
        n: [0.0, 0.0, 1.0],
        d: 0.0,
    };

    fn height(&self, p: Vec3) -> f32 {
        self.n[0] * p[0] + self.n[1] * p[1] + self.n[2] * p[2] + self.d
    }

    /// z of the plane at (x, y).
    fn z_at(&self, x: f32, y: f32) -> f32 {
        -(self.n[0] * x + self.n[1] * y + self.d) / self.n[2]
    }
}

/// Horizontal distance of two points, metres.
fn xy_dist(a: Vec3, b: Vec3) -> f32 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Index of each voxel's points (compressed rows).
struct VoxelPoints {
    start: Vec<u32>,
    points: Vec<u32>,
}

impl VoxelPoints {
    fn new(v: &Voxels) -> VoxelPoints {
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

/// Labels mode: a person's torso holds at least this many voxels for the box's yaw to
/// be fitted on it (≈ 0.03 m² of trunk surface at 5 cm); fewer (a person seen mostly
/// through their limbs, a torso the parser missed) and the yaw follows all their voxels.
const MIN_TORSO_VOXELS: usize = 12;

/// A labelled body (head and torso) whose lowest voxel is at most this fraction of its
/// height up is a person whose legs the cameras miss (hips at ≈ 0.53 of the height).
const HIDDEN_LEGS_FRACTION: f32 = 0.5;
/// A labelled body's head voxels lie on average at most this far below its top, metres
/// (a head's centre is ≈ 0.1 m below the crown; a hand raised over the head adds more).
const HEAD_ON_TOP_M: f32 = 0.3;

/// Whether the voxels `group` (class ids per voxel in `labels`, top `top_h` above
/// `ground`) are a body with its head on top: at least `min_head_voxels` head voxels,
/// on average within [`HEAD_ON_TOP_M`] of the top, and [`MIN_TORSO_VOXELS`] torso voxels.
/// A parser calls parts of a robot head and torso too, but not with the head on top
/// (bundled model, `robot_cell` 2011: head voxels 0.45 m below the top on average,
/// forearms above them).
fn head_on_top(
    group: &[u32],
    labels: &[u8],
    centers: &[Vec3],
    ground: Plane,
    top_h: f32,
    min_head_voxels: usize,
) -> bool {
    let (mut head, mut head_h_sum, mut torso) = (0usize, 0.0f32, 0usize);
    for &v in group {
        let l = labels[v as usize];
        if l == Class::Head.id() {
            head += 1;
            head_h_sum += ground.height(centers[v as usize]);
        } else if l == Class::Torso.id() {
            torso += 1;
        }
    }
    head >= min_head_voxels.max(1)
        && torso >= MIN_TORSO_VOXELS
        && head_h_sum / head as f32 >= top_h - HEAD_ON_TOP_M
}

/// Checks one person candidate (its voxels) against the size limits and fits its box around
/// its raw points. The box's yaw is `facing` where given ([`close_pair_yaw`]), else the
/// principal horizontal axis of its `trunk` voxels (labels mode: those labelled torso;
/// geometry mode: [`trunk_voxels`]) when there are at least [`MIN_TORSO_VOXELS`] of them,
/// else of all the voxels: the trunk (shoulders and hips wider than deep) follows the
/// facing direction, which the true boxes are aligned with, while a pointing, reaching or
/// handing-over arm turns the axis of the whole body towards itself. Torso alone, not with
/// the legs: they stride along the facing direction while hips and shoulders lie across it,
/// so together they have no clear axis.
#[allow(clippy::too_many_arguments)]
fn person_box(
    id: u32,
    group: &[u32],
    trunk: &[u32],
    facing: Option<f32>,
    voxel_labels: Option<&[u8]>,
    centers: &[Vec3],
    index: &VoxelPoints,
    positions: &[Vec3],
    ground: Plane,
    cfg: &BoxesConfig,
) -> Option<PersonBox> {
    if group.len() < cfg.min_voxels {
        return None;
    }
    let (mut lo_h, mut hi_h) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in group {
        let h = ground.height(centers[v as usize]);
        lo_h = lo_h.min(h);
        hi_h = hi_h.max(h);
    }
    // A person stands on the floor: their lowest voxel is near it, unless they are a
    // labelled body (a head on top, a torso) whose legs the cameras do not see below the
    // hips (behind a robot's base or a table, or cut off by unlabelled points). Counted
    // only for such a candidate: most reach the floor.
    let floating = lo_h > cfg.max_bottom_m
        && !(lo_h <= HIDDEN_LEGS_FRACTION * hi_h
            && voxel_labels.is_some_and(|labels| {
                head_on_top(group, labels, centers, ground, hi_h, cfg.min_head_voxels)
            }));
    if hi_h < cfg.min_top_m() || hi_h > cfg.max_height_m || floating {
        tracing::trace!(
            voxels = group.len(),
            lo_h,
            hi_h,
            "candidate dropped: height"
        );
        return None;
    }
    let xy_of = |v: &u32| [centers[*v as usize][0], centers[*v as usize][1]];
    let yaw_from = if trunk.len() >= MIN_TORSO_VOXELS {
        trunk
    } else {
        group
    };
    let yaw =
        facing.unwrap_or_else(|| principal_yaw(&yaw_from.iter().map(xy_of).collect::<Vec<_>>()));
    let mut xy = Vec::new();
    let mut top = f32::NEG_INFINITY;
    for &v in group {
        for &p in index.of(v) {
            let p = positions[p as usize];
            xy.push([p[0], p[1]]);
            top = top.max(p[2]);
        }
    }
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
        ground.z_at(c[0], c[1]),
        top,
        cfg.box_margin_m,
    ))
}

/// Groups of `class` voxels inside `members` that look like separate body parts of
/// different people: connected patches of at least `min_voxels`, patches whose
/// horizontal centres are closer than `separation_m` merged.
fn part_seeds(
    graph: &VoxelGraph,
    v: &Voxels,
    members: &[u32],
    class: Class,
    min_voxels: usize,
    separation_m: f32,
) -> Vec<Vec<u32>> {
    let mut keep = vec![false; v.centers.len()];
    let mut any = false;
    for &i in members {
        if v.labels[i as usize] == class.id() {
            keep[i as usize] = true;
            any = true;
        }
    }
    if !any {
        return Vec::new();
    }
    let mut patches: Vec<Vec<u32>> = graph
        .components(&keep)
        .into_iter()
        .filter(|c| c.len() >= min_voxels)
        .collect();
    let centre = |p: &[u32]| {
        let mut s = [0.0f32; 2];
        for &i in p {
            s[0] += v.centers[i as usize][0];
            s[1] += v.centers[i as usize][1];
        }
        [s[0] / p.len() as f32, s[1] / p.len() as f32]
    };
    // Merge close patches until none are closer than the separation (few patches).
    loop {
        let centres: Vec<[f32; 2]> = patches.iter().map(|p| centre(p)).collect();
        let mut pair = None;
        'outer: for a in 0..patches.len() {
            for b in a + 1..patches.len() {
                let d = (centres[a][0] - centres[b][0]).hypot(centres[a][1] - centres[b][1]);
                if d < separation_m {
                    pair = Some((a, b));
                    break 'outer;
                }
            }
        }
        let Some((a, b)) = pair else { break };
        let moved = patches.swap_remove(b);
        patches[a].extend(moved);
    }
    patches
}

/// Labels mode: body-labelled points → voxels → clusters → split on heads (or torsos)
/// → size filters → boxes on the floor z = 0.
fn labels_mode(cloud: &LabeledCloud, cfg: &BoxesConfig) -> Vec<PersonBox> {
    let body = cloud
        .positions_m
        .iter()
        .zip(&cloud.labels)
        .enumerate()
        .filter_map(|(i, (&p, l))| {
            let c = l.class()?;
            // Floor points near the feet that the parser labelled as feet are not a person.
            (c.is_body() && p[2] > cfg.ground_tol_m).then_some((i, p, c.id()))
        });
    let v = voxelize(body, cfg.voxel_m);
    let index = VoxelPoints::new(&v);
    let dense: Vec<bool> = v
        .counts
        .iter()
        .map(|&c| c >= cfg.min_voxel_points)
        .collect();
    let graph = VoxelGraph::new(&v.centers, cfg.person_gap_m, &dense);
    // Each voxel's person (0, 1, ... in the order found), u32::MAX for none.
    let mut owner = vec![u32::MAX; v.centers.len()];
    let mut people = 0u32;
    for cluster in graph.components(&dense) {
        if cluster.len() < cfg.min_voxels {
            continue;
        }
        let mut seeds = part_seeds(
            &graph,
            &v,
            &cluster,
            Class::Head,
            cfg.min_head_voxels,
            cfg.head_separation_m,
        );
        if seeds.len() < 2 {
            seeds = part_seeds(
                &graph,
                &v,
                &cluster,
                Class::Torso,
                2 * cfg.min_head_voxels,
                cfg.head_separation_m,
            );
        }
        if seeds.len() >= 2 {
            // Along bodies: a step between parts not joined in a body (a hand on someone's
            // head) costs a contact penalty, so an arm reaching someone stays its owner's.
            let split = graph.split_with(&v.centers, &cluster, &seeds, |i, j| {
                if adjacent_parts(v.labels[i as usize], v.labels[j as usize]) {
                    0.0
                } else {
                    CONTACT_PENALTY_M
                }
            });
            for (&i, &g) in cluster.iter().zip(&split) {
                owner[i as usize] = people + g as u32;
            }
            people += seeds.len() as u32;
        } else {
            for &i in &cluster {
                owner[i as usize] = people;
            }
            people += 1;
        }
    }
    attach_limb_fragments(&graph, &v, &dense, &mut owner);
    // Ids in order of each person's first voxel.
    let mut groups: Vec<Vec<u32>> = vec![Vec::new(); people as usize];
    for (i, &g) in owner.iter().enumerate() {
        if let Some(group) = groups.get_mut(g as usize) {
            group.push(i as u32);
        }
    }
    groups.sort_by_key(|g| g.first().copied());
    let mut boxes = Vec::new();
    let torso = Class::Torso.id();
    for group in groups {
        let id = boxes.len() as u32;
        let trunk: Vec<u32> = group
            .iter()
            .copied()
            .filter(|&j| v.labels[j as usize] == torso)
            .collect();
        if let Some(b) = person_box(
            id,
            &group,
            &trunk,
            None,
            Some(&v.labels),
            &v.centers,
            &index,
            &cloud.positions_m,
            Plane::FLOOR,
            cfg,
        ) {
            boxes.push(b);
        }
    }
    tracing::debug!(boxes = boxes.len(), voxels = v.centers.len(), "labels mode");
    boxes
}

/// How far a limb fragment may lie from the part it hangs on, metres: an elbow or a knee
/// the cameras do not see (hidden by the limb itself or by someone in front of it) leaves
/// a gap of up to ≈ 0.3 m between an upper and a lower arm.
const FRAGMENT_REACH_M: f32 = 0.35;
/// Limb fragments smaller than this (voxels) stay where they are: a few mislabelled
/// points are not worth moving a box for.
const MIN_FRAGMENT_VOXELS: usize = 5;
/// A fragment is a forearm: at least this fraction of its voxels labelled lower arm. Pieces
/// of other limb labels floating near people are, with a real parser, mostly its mistakes
/// (streaks of flying pixels at depth edges labelled leg or upper arm): attached, they
/// stretched boxes and cost the refinement (bundled model, naive projection, M-R-N BIoU
/// 64.88 -> 64.33 on the benchmark, lower arms -2.4 IoU).
const MIN_FRAGMENT_LOWER_ARM: f32 = 0.6;
/// A fragment's bounding-box diagonal is at most this, metres: a forearm with its hand
/// (≈ 0.45 m); a longer piece labelled lower arm is something else (a robot link).
const MAX_FRAGMENT_EXTENT_M: f32 = 0.6;

/// Labels mode: gives forearm fragments to the person they hang on. A fragment is a piece
/// of arm joined to no torso along a body (only parts that touch within one body join:
/// [`adjacent_parts`]), mostly lower arm ([`MIN_FRAGMENT_LOWER_ARM`]) and no longer than
/// a forearm ([`MAX_FRAGMENT_EXTENT_M`]) — a forearm whose elbow the cameras did not see,
/// floating on its own (then too small to be a person and dropped) or touching someone
/// else's trunk (then in that person's cluster). Such a piece goes to the person, other
/// than the one it touches, with the upper arm it hangs on
/// nearest to it within [`FRAGMENT_REACH_M`]; with none, it stays where it was. `owner`
/// holds each voxel's person (u32::MAX: none) and is updated in place.
fn attach_limb_fragments(graph: &VoxelGraph, v: &Voxels, dense: &[bool], owner: &mut [u32]) {
    let torso = Class::Torso.id();
    let (upper_arm, lower_arm) = (Class::UpperArms.id(), Class::LowerArms.id());
    // The part an arm voxel hangs on: a lower arm on an upper arm, an upper arm on a torso.
    let parent = |l: u8| if l == lower_arm { upper_arm } else { torso };
    // Pieces of arm (only the arms' voxels, joined along a body: a forearm with its upper
    // arm); a piece hangs on a torso when one of its upper-arm voxels touches one. Only arms:
    // a fragment is a forearm, and the legs would double the work for nothing.
    let arm: Vec<bool> = dense
        .iter()
        .zip(&v.labels)
        .map(|(&d, &l)| d && (l == upper_arm || l == lower_arm))
        .collect();
    let pieces = graph.components_along(&arm, |i, j| {
        adjacent_parts(v.labels[i as usize], v.labels[j as usize])
    });
    let hangs_on_torso = |piece: &[u32]| {
        piece.iter().any(|&i| {
            let i = i as usize;
            let mut found = false;
            if v.labels[i] == upper_arm {
                graph.for_neighbors(i, |j, _| {
                    found |= dense[j as usize] && v.labels[j as usize] == torso;
                });
            }
            found
        })
    };
    for piece in pieces {
        let lower_arms = piece
            .iter()
            .filter(|&&i| v.labels[i as usize] == lower_arm)
            .count();
        if piece.len() < MIN_FRAGMENT_VOXELS
            || (lower_arms as f32) < MIN_FRAGMENT_LOWER_ARM * piece.len() as f32
            || hangs_on_torso(&piece)
        {
            continue;
        }
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for &i in &piece {
            for a in 0..3 {
                lo[a] = lo[a].min(v.centers[i as usize][a]);
                hi[a] = hi[a].max(v.centers[i as usize][a]);
            }
        }
        // No longer than a forearm with its hand (≈ 0.45 m).
        let diagonal2: f32 = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum();
        if diagonal2 > MAX_FRAGMENT_EXTENT_M * MAX_FRAGMENT_EXTENT_M {
            continue;
        }
        // The person it touches (where it is now), if any, is not the one it hangs on.
        let touched = owner[piece[0] as usize];
        let near = |q: Vec3| {
            (0..3).all(|a| (lo[a] - FRAGMENT_REACH_M..=hi[a] + FRAGMENT_REACH_M).contains(&q[a]))
        };
        let mut best = (FRAGMENT_REACH_M * FRAGMENT_REACH_M, u32::MAX);
        for (j, (&o, &l)) in owner.iter().zip(&v.labels).enumerate() {
            if o == u32::MAX
                || o == touched
                || (l != upper_arm && l != torso)
                || !near(v.centers[j])
            {
                continue;
            }
            for &i in &piece {
                if parent(v.labels[i as usize]) == l {
                    let d2 = bodyseg_core::math::dist2(v.centers[i as usize], v.centers[j]);
                    if d2 < best.0 {
                        best = (d2, o);
                    }
                }
            }
        }
        if best.1 != u32::MAX {
            tracing::trace!(
                voxels = piece.len(),
                lower_arms,
                from = touched,
                to = best.1,
                "forearm fragment given to the person it hangs on"
            );
            for &i in &piece {
                owner[i as usize] = best.1;
            }
        }
    }
}

/// Extra length of a voxel-graph edge between body parts that are not joined in a body
/// (a hand touching someone's head or trunk), metres: more than an arm's length
/// (≈ 0.7 m), so a hand touching another person stays nearer its own shoulder along the
/// graph than that person's head (labels mode's split).
const CONTACT_PENALTY_M: f32 = 1.0;

/// Whether class ids `a` and `b` may touch within one body: the same part, or parts
/// joined in the Pascal-Person-Part tree (head, upper arms and upper legs on the torso;
/// lower arm on upper arm, lower leg on upper leg).
fn adjacent_parts(a: u8, b: u8) -> bool {
    let joints = [
        (Class::Head, Class::Torso),
        (Class::Torso, Class::UpperArms),
        (Class::Torso, Class::UpperLegs),
        (Class::UpperArms, Class::LowerArms),
        (Class::UpperLegs, Class::LowerLegs),
    ];
    a == b
        || joints
            .iter()
            .any(|&(p, q)| (p.id(), q.id()) == (a, b) || (q.id(), p.id()) == (a, b))
}

/// splitmix64: a small deterministic generator for RANSAC.
struct SplitMix(u64);

impl SplitMix {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z % n as u64) as usize
    }
}

/// RANSAC ground plane among `centers`: the near-horizontal plane (normal within
/// `max_ground_tilt_deg` of +z) with the most points within `ground_tol_m`; `None` when
/// no sample gives such a plane.
pub(crate) fn fit_ground(centers: &[Vec3], cfg: &BoxesConfig) -> Option<Plane> {
    if centers.len() < 3 {
        return None;
    }
    let min_nz = cfg.max_ground_tilt_deg.to_radians().cos();
    let mut rng = SplitMix(0x6A09_E667_F3BC_C908);
    let mut best: Option<(usize, Plane)> = None;
    // Score on a strided subset: the count only ranks planes.
    let stride = (centers.len() / 4000).max(1);
    for _ in 0..cfg.ransac_iterations {
        let [a, b, c] = [0; 3].map(|_| centers[rng.below(centers.len())]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let mut n = [
            u[1] * w[2] - u[2] * w[1],
            u[2] * w[0] - u[0] * w[2],
            u[0] * w[1] - u[1] * w[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len.is_nan() || len <= 1e-9 {
            continue;
        }
        if n[2] < 0.0 {
            n = n.map(|x| -x);
        }
        n = n.map(|x| x / len);
        if n[2] < min_nz {
            continue;
        }
        let plane = Plane {
            n,
            d: -(n[0] * a[0] + n[1] * a[1] + n[2] * a[2]),
        };
        let count = centers
            .iter()
            .step_by(stride)
            .filter(|&&p| plane.height(p).abs() <= cfg.ground_tol_m)
            .count();
        // The floor has the most points; a table top or a box lid far fewer.
        let better = best.is_none_or(|(bc, _)| count > bc);
        if better {
            best = Some((count, plane));
        }
    }
    best.map(|(_, p)| p)
}

/// Geometry mode: voxels → RANSAC ground plane removed → clusters → heads (height
/// maxima with a continuous column below) → split between heads and what no person can
/// own ([`split_people`]) → size filters → boxes on the ground plane. Labels are not used.
fn geometry_mode(
    positions: &[Vec3],
    colors: Option<&[[u8; 3]]>,
    cfg: &BoxesConfig,
) -> Vec<PersonBox> {
    let all = voxelize(
        positions.iter().enumerate().map(|(i, &p)| (i, p, 0)),
        cfg.voxel_m,
    );
    let ground = fit_ground(&all.centers, cfg).unwrap_or_else(|| {
        // No near-horizontal plane: take the lowest percentile of z as the floor.
        let mut z: Vec<f32> = all.centers.iter().map(|p| p[2]).collect();
        z.sort_by(f32::total_cmp);
        let floor = z.get(z.len() / 100).copied().unwrap_or(0.0);
        tracing::debug!(
            floor,
            "no ground plane found; floor at the 1st percentile of z"
        );
        Plane {
            n: [0.0, 0.0, 1.0],
            d: -floor,
        }
    });
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
    let index = VoxelPoints::new(&all);
    let chroma = colors.map(|c| voxel_chroma(&all, c));
    let mut boxes = Vec::new();
    for cluster in graph.components(&keep) {
        if cluster.len() < cfg.min_voxels {
            continue;
        }
        let heads = find_heads(&graph, &keep, &cluster, &all.centers, &heights, cfg);
        if heads.is_empty() {
            continue;
        }
        let groups = split_people(
            &graph,
            &cluster,
            &heads,
            &all.centers,
            &heights,
            chroma.as_deref(),
            cfg,
        );
        for (head, group) in groups {
            let id = boxes.len() as u32;
            let trunk = trunk_voxels(&group, head, &all.centers, &heights);
            let facing = close_pair_yaw(head, &heads, &all.centers);
            if let Some(b) = person_box(
                id,
                &group,
                &trunk,
                facing,
                None,
                &all.centers,
                &index,
                positions,
                ground,
                cfg,
            ) {
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

/// Splits one cluster (geometry mode) between its heads and what is nobody's, then cuts
/// each person to arm's reach. Groups in order of their first voxel, one per head.
///
/// A robot arm or a shelf touching a person joins their cluster, and cutting at arm's
/// reach alone leaves the part within reach (a robot's elbow and forearm beside the
/// person's chest) in their box. So the cluster is split first, along the voxel graph
/// (multi-source Dijkstra, as labels mode splits between heads), between the people —
/// each seeded with its head and its lower legs (below [`LOW_LEG_FRACTION`] of its
/// height, within `column_radius_m` of the head's vertical) — and the part no person can
/// own, seeded with the voxels beyond `max_reach_m` + [`ANCHOR_SLACK_M`] of every head,
/// or below [`LOW_LEG_FRACTION`] of every head's height and beyond [`LEG_RADIUS_M`] +
/// [`ANCHOR_SLACK_M`] of its vertical (a robot's pedestal and shoulder, a box, a table's
/// legs). A voxel goes to whichever seed is nearer along the graph, the part that is
/// nobody's spreading at [`NOBODY_LENGTH_SCALE`] of the cost: a robot arm touching a
/// person is claimed from its pedestal and shoulder up to about the contact, while a
/// person's own arm, nearer their head than anything that is not them, stays theirs. A
/// path leaving a head sideways within [`HEAD_CONTACT_DEPTH_M`] of its top pays
/// [`CONTACT_PENALTY_M`], so an arm touching the side of a neighbour's head or neck stays
/// its owner's. With the points' colours (`chroma`, [`voxel_chroma`]), the part that is
/// nobody's spreads at [`FOREIGN_COLOR_SCALE`] instead into voxels of a person's colours
/// that it does not wear itself ([`person_colored`]), and pays [`COLOR_EDGE_PENALTY_M`]
/// to step into them from its own: a person's arm lying along a robot link is then theirs,
/// as it is not on positions alone.
fn split_people(
    graph: &VoxelGraph,
    cluster: &[u32],
    heads: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    chroma: Option<&[Option<u16>]>,
    cfg: &BoxesConfig,
) -> Vec<(u32, Vec<u32>)> {
    // A person's seed: their head, and their lower legs (so legs beside a box or a
    // pedestal stay theirs: the feet are far from the head along the graph).
    let is_seed = |j: u32, head: u32, d: f32| {
        let (hj, top) = (heights[j as usize], heights[head as usize]);
        (d <= HEAD_RADIUS_M && hj >= top - HEAD_HEIGHT_M)
            || (d <= cfg.column_radius_m && hj < LOW_LEG_FRACTION * top)
    };
    // Seeds: each person's (the nearest head's where columns touch), then nobody's.
    let mut seeds: Vec<Vec<u32>> = vec![Vec::new(); heads.len() + 1];
    for &j in cluster {
        let p = centers[j as usize];
        let nearest = heads
            .iter()
            .enumerate()
            .map(|(k, &h)| (k, xy_dist(p, centers[h as usize])))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, d)) = nearest
            && is_seed(j, heads[k], d)
        {
            seeds[k].push(j);
            continue;
        }
        let ownable = heads.iter().any(|&h| {
            let d = xy_dist(p, centers[h as usize]);
            d <= cfg.max_reach_m + ANCHOR_SLACK_M
                && (heights[j as usize] >= LOW_LEG_FRACTION * heights[h as usize]
                    || d <= LEG_RADIUS_M + ANCHOR_SLACK_M)
        });
        if !ownable {
            seeds[heads.len()].push(j);
        }
    }
    let mut groups = vec![Vec::new(); heads.len()];
    if heads.len() == 1 && seeds[1].is_empty() {
        groups[0] = cluster.to_vec();
    } else {
        // Leaving a head sideways (outward across HEAD_CONTACT_RADIUS_M around its top,
        // within HEAD_CONTACT_DEPTH_M below it) costs the contact penalty: a body goes on
        // from the head down through the neck, while what touches the head or neck from the
        // side is someone else's hand or arm (a pointing arm reaching past a shorter
        // neighbour's head), which then stays nearer its owner along the graph.
        let head_at: Vec<(Vec3, f32)> = heads
            .iter()
            .map(|&h| {
                (
                    centers[h as usize],
                    heights[h as usize] - HEAD_CONTACT_DEPTH_M,
                )
            })
            .collect();
        let penalty = |i: u32, j: u32| {
            let (pi, pj) = (centers[i as usize], centers[j as usize]);
            let (hi, hj) = (heights[i as usize], heights[j as usize]);
            let leaves = head_at.iter().any(|&(top, band)| {
                hi >= band
                    && hj >= band
                    && xy_dist(pi, top) <= HEAD_CONTACT_RADIUS_M
                    && xy_dist(pj, top) > HEAD_CONTACT_RADIUS_M
            });
            if leaves { CONTACT_PENALTY_M } else { 0.0 }
        };
        // What is nobody's spreads at NOBODY_LENGTH_SCALE of the cost (see there).
        let nobody = heads.len();
        let plain = |g: usize, _: u32| {
            if g == nobody {
                NOBODY_LENGTH_SCALE
            } else {
                1.0
            }
        };
        let mut owner =
            graph.split_scaled(centers, cluster, &seeds, plain, |_, i, j| penalty(i, j));
        // With colours, again: the part that is nobody's now spreading slowly through a
        // person's colours that the part it claimed on positions hardly wears
        // (person_colored), and each person slowly through the colours that only another
        // person wears (worn_by_one). Only those costs change: with neither (one person and
        // nothing beyond their reach, or nothing of such a colour) the split is the same.
        if let Some(chroma) = chroma {
            // Here there are two people or more, or a part that is nobody's: the columns'
            // colours serve one of the two tests at least.
            let columns = column_colors(chroma, cluster, heads, centers, cfg.column_radius_m);
            let foreign = (!seeds[nobody].is_empty())
                .then(|| {
                    let claimed: Vec<u32> = cluster
                        .iter()
                        .zip(&owner)
                        .filter(|&(_, &g)| g == nobody)
                        .map(|(&j, _)| j)
                        .collect();
                    person_colored(chroma, cluster, &columns, &claimed)
                })
                .filter(|f| cluster.iter().any(|&j| f[j as usize]));
            let mine = (heads.len() >= 2)
                .then(|| worn_by_one(chroma, cluster, &columns))
                .filter(|m| cluster.iter().any(|&j| m[j as usize].is_some()));
            if foreign.is_some() || mine.is_some() {
                let is_foreign = |j: u32| foreign.as_ref().is_some_and(|f| f[j as usize]);
                // Whether voxel j is of a colour only another person than g wears.
                let others = |g: usize, j: u32| {
                    mine.as_ref()
                        .is_some_and(|m| m[j as usize].is_some_and(|k| k as usize != g))
                };
                let scale = |g: usize, j: u32| {
                    if g == nobody {
                        if is_foreign(j) {
                            FOREIGN_COLOR_SCALE
                        } else {
                            NOBODY_LENGTH_SCALE
                        }
                    } else if others(g, j) {
                        OTHER_COLOR_SCALE
                    } else {
                        1.0
                    }
                };
                // ... and pays COLOR_EDGE_PENALTY_M to step into a person's colours from
                // its own, a person OTHER_COLOR_EDGE_M to step into another's (see there).
                let edge = |g: usize, i: u32, j: u32| {
                    let crosses = g == nobody && is_foreign(j) && !is_foreign(i);
                    let enters = g != nobody && others(g, j) && !others(g, i);
                    penalty(i, j)
                        + if crosses { COLOR_EDGE_PENALTY_M } else { 0.0 }
                        + if enters { OTHER_COLOR_EDGE_M } else { 0.0 }
                };
                owner = graph.split_scaled(centers, cluster, &seeds, scale, edge);
            }
        }
        for (&i, &g) in cluster.iter().zip(&owner) {
            // Group `heads.len()` is nobody's: dropped.
            if let Some(group) = groups.get_mut(g) {
                group.push(i);
            }
        }
    }
    // Whatever is still theirs beyond arm's reach (a shelf's far end) is not them.
    for (group, &head) in groups.iter_mut().zip(heads) {
        let top = centers[head as usize];
        let legs_below = LEG_HEIGHT_FRACTION * heights[head as usize];
        group.retain(|&j| {
            let d = xy_dist(centers[j as usize], top);
            // Below the hips only the legs: a table top beside a person is not them.
            d <= cfg.max_reach_m && (heights[j as usize] >= legs_below || d <= LEG_RADIUS_M)
        });
    }
    let mut groups: Vec<(u32, Vec<u32>)> = heads.iter().copied().zip(groups).collect();
    groups.sort_by_key(|(_, g)| g.first().copied());
    groups
}

/// Geometry mode: the voxels of `group` that are most likely its trunk, whose principal
/// horizontal axis gives the box's yaw as labels mode's torso does ([`person_box`]):
/// those between [`TRUNK_LOW_FRACTION`] and [`TRUNK_HIGH_FRACTION`] of the head's height
/// (hips to chest) within [`TRUNK_RADIUS_M`] of its vertical. Arms hanging at the sides
/// are across the facing direction, as the shoulders and hips; a reaching or pointing
/// arm leaves the radius; the legs, striding along the facing direction, are below.
fn trunk_voxels(group: &[u32], head: u32, centers: &[Vec3], heights: &[f32]) -> Vec<u32> {
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

/// Two people of one cluster whose heads are closer than this, metres (less than an arm's
/// length: touching, not just near), get boxes aligned with the line between their heads
/// ([`close_pair_yaw`]) instead of their trunks' axes. That close they hand something over
/// face to face or work shoulder to shoulder, aligned with that line either way, and each
/// hides the other's front from the cameras: only an arc of each trunk is seen, and its
/// axis can be far off (`handover` 802: two people 0.54 m apart, the taller one's trunk
/// axis 24° off: box IoU 0.49–0.50, under the 0.5 needed, in 13 of 25 frames; 0.52–0.53
/// on the line between the heads). Taking the line for every pair
/// in a cluster (people up to ≈ 1 m apart) won those frames but lowered the mean best IoU
/// in 7 of the 10 fresh `handover` and `robot_cell` groups and lost 4 frames of `handover`
/// 900 (heads 0.71 m apart, whose trunks gave the better axis). Chosen on 802 and 900, then
/// checked on groups never looked at before, 1500–1503, 1600–1603 and 1700–1703:
/// `handover` 100 / 95 / 97% → 100 / 97 / 97%, mean best IoU 0.776 / 0.792 / 0.759 →
/// 0.776 / 0.796 / 0.772; `robot_cell` frames unchanged.
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

/// Geometry mode's split: the part of a cluster no person can own spreads along the
/// graph at this fraction of the length a person's spreads at. It is anchored far from
/// every head (a robot's pedestal and shoulder), so at equal cost it would claim a robot's
/// forearm only about halfway to where the forearm touches someone; at half the cost it
/// claims all of it, also the part that passes a person's elbow and ends beside them
/// (`robot_cell` 701 lost 17 of 100 frames so). The price: where a person's hand rests on
/// a robot, more of their forearm goes to the robot than before. On all seven seed groups
/// of the box study: `robot_cell` geometry 700–703 80% → 96%, 500–503 96% → 97%, 400–403
/// 87% (one frame lost, one won), no other cell changed.
const NOBODY_LENGTH_SCALE: f32 = 0.5;
/// Geometry mode's split with colours: the part that is nobody's spreads into a voxel of a
/// person's colour ([`person_colored`]: a sleeve or a hand reaching along a robot link)
/// at this fraction of a person's cost instead of [`NOBODY_LENGTH_SCALE`].
const FOREIGN_COLOR_SCALE: f32 = 1.5;
/// Geometry mode's split with colours: what the part that is nobody's pays, metres, on an
/// edge from a voxel not of a person's colour into one that is ([`person_colored`]), as a
/// path leaving a head sideways pays [`CONTACT_PENALTY_M`]. A robot link along which a
/// person's arm lies touches every voxel of the arm: the slower spread alone
/// ([`FOREIGN_COLOR_SCALE`], on one 5 cm step from the link) hardly slowed it, and the
/// robot took the arm from the side (`robot_cell` 1101 frame 60: the reaching person's box
/// IoU 0.41; 0.94 with the penalty). With it the robot reaches the arm only along the arm
/// itself, from its tip. On the twelve seed groups of the box study (with the rule of
/// [`person_colored`]): `robot_cell` geometry 1100–1103 85% → 95%, 900–903 94% → 95%, no
/// frame lost in any cell; mean best IoU up in 9 of the 12 `robot_cell` groups (1100–1103
/// 0.794 → 0.807), down 0.001 in one (600–603).
const COLOR_EDGE_PENALTY_M: f32 = 1.0;
/// Geometry mode's split with colours: a person spreads into a voxel of a colour only
/// another person wears ([`worn_by_one`]: a neighbour's sleeve reaching their chest) at
/// this multiple of the cost, and pays [`OTHER_COLOR_EDGE_M`] to step into it from one
/// that is not. Where one person's arm touches another's body below the head, the graph
/// alone gives the arm's far end to the body it touches (nearer that person's head than
/// its own's along the graph); the colours keep it its owner's. With both, on the box
/// study's fifteen seed groups (1,500 frames a preset): `handover` geometry 11 → 4 bad
/// frames, mean best IoU up in every group (0.697 → 0.762 on 900–903, 0.744 → 0.814 on
/// 1100–1103), `robot_cell` 37 → 32 (403 frames 28, 36, 44 and 96: a reaching arm; 1500
/// frame 40), mean
/// best IoU up or equal in every group; `single` unchanged (one person: not used). Flat
/// from 2 to 4 and from 0.3 to 0.8 m.
const OTHER_COLOR_SCALE: f32 = 3.0;
/// See [`OTHER_COLOR_SCALE`], metres.
const OTHER_COLOR_EDGE_M: f32 = 0.5;
/// A colour is one person's only ([`worn_by_one`]) when every other person's column holds
/// less than this fraction of it (with neighbouring bins): an arm reaching across a
/// neighbour's column adds its sleeve there. (0.03, the same as [`PERSON_COLOR_DENSITY`]:
/// one `robot_cell` frame lost, 1101 frame 44; 0.015: two of the five `robot_cell` frames
/// above not won, 403 frames 28 and 44, and one `handover` frame, 1603 frame 84.)
const OTHER_WEARS_DENSITY: f32 = 0.02;
/// A colour is a person's when at least this fraction of the coloured voxels in the column
/// below their head share its chromaticity bin or a neighbouring one ([`person_colored`]).
const PERSON_COLOR_DENSITY: f32 = 0.03;
/// Per voxel, its points' mean colour as a linear-RGB chromaticity bin ([`chroma_bin`]);
/// `None` where it is too dark to tell (black: no colour).
fn voxel_chroma(all: &Voxels, colors: &[[u8; 3]]) -> Vec<Option<u16>> {
    // sRGB to linear, once per byte value.
    let lin: Vec<f32> = (0..=255).map(srgb_to_linear).collect();
    let mut sums = vec![[0f32; 3]; all.centers.len()];
    for (&i, &v) in all.points.iter().zip(&all.point_voxel) {
        if let Some(c) = colors.get(i as usize) {
            for a in 0..3 {
                sums[v as usize][a] += lin[usize::from(c[a])];
            }
        }
    }
    sums.iter()
        .zip(&all.counts)
        .map(|(s, &n)| {
            let total = s[0] + s[1] + s[2];
            // Darker than ~sRGB 60 on average: shading, not a colour.
            if total < 0.045 * 3.0 * n as f32 {
                return None;
            }
            Some(chroma_bin(*s) as u16)
        })
        .collect()
}

/// Per voxel of `cluster` (indexed by voxel): whether the part that is nobody's spreads
/// into it at [`FOREIGN_COLOR_SCALE`] (and pays [`COLOR_EDGE_PENALTY_M`] to enter it):
/// its colour is one of a person's — at least [`PERSON_COLOR_DENSITY`] of the coloured
/// voxels of their column (`people`, [`column_colors`]: head, shirt, trousers, where
/// nothing but the person stands) share its chromaticity bin or a neighbouring one — and
/// that person wears its very bin at least as much as what the part that is nobody's
/// claimed on positions alone (`claimed`) does, as shares of each one's coloured voxels.
/// That part is mostly the robot, so its colours are the robot's; an arm it took along a
/// link is a small share of it. A sleeve or a hand reaching along a robot link then stays
/// its owner's, while the link, of the robot's colour, is still claimed from the pedestal
/// at [`NOBODY_LENGTH_SCALE`]. Where the robot wears a person's colour more than they do
/// the split is as without colours.
///
/// The very bin, compared: a colour lies a bin from both sides' in two cases of the box
/// study. A grey shirt one bin from grey robot joints (`robot_cell` 1101: shirt (15, 17),
/// 30% of the column, 2% of the robot; joints (15–16, 15–16)) is the person's; a shaded
/// orange one bin from the robot's orange, 3.5% of the robot, which an orange shirt makes
/// common in the person's column (`robot_cell` 500 frame 68: robot (31, 16), shade
/// (30, 16), shirt (32–33, 14)), is the robot's. (Before, a colour was the robot's at 10%
/// of its part in the very bin: the shade was then the person's, and with the penalty the
/// robot's shaded voxels stayed in the person's box.)
fn person_colored(
    chroma: &[Option<u16>],
    cluster: &[u32],
    people: &[ChromaHist],
    claimed: &[u32],
) -> Vec<bool> {
    let nobody = ChromaHist::of(chroma, claimed.iter().copied());
    let mut out = vec![false; chroma.len()];
    for &j in cluster {
        if let Some(b) = chroma[j as usize] {
            let robot = nobody.share(b);
            // At least as much: a colour neither wears in its very bin, a bin from a
            // person's (a hand a shade off the face), is the person's.
            out[j as usize] = people
                .iter()
                .any(|p| p.near_at_least(b, PERSON_COLOR_DENSITY) && p.share(b) >= robot);
        }
    }
    out
}

/// A histogram of voxels' chromaticity bins ([`voxel_chroma`]; voxels without a colour
/// are not counted).
struct ChromaHist {
    bins: Vec<u32>,
    total: u32,
}

impl ChromaHist {
    fn of(chroma: &[Option<u16>], members: impl Iterator<Item = u32>) -> ChromaHist {
        let mut bins = vec![0u32; CHROMA_BINS * CHROMA_BINS];
        let mut total = 0u32;
        for j in members {
            if let Some(b) = chroma[j as usize] {
                bins[usize::from(b)] += 1;
                total += 1;
            }
        }
        ChromaHist { bins, total }
    }

    /// Whether at least `density` of the voxels lie within a bin of `b`.
    fn near_at_least(&self, b: u16, density: f32) -> bool {
        let n: u32 = near_chroma_bins(usize::from(b)).map(|k| self.bins[k]).sum();
        self.total > 0 && n as f32 >= density * self.total as f32
    }

    /// The share of the voxels in the very bin `b`.
    fn share(&self, b: u16) -> f32 {
        if self.total == 0 {
            0.0
        } else {
            self.bins[usize::from(b)] as f32 / self.total as f32
        }
    }
}

/// The colours of the column below each of `heads` (within `column_radius_m` of its
/// vertical, among `cluster`): where nothing but that person stands (head, shirt, trousers).
fn column_colors(
    chroma: &[Option<u16>],
    cluster: &[u32],
    heads: &[u32],
    centers: &[Vec3],
    column_radius_m: f32,
) -> Vec<ChromaHist> {
    heads
        .iter()
        .map(|&h| {
            let top = centers[h as usize];
            let column = cluster
                .iter()
                .copied()
                .filter(|&j| xy_dist(centers[j as usize], top) <= column_radius_m);
            ChromaHist::of(chroma, column)
        })
        .collect()
}

/// Per voxel of `cluster` (indexed by voxel): the one person (index into `people`, the
/// colours of each head's column, [`column_colors`]) whose colour it is, `None` for none
/// or several: at least [`PERSON_COLOR_DENSITY`] of the coloured voxels of their column
/// share its chromaticity bin or a neighbouring one, and less than
/// [`OTHER_WEARS_DENSITY`] of every other person's column do. A sleeve reaching a
/// neighbour's chest is then its owner's colour ([`split_people`]).
fn worn_by_one(chroma: &[Option<u16>], cluster: &[u32], people: &[ChromaHist]) -> Vec<Option<u32>> {
    let mut out = vec![None; chroma.len()];
    for &j in cluster {
        if let Some(b) = chroma[j as usize] {
            let mut wearers =
                (0..people.len()).filter(|&k| people[k].near_at_least(b, PERSON_COLOR_DENSITY));
            if let (Some(k), None) = (wearers.next(), wearers.next())
                && people
                    .iter()
                    .enumerate()
                    .all(|(o, p)| o == k || !p.near_at_least(b, OTHER_WEARS_DENSITY))
            {
                out[j as usize] = Some(k as u32);
            }
        }
    }
    out
}

/// How far beyond a person's reach (`max_reach_m`, [`LEG_RADIUS_M`]) a voxel must lie to
/// seed the part of a cluster that is nobody's, metres: a hand stretched a little past
/// the reach limit is cut, but does not pull the person's forearm away with it.
const ANCHOR_SLACK_M: f32 = 0.2;
/// Below this fraction of a person's height lie only their lower legs (knees are at
/// ≈ 0.28 of the height; the fingertips of a hanging arm at ≈ 0.38, a hand reaching to a
/// table higher): those within `column_radius_m` of the head's vertical seed the person,
/// and voxels this low beyond the legs' reach seed the part that is nobody's, without
/// pulling a hand and its forearm away.
const LOW_LEG_FRACTION: f32 = 0.3;
/// Horizontal radius around a head's top that holds all of the head, metres (a head is
/// ≈ 0.1 m in radius; hair, a tilted head and voxel centroids add up to 0.1 m).
const HEAD_CONTACT_RADIUS_M: f32 = 0.2;
/// How far below a head's top leaving it sideways costs the contact penalty (geometry
/// mode's split), metres: the head (≈ 0.22 m) and the neck down to the shoulders' top,
/// where only someone else's arm touches a person from the side (a pointing arm resting
/// on a neighbour's neck). A person's own arms leave lower, from the shoulders. 0.2 (the
/// head alone) on the box study's seven seed groups → 0.3: `handover` geometry 200–203
/// 93% → 95%, 300–303 94% → 99%, 700–703 97% → 98%, `robot_cell` 400–403 87% → 96%,
/// 600–603 97% → 98%; no cell lower.
const HEAD_CONTACT_DEPTH_M: f32 = 0.3;
/// Horizontal radius of a head around its top, metres (a head is ≈ 0.2 m wide).
const HEAD_RADIUS_M: f32 = 0.12;
/// Height of a head below its top, metres (crown to chin ≈ 0.22 m; the shoulders start
/// lower).
const HEAD_HEIGHT_M: f32 = 0.2;
/// Below this fraction of a person's height only their legs are theirs (hips are at
/// ≈ 0.53 of the height; a hand resting lower is cut, a table top beside them too).
const LEG_HEIGHT_FRACTION: f32 = 0.5;
/// Horizontal radius around the head's vertical that holds the legs, metres (a stride
/// or a crouch puts a foot ≈ 0.35 m from it).
const LEG_RADIUS_M: f32 = 0.4;
/// Tops at least this high are taken to be people's when judging head compactness,
/// metres: a workcell robot arm on its base (≈ 1.4 m in bodyseg-synth) stays below.
const TALL_TOP_M: f32 = 1.5;
/// Extra head radius allowed to such tall tops, metres (hair, a tilted head, a
/// neighbour's hand or arm on the head). 0.05 → 0.1 on the box study's seven seed groups:
/// `robot_cell` geometry 400–403 96% → 97%, 500–503 97% → 98%, 600–603 98% → 100% (heads
/// of 1.5–1.8 m with a neighbour's arm on them had a 75th percentile of 0.20–0.24 m); no
/// cell lower. Among the head candidates of all 28 `robot_cell` seeds (25 frames each),
/// none above 1.5 m that was not a head passed the column test.
const TALL_HEAD_SLACK_M: f32 = 0.1;
/// Two heads' tops are at least this far apart horizontally, metres (a head is ≈ 0.2 m
/// wide): a higher top closer than this always hides a lower one.
const MIN_HEAD_GAP_M: f32 = 0.25;
/// A branch leaving a head candidate sideways that rises this much above its top is
/// someone's limb reaching onto it, metres ([`reaching_limbs`]). With it, on the box
/// study's seven seed groups: `robot_cell` geometry 300–303 91% → 94% (a crouching
/// person whose head a neighbour's arm touches from above: 302, frames 44–52), no other
/// cell changed. Without [`MIN_DENSE_FILL`] it also let robot joints touched by a
/// person's arm pass as heads (`robot_cell` 700–703 96% → 90%).
const REACH_RISE_M: f32 = 0.05;
/// A slice of a dense column holds at least this many voxels ([`dense_column`]).
const DENSE_SLICE_VOXELS: usize = 4;
/// Share of dense slices below a head candidate for someone's limb touching it to be
/// left out of its head test ([`dense_column`]).
const MIN_DENSE_FILL: f32 = 0.95;
/// A top hidden by someone's limb lying on it ([`find_heads`]) is a head only at least
/// this high, metres (a crouching adult's head: 1.05–1.4 m in bodyseg-synth). Lower, the
/// tops hidden by a link rising from them in the box study were a robot's base under its
/// upper arm (0.94–0.97 m, `robot_cell`, ten frames of ten seeds). (1.2 → 1.0, with
/// [`MIN_HEAD_AREA_M2`], which keeps out the forearms held before a chest at 1.05–1.2 m
/// that 1.2 was for (`robot_cell` 101 frames 80–88, `handover` 503 frames 16 and 76):
/// `robot_cell` geometry 1100–1103 and 900–903 +2 and +3 frames, crouching people under a
/// neighbour's arm; no frame lost in any preset's fifteen seed groups.)
const LIMB_HIDDEN_MIN_TOP_M: f32 = 1.0;
/// A head's blob (what is connected to its top within a head's height and is not someone
/// else's limb, [`find_heads`]) covers at least this much, m² (as voxels of `voxel_m`: 30
/// at 5 cm). Of the tops that passed the column test in seven seed groups of each preset
/// (100, 300, 500, 800, 1000, 1200, 1600), the heads had 38 voxels or more; the 8 others,
/// none of them within a true box's head height, 11–22: hands held out in hand-overs
/// (`handover` 503, 1201, 1202; 1.04–1.5 m high), which stand over their owner's body
/// column too. (`handover` geometry 1200–1203 97% → 100%; no frame lost in any preset's
/// fifteen seed groups.)
const MIN_HEAD_AREA_M2: f32 = 0.075;
/// Cell of the top-view height map heads are searched in, metres.
const HEIGHT_MAP_CELL_M: f32 = 0.08;
/// Height of the slices of the column test, metres.
const COLUMN_SLICE_M: f32 = 0.1;

/// The heads of one cluster (geometry mode): cells of the top-view height map that are
/// the highest within `head_separation_m`, at least `geometry_min_height_m` high, as large
/// as a head ([`MIN_HEAD_AREA_M2`]), with a column of
/// points below them (`column_radius_m`, `min_column_fill`) reaching down to
/// `max_bottom_m`. Returns one voxel per head (its top), highest first.
fn find_heads(
    graph: &VoxelGraph,
    keep: &[bool],
    cluster: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    cfg: &BoxesConfig,
) -> Vec<u32> {
    let inv = 1.0 / HEIGHT_MAP_CELL_M;
    let cell = |p: Vec3| [(p[0] * inv).floor() as i32, (p[1] * inv).floor() as i32];
    let mut map: FxHashMap<[i32; 2], u32> = FxHashMap::default();
    let higher = |a: u32, b: u32| {
        let (ha, hb) = (heights[a as usize], heights[b as usize]);
        ha > hb || (ha == hb && a < b)
    };
    for &i in cluster {
        let e = map.entry(cell(centers[i as usize])).or_insert(i);
        if higher(i, *e) {
            *e = i;
        }
    }
    let mut tops: Vec<u32> = map
        .values()
        .copied()
        .filter(|&v| heights[v as usize] >= cfg.min_top_m())
        .collect();
    tops.sort_by(|&a, &b| {
        heights[b as usize]
            .total_cmp(&heights[a as usize])
            .then(a.cmp(&b))
    });
    let r = (cfg.head_separation_m * inv).ceil() as i32;
    // The cluster's voxels in horizontal cells as wide as the widest column radius, so
    // that a column test reads the 3 × 3 cells around a top instead of the whole cluster
    // (a wall or a shelf has hundreds of candidate tops).
    let column_cell_m = LEG_RADIUS_M.max(cfg.column_radius_m);
    let column_key = |p: Vec3| {
        [
            (p[0] / column_cell_m).floor() as i32,
            (p[1] / column_cell_m).floor() as i32,
        ]
    };
    let mut columns: FxHashMap<[i32; 2], Vec<u32>> = FxHashMap::default();
    for &i in cluster {
        columns
            .entry(column_key(centers[i as usize]))
            .or_default()
            .push(i);
    }
    // Every voxel of the cluster within `column_cell_m` of `p` horizontally (and more).
    let column_near = |p: Vec3| {
        let k = column_key(p);
        let mut near = Vec::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(vs) = columns.get(&[k[0] + dx, k[1] + dy]) {
                    near.extend_from_slice(vs);
                }
            }
        }
        near
    };
    let min_blob_voxels = MIN_HEAD_AREA_M2 / (cfg.voxel_m * cfg.voxel_m);
    let mut heads: Vec<u32> = Vec::new();
    for v in tops {
        let (p, c) = (centers[v as usize], cell(centers[v as usize]));
        // A higher top within `head_separation_m` hides this one unless it is a separate
        // peak: at least MIN_HEAD_GAP_M away and not joined to anything higher within a
        // head's height below this top (two heads leaning together, not a shoulder).
        // Closer tops hide it, unless they are someone's limb lying on it (see below).
        let mut hiders = Vec::new();
        let mut higher_near = false;
        for dx in -r..=r {
            for dy in -r..=r {
                if let Some(&o) = map.get(&[c[0] + dx, c[1] + dy])
                    && o != v
                    && higher(o, v)
                {
                    let d = xy_dist(centers[o as usize], p);
                    if d < MIN_HEAD_GAP_M {
                        hiders.push(o);
                    }
                    higher_near |= d < cfg.head_separation_m;
                }
            }
        }
        let h = heights[v as usize];
        // A limb lying on the head (a hand or forearm on its way up to its owner's
        // shoulder) neither hides it nor makes it part of something higher, far from
        // every head found so far; near one, such a top is that person's shoulder or
        // forearm under their own or a neighbour's hand. The cheap tests come first: most
        // tops are hidden (a head's or a shoulder's, near a head found before; a wall's).
        // (Also asking the hiding limb to be at most 0.12 m higher than the top, with no
        // top of its own, changed no frame of eleven seed groups and lost one of
        // `robot_cell` 1200-1203.)
        let may_be_under_limb = (LIMB_HIDDEN_MIN_TOP_M..=cfg.max_height_m).contains(&h)
            && heads
                .iter()
                .all(|&k| xy_dist(centers[k as usize], p) >= cfg.head_separation_m);
        let (percent, limit) = if h >= TALL_TOP_M {
            (75, cfg.max_head_radius_m + TALL_HEAD_SLACK_M)
        } else {
            (90, cfg.max_head_radius_m)
        };
        // Someone's limb touching the head from above (an arm reaching onto a crouching
        // person) is left out of the head test, but only where a body fills the column
        // below: a robot's joint stands on thin links and a pedestal. Such a limb lies
        // beyond `limit` of the top ([`reaching_limbs`]), so a top hidden by something
        // nearer, or over a column that is not filled, stays hidden: both are known
        // before the blob is grown.
        let limb_hidden = !hiders.is_empty();
        if limb_hidden
            && !(may_be_under_limb
                && hiders
                    .iter()
                    .all(|&o| xy_dist(centers[o as usize], p) > limit))
        {
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                may_be_under_limb,
                "head candidate dropped: hidden by a higher top"
            );
            continue;
        }
        let near = column_near(p);
        let dense = dense_column(&near, centers, heights, v, cfg) >= MIN_DENSE_FILL;
        if limb_hidden && !dense {
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                "head candidate dropped: hidden, column not dense"
            );
            continue;
        }
        // Only what is connected to the top within the head's height belongs to this
        // head: a neighbour's head or a raised arm beside it (touching it only through
        // the shoulders, lower down) does not.
        let band = h - HEAD_HEIGHT_M;
        let blob = graph.grow(v, |j| {
            keep[j as usize]
                && heights[j as usize] >= band
                && xy_dist(centers[j as usize], p) < cfg.head_separation_m
        });
        let raised = higher_near && blob.iter().any(|&j| heights[j as usize] > h);
        if raised && !may_be_under_limb {
            tracing::trace!(x = p[0], y = p[1], h, "head candidate dropped: raised");
            continue;
        }
        let under_limb = limb_hidden || raised;
        let foreign = if dense {
            reaching_limbs(graph, keep, &blob, centers, heights, v, limit, cfg)
        } else {
            FxHashSet::default()
        };
        if under_limb {
            // What hides the top, and all of the blob higher than it, must be such a limb.
            let limb = |j: &u32| foreign.contains(j);
            if !hiders.iter().all(limb) || blob.iter().any(|j| heights[*j as usize] > h && !limb(j))
            {
                tracing::trace!(
                    x = p[0],
                    y = p[1],
                    h,
                    "head candidate dropped: hidden by something higher that is not a limb"
                );
                continue;
            }
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                "head candidate: the limb lying on it does not hide it"
            );
        }
        // Head test: a head is a compact top. A robot arm's or a shelf's top continues
        // sideways (cylinders sloping down from a joint).
        let mut near_top: Vec<f32> = blob
            .iter()
            .filter(|j| !foreign.contains(j))
            .map(|&j| xy_dist(centers[j as usize], p))
            .collect();
        near_top.sort_by(f32::total_cmp);
        // A percentile, so that a hand raised to the face or a stray voxel does not count:
        // the 90th below TALL_TOP_M; above it (only people reach there) the 75th, as a
        // neighbour's hand or pointing arm touching the head may cover a quarter of it.
        let spread = near_top
            .get(near_top.len() * percent / 100)
            .copied()
            .unwrap_or(0.0);
        if spread > limit {
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                spread,
                "head candidate dropped: not compact"
            );
            continue;
        }
        // A head is a head's size: a hand or a forearm held before a chest or handed over
        // is a compact top too, over a body's column (its owner's), but smaller.
        if (near_top.len() as f32) < min_blob_voxels {
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                voxels = near_top.len(),
                "head candidate dropped: smaller than a head"
            );
            continue;
        }
        let (fill, lowest) = column_fill(&near, centers, heights, v, cfg);
        tracing::trace!(
            x = p[0],
            y = p[1],
            h,
            fill,
            lowest,
            blob = near_top.len(),
            spread,
            "head candidate"
        );
        if fill >= cfg.min_column_fill && lowest <= cfg.max_bottom_m {
            heads.push(v);
        }
    }
    heads
}

/// The voxels of a head candidate's blob (`blob`, grown from the top `top`) that belong to
/// someone else's limb reaching down onto it: beyond `limit` of the top's vertical, joined
/// outward (above the blob's band, within `max_reach_m`) to anything higher than the top.
/// A robot's top continues sideways only downwards (links sloping down from a joint); an
/// arm touching a crouching person's head rises to its owner's shoulder.
#[allow(clippy::too_many_arguments)]
fn reaching_limbs(
    graph: &VoxelGraph,
    keep: &[bool],
    blob: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    top: u32,
    limit: f32,
    cfg: &BoxesConfig,
) -> FxHashSet<u32> {
    let p = centers[top as usize];
    let h = heights[top as usize];
    let band = h - HEAD_HEIGHT_M;
    let xy = |j: u32| xy_dist(centers[j as usize], p);
    let mut seen: FxHashSet<u32> = FxHashSet::default();
    let mut foreign = FxHashSet::default();
    for &s in blob {
        if xy(s) <= limit || seen.contains(&s) {
            continue;
        }
        let branch = graph.grow(s, |j| {
            keep[j as usize] && heights[j as usize] >= band && {
                let d = xy(j);
                d > limit && d <= cfg.max_reach_m
            }
        });
        let rises = branch
            .iter()
            .any(|&j| heights[j as usize] > h + REACH_RISE_M);
        seen.extend(branch.iter().copied());
        if rises {
            tracing::trace!(
                x = p[0],
                y = p[1],
                h,
                voxels = branch.len(),
                "head candidate: a limb reaching onto it is left out of its head test"
            );
            foreign.extend(branch);
        }
    }
    foreign
}

/// The fraction of the [`COLUMN_SLICE_M`] slices between [`LOW_LEG_FRACTION`] of the
/// height of `top` and `top` that hold at least [`DENSE_SLICE_VOXELS`] of `voxels` within
/// `column_radius_m` of its vertical: a person's trunk, neck and head fill every slice; a
/// robot's joint stands on a thin sloping link (one or two voxels a slice). `voxels` are
/// the cluster's, or those of its cells around the top (`column_near` in [`find_heads`]).
fn dense_column(
    voxels: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    top: u32,
    cfg: &BoxesConfig,
) -> f32 {
    let low = LOW_LEG_FRACTION * heights[top as usize];
    let (counts, _) = column_slices(voxels, centers, heights, top, low, |_| cfg.column_radius_m);
    counts.iter().filter(|&&c| c >= DENSE_SLICE_VOXELS).count() as f32 / counts.len() as f32
}

/// The column test of the head candidate `top` (geometry mode): the fraction of the
/// [`COLUMN_SLICE_M`] slices between the ground and the top that hold one of `voxels` (as
/// in [`dense_column`]) within `column_radius_m` of the top's vertical (below
/// [`LOW_LEG_FRACTION`] of the top's height: within [`LEG_RADIUS_M`]), and the lowest such
/// voxel's height.
fn column_fill(
    voxels: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    top: u32,
    cfg: &BoxesConfig,
) -> (f32, f32) {
    // The lower legs may stand farther out: a crouch puts the feet ≈ 0.3 m behind the
    // head, a stride ahead of it; only the column above them must be narrow.
    let legs_below = LOW_LEG_FRACTION * heights[top as usize];
    let (counts, lowest) = column_slices(voxels, centers, heights, top, cfg.ground_tol_m, |hj| {
        if hj < legs_below {
            LEG_RADIUS_M.max(cfg.column_radius_m)
        } else {
            cfg.column_radius_m
        }
    });
    let fill = counts.iter().filter(|&&c| c > 0).count() as f32 / counts.len() as f32;
    (fill, lowest)
}

/// How many of `voxels` lie in each [`COLUMN_SLICE_M`] slice of the column below `top`,
/// from height `from_m` up to the top (at least one slice), counting those at least
/// `from_m` high within `radius(height)` of the top's vertical; and the lowest of them.
fn column_slices(
    voxels: &[u32],
    centers: &[Vec3],
    heights: &[f32],
    top: u32,
    from_m: f32,
    radius: impl Fn(f32) -> f32,
) -> (Vec<usize>, f32) {
    let p = centers[top as usize];
    let h = heights[top as usize];
    let slices = ((h - from_m) / COLUMN_SLICE_M).ceil().max(1.0) as usize;
    let mut counts = vec![0usize; slices];
    let mut lowest = f32::INFINITY;
    for &j in voxels {
        let (q, hj) = (centers[j as usize], heights[j as usize]);
        if hj >= from_m && xy_dist(q, p) <= radius(hj) {
            lowest = lowest.min(hj);
            if let Some(c) = counts.get_mut(((hj - from_m) / COLUMN_SLICE_M) as usize) {
                *c += 1;
            }
        }
    }
    (counts, lowest)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_person_s_colors_the_robot_does_not_wear_slow_the_robot_s_spread() {
        let bin = |r: usize, g: usize| Some((r * CHROMA_BINS + g) as u16);
        // A person at x = 0 (head 0, then 20 voxels in the column: 10 shirt, 10 skin) and
        // beside them, 1 m away, a robot of 40 voxels: 39 orange, one (under the density)
        // in the shirt's colour.
        let (shirt, skin, orange) = (bin(15, 15), bin(25, 17), bin(32, 16));
        let mut centers = vec![[0.0, 0.0, 1.8]];
        let mut chroma = vec![skin];
        for k in 0..20 {
            centers.push([0.05, 0.0, 1.6 - 0.05 * k as f32]);
            chroma.push(if k < 10 { shirt } else { skin });
        }
        for k in 0..40 {
            centers.push([1.0, 0.0, 0.1 + 0.025 * k as f32]);
            chroma.push(if k == 0 { shirt } else { orange });
        }
        // Then the voxels to judge, all out of every column and seed: a sleeve (shirt), a
        // hand (a bin beside the skin's), a robot link (orange), one too dark, one of a
        // colour nobody wears.
        let judged = [shirt, bin(26, 17), orange, None, bin(10, 30)];
        for c in judged {
            centers.push([0.5, 0.0, 1.2]);
            chroma.push(c);
        }
        let cluster: Vec<u32> = (0..centers.len() as u32).collect();
        let robot: Vec<u32> = (21..61).collect();
        let got = person_colored(
            &chroma,
            &cluster,
            &column_colors(&chroma, &cluster, &[0], &centers, 0.2),
            &robot,
        );
        assert_eq!(&got[61..], &[true, true, false, false, false]);
        // The scene with the person in `shirt` (their column's and the judged sleeve) and
        // the robot's voxels `part` (and the judged link) in `robot_color`.
        let dressed = |shirt, part: std::ops::Range<usize>, robot_color| {
            let mut c = chroma.clone();
            c[1..11].fill(shirt);
            c[part].fill(robot_color);
            c[61] = shirt;
            c[63] = robot_color;
            c
        };
        // A shirt of the robot's colour: nothing is slowed any more than without colours.
        let same = dressed(orange, 0..0, orange);
        let got = person_colored(
            &same,
            &cluster,
            &column_colors(&same, &cluster, &[0], &centers, 0.2),
            &robot,
        );
        assert_eq!(&got[61..], &[false, true, false, false, false]);
        // Nothing claimed with a colour (a dark pedestal alone): a person's colours slow it.
        let dark: Vec<Option<u16>> = (0..chroma.len())
            .map(|j| {
                if robot.contains(&(j as u32)) {
                    None
                } else {
                    chroma[j]
                }
            })
            .collect();
        let got = person_colored(
            &dark,
            &cluster,
            &column_colors(&dark, &cluster, &[0], &centers, 0.2),
            &robot,
        );
        assert_eq!(&got[61..], &[true, true, false, false, false]);
        // A grey shirt one bin from the robot's grey joints (half its voxels): the sleeve
        // is still the person's colour, the joints still the robot's.
        let grey = dressed(bin(15, 17), 21..41, bin(15, 16));
        let got = person_colored(
            &grey,
            &cluster,
            &column_colors(&grey, &cluster, &[0], &centers, 0.2),
            &robot,
        );
        assert_eq!(&got[61..], &[true, true, false, false, false]);
        // An orange shirt a bin from the robot's orange, and the robot's shade of it (5% of
        // the robot, a bin from both): the shade is the robot's, which wears its very bin
        // more than the person. (When a colour was the robot's only from 10% of its part
        // on, the shade was the person's.)
        let shaded = dressed(bin(33, 15), 21..23, bin(32, 15));
        let got = person_colored(
            &shaded,
            &cluster,
            &column_colors(&shaded, &cluster, &[0], &centers, 0.2),
            &robot,
        );
        assert_eq!(&got[61..], &[true, true, false, false, false]);
    }

    #[test]
    fn a_color_only_one_person_wears_is_theirs() {
        let bin = |r: usize, g: usize| Some((r * CHROMA_BINS + g) as u16);
        let (skin, red, blue, grey) = (bin(30, 12), bin(40, 10), bin(8, 12), bin(15, 17));
        // Two people 1 m apart, each a column of 40 voxels: 10 skin, then 30 of their shirt
        // (red, blue), in the red one's 3 of them grey (7.5%: theirs), in the blue one's 1
        // (2.5%: under PERSON_COLOR_DENSITY, over OTHER_WEARS_DENSITY).
        let mut centers = vec![[0.0, 0.0, 1.8], [1.0, 0.0, 1.8]];
        let mut chroma = vec![skin, skin];
        for (x, shirt) in [(0.0, red), (1.0, blue)] {
            for k in 0..40 {
                centers.push([x, 0.0, 1.75 - 0.04 * k as f32]);
                chroma.push(match k {
                    0..10 => skin,
                    10..13 if x == 0.0 => grey,
                    39 if x == 1.0 => grey,
                    _ => shirt,
                });
            }
        }
        // Judged, between them and in neither column: a red sleeve, a blue one, a hand,
        // something grey (both wear a little), a colour nobody wears, one too dark.
        for c in [red, blue, skin, grey, bin(20, 30), None] {
            centers.push([0.5, 0.0, 1.3]);
            chroma.push(c);
        }
        let cluster: Vec<u32> = (0..centers.len() as u32).collect();
        let got = worn_by_one(
            &chroma,
            &cluster,
            &column_colors(&chroma, &cluster, &[0, 1], &centers, 0.2),
        );
        assert_eq!(&got[82..], &[Some(0), Some(1), None, None, None, None]);
        // One person: every colour they wear is theirs alone, the grey too.
        let got = worn_by_one(
            &chroma,
            &cluster,
            &column_colors(&chroma, &cluster, &[0], &centers, 0.2),
        );
        assert_eq!(&got[82..], &[Some(0), None, Some(0), Some(0), None, None]);
    }

    /// A person 1.8 m tall at x = 0 (one voxel column: skin head, shirt, trousers) whose
    /// arm (shirt sleeve to x = 0.4 m, then skin) reaches out to x = 0.75 m at 1.45 m, along
    /// and 5 cm above an orange robot link from x = 0.1 m to its pedestal at x = 1.5 m:
    /// voxel centres, chromaticity bins, and the arm's voxels.
    fn arm_along_a_link() -> (Vec<Vec3>, Vec<Option<u16>>, Vec<u32>) {
        let bin = |r: usize, g: usize| Some((r * CHROMA_BINS + g) as u16);
        let (skin, shirt, trousers, orange) = (bin(30, 12), bin(15, 17), bin(5, 9), bin(31, 16));
        let mut centers = Vec::new();
        let mut chroma = Vec::new();
        let mut push = |p: Vec3, c: Option<u16>| {
            centers.push(p);
            chroma.push(c);
            centers.len() as u32 - 1
        };
        for k in 0..=34 {
            let z = 0.1 + 0.05 * k as f32;
            let color = match z {
                z if z >= 1.6 => skin,
                z if z >= 0.9 => shirt,
                _ => trousers,
            };
            push([0.0, 0.0, z], color);
        }
        let arm: Vec<u32> = (1..=15)
            .map(|k| {
                let x = 0.05 * k as f32;
                push([x, 0.0, 1.45], if x <= 0.4 { shirt } else { skin })
            })
            .collect();
        for k in 2..=30 {
            push([0.05 * k as f32, 0.0, 1.4], orange);
        }
        for k in 0..26 {
            push([1.5, 0.0, 0.1 + 0.05 * k as f32], orange);
        }
        (centers, chroma, arm)
    }

    #[test]
    fn an_arm_along_a_robot_link_stays_its_owner_s_by_its_colors() {
        let (centers, chroma, arm) = arm_along_a_link();
        let heights: Vec<f32> = centers.iter().map(|p| p[2]).collect();
        let cfg = BoxesConfig {
            mode: BoxMode::Geometry,
            ..BoxesConfig::default()
        };
        let every = vec![true; centers.len()];
        let graph = VoxelGraph::new(&centers, cfg.person_gap_m, &every);
        let [cluster] = graph.components(&every).try_into().expect("one cluster");
        let head = 34;
        // How many of the arm's voxels are the person's, and whether any of the robot's
        // beyond the arm's reach (its link past x = 0.8 m, its pedestal) is.
        let person = |chroma: Option<&[Option<u16>]>| {
            let groups = split_people(&graph, &cluster, &[head], &centers, &heights, chroma, &cfg);
            let [(h, group)] = groups.as_slice() else {
                panic!("one person: {groups:?}");
            };
            assert_eq!(*h, head);
            let robot = group.iter().any(|&j| centers[j as usize][0] > 0.8);
            (arm.iter().filter(|j| group.contains(j)).count(), robot)
        };
        // On positions alone the robot, spreading along its link, takes most of the arm.
        let (kept, robot) = person(None);
        assert!(
            kept <= 6 && !robot,
            "without colours: {kept} arm voxels, robot {robot}"
        );
        // With colours the robot steps into the sleeve and the skin only through the colour
        // edge's penalty: the arm is the person's, the robot still not. (At the slower
        // spread alone the robot took the arm beyond x ≈ 0.3 m from the side, one short
        // step from the link.)
        let (kept, robot) = person(Some(&chroma));
        assert!(
            kept == arm.len() && !robot,
            "with colours: {kept} arm voxels, robot {robot}"
        );
    }

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

    /// Voxel centres at (`x`, 0, z) for every z in `z_m`.
    fn line(out: &mut Vec<Vec3>, x: f32, z_m: &[f32]) {
        out.extend(z_m.iter().map(|&z| [x, 0.0, z]));
    }

    /// `column_fill` of the highest of `centers` (heights: z), over all of them.
    fn fill_of(centers: &[Vec3]) -> (f32, f32) {
        let heights: Vec<f32> = centers.iter().map(|p| p[2]).collect();
        let top = (0..centers.len() as u32)
            .max_by(|&a, &b| heights[a as usize].total_cmp(&heights[b as usize]))
            .expect("voxels");
        let all: Vec<u32> = (0..centers.len() as u32).collect();
        column_fill(&all, centers, &heights, top, &BoxesConfig::default())
    }

    #[test]
    fn parts_joined_in_a_body_are_adjacent_others_touch() {
        let id = Class::id;
        assert!(adjacent_parts(id(Class::Head), id(Class::Torso)));
        assert!(adjacent_parts(id(Class::LowerArms), id(Class::UpperArms)));
        assert!(adjacent_parts(id(Class::Torso), id(Class::Torso)));
        // A hand on a head or a trunk is a contact, not a joint.
        assert!(!adjacent_parts(id(Class::LowerArms), id(Class::Head)));
        assert!(!adjacent_parts(id(Class::Torso), id(Class::LowerArms)));
        assert!(!adjacent_parts(id(Class::Head), id(Class::UpperArms)));
    }

    #[test]
    fn column_counts_feet_beside_the_head_but_not_a_trunk_beside_it() {
        // Heights at the middle of the 10 cm slices above ground_tol_m (0.05 m), the top
        // at 1.22 m: 12 slices. A crouch: head and trunk above the knees at x = 0
        // (0.5–1.22 m: 8 slices), the lower legs 0.3 m behind (0.1–0.3 m: 3 slices),
        // beyond `column_radius_m`, within a leg's reach.
        let trunk = [0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.22];
        let mut centers = Vec::new();
        line(&mut centers, 0.0, &trunk);
        line(&mut centers, 0.3, &[0.1, 0.2, 0.3]);
        let (fill, lowest) = fill_of(&centers);
        // Counting only the column within 0.2 m: 8 of 12 slices (0.67 < min_column_fill),
        // lowest 0.5 m (> max_bottom_m): the crouching person had no head.
        assert_eq!(fill, 11.0 / 12.0);
        assert_eq!(lowest, 0.1);
        // Something 0.3 m beside the top above the legs' height (a neighbour's trunk)
        // does not fill the column.
        let mut centers = Vec::new();
        line(&mut centers, 0.0, &[1.1, 1.2, 1.22]);
        line(&mut centers, 0.3, &[0.5, 0.6, 0.7, 0.8, 0.9, 1.0]);
        let (fill, lowest) = fill_of(&centers);
        assert_eq!(fill, 2.0 / 12.0);
        assert_eq!(lowest, 1.1);
    }
}
