//! R — remove_nodes (ALGORITHM.md §5.5), and its bridge through noise points.

use crate::graph::{BodyTree, ClusterGraph};
use crate::grid::CellGrid;
use bodyseg_core::Label;
use bodyseg_core::math::Vec3;

/// R — remove_nodes: when the tree is valid, every body-labelled cluster not connected to
/// the tree through a chain of inside / intersect / tree edges *between body-labelled
/// clusters* becomes background. Background clusters stay background; a chain may not pass
/// through them (a floor touches everything). With no valid tree, nothing changes.
pub fn remove_nodes(labels: &[Label], graph: &ClusterGraph, tree: &BodyTree) -> Vec<Label> {
    if !tree.is_valid() {
        return labels.to_vec();
    }
    let k = labels.len();
    let mut reached = vec![false; k];
    // Tree nodes are body-labelled (they never change), and tree edges join them; seeding
    // the search with all of them covers the tree edges.
    let mut stack: Vec<u32> = tree.nodes().collect();
    for &n in &stack {
        reached[n as usize] = true;
    }
    while let Some(a) = stack.pop() {
        for &b in &graph.adjacent[a as usize] {
            if !reached[b as usize] && labels[b as usize].is_body() {
                reached[b as usize] = true;
                stack.push(b);
            }
        }
    }
    labels
        .iter()
        .zip(&reached)
        .map(|(&l, &r)| {
            if l.is_body() && !r {
                Label::BACKGROUND
            } else {
                l
            }
        })
        .collect()
}

/// R's bridge (`remove_through_noise`): after [`remove_nodes`] (`removed`, from
/// `before`), a cluster R turned into background gets its label back when a chain of body
/// points joins it to a tree cluster: points of body-labelled clusters (labels `before`)
/// and noise points the parser labelled body (`own`), in cells of `cell_m` touching one
/// another (26 neighbours, so gaps up to about one cell). Tree clusters are never removed.
///
/// Why: the contact graph R walks joins clusters only, and the points left out of the
/// clustering — labels the parser doubted (`noise_doubt_ratio`), sparse DBSCAN noise — are
/// still the body's surface. A forearm or a foot joined to the body by a strip the parser
/// hesitated on (an elbow, a knee, a hidden ankle) was cut off and removed; an object or a
/// clump of flying pixels with no body points between it and the person still is. Measured
/// on the tune sets of docs/notes/2026-11-30-improved-refinement-tuning.md.
pub fn restore_bridged(
    removed: &[Label],
    before: &[Label],
    positions_m: &[Vec3],
    cluster_of: &[Option<u32>],
    own: &[Label],
    tree: &BodyTree,
    cell_m: f32,
) -> Vec<Label> {
    let mut out = removed.to_vec();
    if !tree.is_valid() || removed == before {
        return out;
    }
    let key = |p: Vec3| p.map(|x| (x / cell_m).floor() as i32);
    // Cells holding body points, then their components (flood fill over 26 neighbours).
    let body: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| match cluster_of[i as usize] {
            Some(c) => before[c as usize].is_body(),
            None => own[i as usize].is_body(),
        })
        .collect();
    let keys: Vec<[i32; 3]> = body.iter().map(|&i| key(positions_m[i as usize])).collect();
    let grid = CellGrid::new(positions_m, &body, &keys, 1);
    let around: Vec<[i32; 3]> = (-1..=1)
        .flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| [x, y, z])))
        .collect();
    let offs = grid.offsets(&around);
    const UNSEEN: u32 = u32::MAX;
    let mut component = vec![UNSEEN; grid.num_cells()];
    let mut next = 0;
    let mut stack = Vec::new();
    for start in 0..grid.num_cells() as u32 {
        if component[start as usize] != UNSEEN {
            continue;
        }
        component[start as usize] = next;
        stack.push(start);
        while let Some(c) = stack.pop() {
            let at = grid.anchor(c);
            for o in 0..around.len() {
                if let Some(n) = grid.near_cell(at, &offs, o)
                    && component[n as usize] == UNSEEN
                {
                    component[n as usize] = next;
                    stack.push(n);
                }
            }
        }
        next += 1;
    }
    // Per body point, its cell's component.
    let mut component_of = vec![UNSEEN; positions_m.len()];
    for c in 0..grid.num_cells() as u32 {
        for &i in &grid.ids()[grid.range(c)] {
            component_of[i as usize] = component[c as usize];
        }
    }
    // The components the tree lies in (tree clusters are body clusters: all in the grid),
    // and those of each removed cluster (body clusters before R).
    let in_tree: Vec<bool> = (0..before.len() as u32).map(|c| tree.contains(c)).collect();
    let mut with_tree = vec![false; next as usize];
    for (&id, c) in component_of.iter().zip(cluster_of) {
        if let Some(c) = c
            && in_tree[*c as usize]
            && id != UNSEEN
        {
            with_tree[id as usize] = true;
        }
    }
    for (&id, c) in component_of.iter().zip(cluster_of) {
        if let Some(c) = c {
            let c = *c as usize;
            if out[c] != before[c] && id != UNSEEN && with_tree[id as usize] {
                out[c] = before[c];
            }
        }
    }
    out
}
