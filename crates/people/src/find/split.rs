//! Geometry mode's split: one cluster divided along the voxel graph (multi-source
//! Dijkstra) between its people, each seeded with their head and lower legs, and what no
//! person can own (a robot's pedestal and arm, a box, a table), with the points' colours
//! where given; then each person cut to arm's reach.

use crate::config::BoxesConfig;
use crate::find::candidates::{CONTACT_PENALTY_M, Cluster, VoxelHeights};
use crate::find::color::{column_colors, person_colored, worn_by_one};
use crate::find::ground::xy_dist;
use crate::find::heads::{HEAD_HEIGHT_M, LEG_RADIUS_M, LOW_LEG_FRACTION};
use bodyseg_core::math::Vec3;

/// How far beyond a person's reach (`max_reach_m`, [`LEG_RADIUS_M`]) a voxel must lie to
/// seed the part of a cluster that is nobody's, metres: a hand stretched a little past
/// the reach limit is cut, but does not pull the person's forearm away with it.
const ANCHOR_SLACK_M: f32 = 0.2;
/// Horizontal radius around a head's top that holds all of the head, metres (a head is
/// ≈ 0.1 m in radius; hair, a tilted head and voxel centroids add up to 0.1 m).
const HEAD_CONTACT_RADIUS_M: f32 = 0.2;
/// How far below a head's top leaving it sideways costs [`CONTACT_PENALTY_M`], metres:
/// the head (≈ 0.22 m) and the neck down to the shoulders' top, where only someone else's
/// arm touches a person from the side; a person's own arms leave lower, from the shoulders.
const HEAD_CONTACT_DEPTH_M: f32 = 0.3;
/// Horizontal radius of a head around its top, metres (a head is ≈ 0.2 m wide).
const HEAD_RADIUS_M: f32 = 0.12;
/// Below this fraction of a person's height only their legs are theirs (hips are at
/// ≈ 0.53 of the height; a hand resting lower is cut, a table top beside them too).
const LEG_HEIGHT_FRACTION: f32 = 0.5;
/// The part of a cluster no person can own spreads along the graph at this fraction of the
/// length a person's spreads at: it is anchored far from every head (a robot's pedestal
/// and shoulder), so at equal cost it would claim a robot's forearm only about halfway to
/// where it touches someone. The price: where a hand rests on a robot, more of the forearm
/// goes to the robot.
const NOBODY_LENGTH_SCALE: f32 = 0.5;
/// With colours, the part that is nobody's spreads into a voxel of a person's colour
/// ([`person_colored`]: a sleeve or a hand reaching along a robot link) at this fraction
/// of a person's cost instead of [`NOBODY_LENGTH_SCALE`]: slower than a person.
const FOREIGN_COLOR_SCALE: f32 = 1.5;
/// With colours, what the part that is nobody's pays, metres, on an edge from a voxel not
/// of a person's colour into one that is ([`person_colored`]), as much as a contact
/// ([`CONTACT_PENALTY_M`]): a robot link touches every voxel of an arm lying along it, so
/// the slower spread alone hardly slows it; with the penalty the robot reaches the arm only
/// along the arm itself, from its tip.
const COLOR_EDGE_PENALTY_M: f32 = 1.0;
/// With colours, a person spreads into a voxel of a colour only another person wears
/// ([`worn_by_one`]: a neighbour's sleeve reaching their chest) at this multiple of the
/// cost (a ratio): where one person's arm touches another's body below the head, the graph
/// alone gives the arm's far end to the body it touches; its colour keeps it its owner's.
const OTHER_COLOR_SCALE: f32 = 3.0;
/// With colours, what a person pays, metres, to step into a voxel of a colour only another
/// person wears from one that is not ([`OTHER_COLOR_SCALE`]): less than a contact
/// ([`CONTACT_PENALTY_M`]), as a colour is weaker evidence than a step between bodies.
const OTHER_COLOR_EDGE_M: f32 = 0.5;

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
/// its owner's. With the points' colours (`chroma`,
/// [`voxel_chroma`](crate::find::color::voxel_chroma)), the part that is nobody's spreads
/// at [`FOREIGN_COLOR_SCALE`] instead into voxels of a person's colours that it does not
/// wear itself ([`person_colored`]), and pays [`COLOR_EDGE_PENALTY_M`] to step into them
/// from its own: a person's arm lying along a robot link is then theirs, as it is not on
/// positions alone; and each person spreads at [`OTHER_COLOR_SCALE`] into the colours only
/// another person wears ([`worn_by_one`]), paying [`OTHER_COLOR_EDGE_M`] to step into them.
pub(crate) fn split_people(
    cluster: &Cluster,
    heads: &[u32],
    chroma: Option<&[Option<u16>]>,
    cfg: &BoxesConfig,
) -> Vec<(u32, Vec<u32>)> {
    let Cluster {
        graph,
        members,
        at: VoxelHeights { centers, heights },
        ..
    } = *cluster;
    // A person's seed: their head, and their lower legs (so legs beside a box or a
    // pedestal stay theirs: the feet are far from the head along the graph).
    let is_seed = |j: u32, head: u32, d: f32| {
        let (hj, top) = (heights[j as usize], heights[head as usize]);
        (d <= HEAD_RADIUS_M && hj >= top - HEAD_HEIGHT_M)
            || (d <= cfg.column_radius_m && hj < LOW_LEG_FRACTION * top)
    };
    // Seeds: each person's (the nearest head's where columns touch), then nobody's.
    let mut seeds: Vec<Vec<u32>> = vec![Vec::new(); heads.len() + 1];
    for &j in members {
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
        groups[0] = members.to_vec();
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
            graph.split_scaled(centers, members, &seeds, plain, |_, i, j| penalty(i, j));
        // With colours, again: the part that is nobody's now spreading slowly through a
        // person's colours that the part it claimed on positions hardly wears
        // (person_colored), and each person slowly through the colours that only another
        // person wears (worn_by_one). Only those costs change: with neither (one person and
        // nothing beyond their reach, or nothing of such a colour) the split is the same.
        if let Some(chroma) = chroma {
            // Here there are two people or more, or a part that is nobody's: the columns'
            // colours serve one of the two tests at least.
            let columns = column_colors(chroma, members, heads, centers, cfg.column_radius_m);
            let foreign = (!seeds[nobody].is_empty())
                .then(|| {
                    let claimed: Vec<u32> = members
                        .iter()
                        .zip(&owner)
                        .filter(|&(_, &g)| g == nobody)
                        .map(|(&j, _)| j)
                        .collect();
                    person_colored(chroma, members, &columns, &claimed)
                })
                .filter(|f| members.iter().any(|&j| f[j as usize]));
            let mine = (heads.len() >= 2)
                .then(|| worn_by_one(chroma, members, &columns))
                .filter(|m| members.iter().any(|&j| m[j as usize].is_some()));
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
                owner = graph.split_scaled(centers, members, &seeds, scale, edge);
            }
        }
        for (&i, &g) in members.iter().zip(&owner) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::BoxMode;
    use crate::voxel::VoxelGraph;
    use bodyseg_core::math::CHROMA_BINS;

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
        let [members] = graph.components(&every).try_into().expect("one cluster");
        let cluster = Cluster {
            graph: &graph,
            keep: &every,
            members: &members,
            at: VoxelHeights {
                centers: &centers,
                heights: &heights,
            },
        };
        let head = 34;
        // How many of the arm's voxels are the person's, and whether any of the robot's
        // beyond the arm's reach (its link past x = 0.8 m, its pedestal) is.
        let person = |chroma: Option<&[Option<u16>]>| {
            let groups = split_people(&cluster, &[head], chroma, &cfg);
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
}
