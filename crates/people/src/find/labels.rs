//! Labels mode: body-labelled points → voxels → clusters → split between heads (or
//! torsos) → forearm fragments given to the arm they hang on → size filters → boxes on
//! the floor z = 0.

use crate::config::BoxesConfig;
use crate::find::candidates::{
    CONTACT_PENALTY_M, Candidate, HeightSpan, MIN_TORSO_VOXELS, VoxelCloud, clusters, person_box,
};
use crate::find::ground::Plane;
use crate::voxel::{VoxelGraph, Voxels, voxelize};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, LabeledCloud, PersonBox};

/// A labelled body (head and torso) whose lowest voxel is at most this fraction of its
/// height up is a person whose legs the cameras miss (hips at ≈ 0.53 of the height).
const HIDDEN_LEGS_FRACTION: f32 = 0.5;
/// A labelled body's head voxels lie on average at most this far below its top, metres:
/// a head's centre is ≈ 0.1 m below the crown, and a hand raised over the head adds more.
const HEAD_ON_TOP_M: f32 = 0.3;

/// How far a limb fragment may lie from the part it hangs on, metres: an elbow or a knee
/// the cameras do not see (hidden by the limb itself or by someone in front of it) leaves
/// a gap of up to ≈ 0.3 m between an upper and a lower arm.
const FRAGMENT_REACH_M: f32 = 0.35;
/// Limb fragments smaller than this (voxels) stay where they are: a few mislabelled
/// points are not worth moving a box for.
const MIN_FRAGMENT_VOXELS: usize = 5;
/// A fragment is a forearm: at least this fraction of its voxels labelled lower arm.
/// Pieces of other limb labels floating near people are, with a real parser, mostly its
/// mistakes (streaks of flying pixels at depth edges labelled leg or upper arm).
const MIN_FRAGMENT_LOWER_ARM: f32 = 0.6;
/// A fragment's bounding-box diagonal is at most this, metres: a forearm with its hand
/// (≈ 0.45 m); a longer piece labelled lower arm is something else (a robot link).
const MAX_FRAGMENT_EXTENT_M: f32 = 0.6;

/// Labels mode: body-labelled points → voxels → clusters → split on heads (or torsos)
/// → size filters → boxes on the floor z = 0.
pub(crate) fn labels_mode(cloud: &LabeledCloud, cfg: &BoxesConfig) -> Vec<PersonBox> {
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
    let dense: Vec<bool> = v
        .counts
        .iter()
        .map(|&c| c >= cfg.min_voxel_points)
        .collect();
    let graph = VoxelGraph::new(&v.centers, cfg.person_gap_m, &dense);
    // Each voxel's person (0, 1, ... in the order found), u32::MAX for none.
    let mut owner = vec![u32::MAX; v.centers.len()];
    let mut people = 0u32;
    for cluster in clusters(&graph, &dense, cfg.min_voxels) {
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
            let split = graph.split_scaled(
                &v.centers,
                &cluster,
                &seeds,
                |_, _| 1.0,
                |_, i, j| {
                    if adjacent_parts(v.labels[i as usize], v.labels[j as usize]) {
                        0.0
                    } else {
                        CONTACT_PENALTY_M
                    }
                },
            );
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
    let scene = VoxelCloud::new(&v, &cloud.positions_m, Plane::FLOOR);
    let mut boxes = Vec::new();
    let torso = Class::Torso.id();
    for group in groups {
        let trunk: Vec<u32> = group
            .iter()
            .copied()
            .filter(|&j| v.labels[j as usize] == torso)
            .collect();
        let candidate = Candidate {
            id: boxes.len() as u32,
            voxels: &group,
            trunk: &trunk,
            facing: None,
        };
        // A body whose legs the cameras do not see below the hips (behind a robot's base
        // or a table, or cut off by unlabelled points) floats but is a person.
        let legs_hidden = |span: HeightSpan| {
            span.lo_m <= HIDDEN_LEGS_FRACTION * span.hi_m
                && head_on_top(&v, &group, span.hi_m, cfg.min_head_voxels)
        };
        if let Some(b) = person_box(&scene, &candidate, cfg, legs_hidden) {
            boxes.push(b);
        }
    }
    tracing::debug!(boxes = boxes.len(), voxels = v.centers.len(), "labels mode");
    boxes
}

/// Whether the voxels `group` of `v` (top `top_h` above the floor z = 0) are a body with
/// its head on top: at least `min_head_voxels` head voxels, on average within
/// [`HEAD_ON_TOP_M`] of the top, and [`MIN_TORSO_VOXELS`] torso voxels. A parser calls
/// parts of a robot head and torso too, but not with the head on top (its forearms are
/// above them).
fn head_on_top(v: &Voxels, group: &[u32], top_h: f32, min_head_voxels: usize) -> bool {
    let (mut head, mut head_h_sum, mut torso) = (0usize, 0.0f32, 0usize);
    for &i in group {
        let l = v.labels[i as usize];
        if l == Class::Head.id() {
            head += 1;
            head_h_sum += Plane::FLOOR.height(v.centers[i as usize]);
        } else if l == Class::Torso.id() {
            torso += 1;
        }
    }
    head >= min_head_voxels.max(1)
        && torso >= MIN_TORSO_VOXELS
        && head_h_sum / head as f32 >= top_h - HEAD_ON_TOP_M
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Voxels of a 0.2 m wide body from the floor up: per 5 cm layer (from z = 0), the
    /// class of its 4 × 4 voxels.
    fn body(layers: &[Class]) -> Voxels {
        let mut points = Vec::new();
        for (k, class) in layers.iter().enumerate() {
            for i in 0..4 {
                for j in 0..4 {
                    let at = |n: usize| 0.05 * n as f32 + 0.025;
                    points.push((points.len(), [at(i), at(j), at(k)], class.id()));
                }
            }
        }
        voxelize(points.into_iter(), 0.05)
    }

    #[test]
    fn a_body_with_its_head_on_top_keeps_its_box_without_legs_a_robot_does_not() {
        use Class::{Background, Head, LowerArms, Torso};
        // Hidden legs (unlabelled) to 0.8 m, a torso to 1.5 m, a head to 1.75 m.
        let mut person = vec![Background; 16];
        person.extend([Torso; 14]);
        person.extend([Head; 5]);
        let v = body(&person);
        let labelled: Vec<u32> = (16 * 16..v.centers.len() as u32).collect();
        assert!(head_on_top(&v, &labelled, 1.725, 4));
        // Too few head voxels for the configuration: not a body.
        assert!(!head_on_top(&v, &labelled, 1.725, 81));
        // A robot a parser calls head and torso in places: the "head" below its forearms.
        let mut robot = vec![Background; 16];
        robot.extend([Torso; 8]);
        robot.extend([Head; 3]);
        robot.extend([LowerArms; 8]);
        let v = body(&robot);
        let labelled: Vec<u32> = (16 * 16..v.centers.len() as u32).collect();
        assert!(!head_on_top(
            &v,
            &labelled,
            v.centers[v.centers.len() - 1][2],
            4
        ));
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
}
