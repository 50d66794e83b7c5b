//! Label-aware DBSCAN (Ester et al. 1996; ALGORITHM.md §5.1), exact and grid-accelerated.
//!
//! Distance: `d(p, q) = ‖p − q‖ + λ·[label(p) ≠ label(q)]` with λ = `label_penalty_m`.
//! With λ ≥ eps (the default, λ = ∞) points of different labels are never neighbours, so
//! the clustering is DBSCAN run separately on each label's points: that is how it is run
//! (rayon across labels). A finite λ < eps runs one grid over all points with the
//! label-aware neighbour test. `unknown` points never take part: they are noise.
//!
//! Definitions (the reference [`dbscan_brute_force`] implements them literally):
//! - core point: at least `min_points` points (itself included) within distance ≤ eps;
//! - clusters: connected components of core points (core q within eps of core p);
//! - border point: a non-core point within eps of a core point; it joins the cluster of its
//!   nearest core point, ties going to the core point with the smaller index;
//! - cluster ids are assigned in order of each cluster's smallest point index;
//! - a cluster's label is the most common label among its points (ties: smaller class id);
//!   with λ ≥ eps all its points share one label.
//!
//! Distances are compared squared, with [`bodyseg_core::math::dist2`] in `f32`, in both the
//! fast path and the reference, so both round identically and results are equal exactly.
//!
//! Speed: points are binned into the crate's grid (`grid.rs`) with cells of side
//! slightly under eps/√3, so a cell's diagonal is below eps: a cell holding ≥ `min_points`
//! points makes them all core without a single distance computation, and only the 5×5×5
//! block of cells around a point can hold its neighbours. Neighbour counting visits the
//! cells nearest first, adds whole cells whose points' box lies within eps and stops as
//! soon as `min_points` is reached; cells are looked up as they are needed, so a point
//! whose nearest cells already hold `min_points` neighbours touches no others.
//!
//! Any finite input is safe: a cloud so wide, or an eps so small, that the extent would
//! need more than 2^30 (`grid::MAX_CELLS_PER_AXIS`) cells per axis gets wider cells, and
//! then the shortcuts that need a cell's diagonal below eps are not taken (the result is
//! the same, found by distance tests).

use crate::grid::{Aabb, GridFrame};
use bodyseg_core::math::{Vec3, dist2};
use bodyseg_core::{Label, NUM_CLASSES};
use rayon::prelude::*;

mod brute_force;
mod connect;
mod counting;
mod group;
pub use brute_force::dbscan_brute_force;
use connect::connect;
use counting::core_points;
pub use group::{Clustering, DbscanParams};
use group::{GroupGrid, GroupResult, Thresholds, assemble, cell_side_m};

/// Runs label-aware DBSCAN on `positions_m` (any frame, metres) with their `labels`.
///
/// # Panics
/// Never for valid parameters; `positions_m` and `labels` must have equal length (checked
/// by the caller, `refine` validates its input).
pub fn dbscan(positions_m: &[Vec3], labels: &[Label], params: &DbscanParams) -> Clustering {
    dbscan_with_cells(positions_m, labels, params, false).0
}

/// [`dbscan`], and with `want_cells` the clustered points binned in DBSCAN's cells
/// ([`ClusteredCells`], for N's nearest-point search), when the label groups' grids allow.
pub(crate) fn dbscan_with_cells(
    positions_m: &[Vec3],
    labels: &[Label],
    params: &DbscanParams,
    want_cells: bool,
) -> (Clustering, Option<ClusteredCells>) {
    debug_assert_eq!(positions_m.len(), labels.len());
    let n = positions_m.len();
    let separate_labels = params.label_penalty_m >= params.eps_m;
    // Every labelled point, and their box: one frame of cells for all the label groups,
    // so that their cells line up (N's index is then built by merging them).
    // Each group's points with their tight box (the box of the group's grid).
    let groups: Vec<(Vec<u32>, Aabb)> = if separate_labels {
        // By runs of one label (points in image order: ~20 on sensor clouds), so that a
        // run's indices go in one `extend` and its box grows in registers; the runs are
        // listed first, so that each group's list is allocated at its size (no growth
        // by reallocation and copy). Each group still takes its points in index order,
        // so the lists and boxes are the same.
        let mut runs: Vec<(u32, u32, usize)> = Vec::new();
        let mut sizes = [0usize; NUM_CLASSES];
        let mut i = 0;
        while i < n {
            let l = labels[i];
            let end = labels[i..]
                .iter()
                .position(|&m| m != l)
                .map_or(n, |k| i + k);
            if let Some(c) = l.class() {
                runs.push((i as u32, end as u32, c.index()));
                sizes[c.index()] += end - i;
            }
            i = end;
        }
        let mut g: Vec<(Vec<u32>, Aabb)> = sizes
            .iter()
            .map(|&m| (Vec::with_capacity(m), Aabb::EMPTY))
            .collect();
        for &(start, end, c) in &runs {
            let (ids, b) = &mut g[c];
            ids.extend(start..end);
            let mut run_box = *b;
            for &p in &positions_m[start as usize..end as usize] {
                run_box.grow(p);
            }
            *b = run_box;
        }
        g.retain(|(v, _)| !v.is_empty());
        g
    } else {
        let all: Vec<u32> = (0..n as u32)
            .filter(|&i| !labels[i as usize].is_unknown())
            .collect();
        let b = Aabb::of_ids(positions_m, &all);
        vec![(all, b)]
    };
    let mut bounds = Aabb::EMPTY;
    for (_, b) in &groups {
        bounds.union(b);
    }
    if groups.is_empty() {
        bounds = Aabb::of_ids(positions_m, &[]);
    }
    let frame = GridFrame::covering_box(bounds, cell_side_m(params.eps_m));
    let group_results: Vec<GroupResult> = groups
        .par_iter()
        .map(|(idx, b)| cluster_group(positions_m, labels, idx, b, params, &frame))
        .collect();
    let clustering = assemble(n, labels, &group_results, separate_labels);
    let cells = want_cells
        .then(|| ClusteredCells::merge(&frame, &group_results))
        .flatten();
    (clustering, cells)
}

/// The clustered points (core and border) of a clustering in DBSCAN's cells, all labels
/// together: N's nearest-point index, built from the label groups' sorted cells without
/// binning the points again.
pub(crate) type ClusteredCells = crate::grid::nn::NnIndex;

impl ClusteredCells {
    /// `None` when the groups' frame is not one [`NnIndex::from_cells`] takes.
    fn merge(frame: &GridFrame, results: &[GroupResult]) -> Option<ClusteredCells> {
        let parts: Vec<crate::grid::nn::CellPart<'_>> = results
            .iter()
            .filter_map(|r| {
                r.grid
                    .as_ref()
                    .map(|(g, b)| (g, b.as_slice(), r.component.as_slice()))
            })
            .collect();
        crate::grid::nn::NnIndex::from_cells(frame, &parts)
    }
}

/// Clusters one group of points (one label, or all points in the finite-penalty mode).
fn cluster_group(
    positions: &[Vec3],
    labels: &[Label],
    idx: &[u32],
    bounds: &Aabb,
    params: &DbscanParams,
    frame: &GridFrame,
) -> GroupResult {
    let m = idx.len();
    let min_pts = params.min_points;
    if m == 0 || min_pts > m {
        return GroupResult {
            ids: idx.to_vec(),
            component: vec![None; m],
            first: Vec::new(),
            is_core: vec![false; m],
            grid: None,
        };
    }
    let th = Thresholds::new(params);
    // One label in the group: no label test in the inner loops.
    let mixed = params.label_penalty_m < params.eps_m;
    let mut g = GroupGrid::build(positions, labels, idx, params.eps_m, frame, bounds, mixed);
    let (mut core, border_cells) = if mixed {
        core_points::<true>(&g, min_pts, th)
    } else {
        core_points::<false>(&g, min_pts, th)
    };
    let core_end = core_first(&mut g, &mut core);
    let core_box = core_boxes(&g, &core_end);
    let (uf, all_whole) = connect(&g, &core_end, &core_box, th);
    let mut uf = uf;
    let unit = |c: u32, i: usize| -> u32 { if all_whole { c } else { i as u32 } };
    let core_range = |c: u32| g.grid.range(c).start..core_end[c as usize] as usize;

    // Components of core points, border points to their nearest core point's, numbered
    // densely as they are met (any order: global ids are assigned later, by each
    // component's smallest point index, noted on the way in `first`). Roots are
    // union-find elements, so a table over them replaces a hash map.
    let ids = g.grid.ids();
    let mut dense = vec![u32::MAX; uf.0.len()];
    let mut first: Vec<u32> = Vec::new();
    let mut dense_of = |root: u32, id: u32| -> u32 {
        let d = &mut dense[root as usize];
        if *d == u32::MAX {
            *d = first.len() as u32;
            first.push(id);
        } else {
            let f = &mut first[*d as usize];
            *f = (*f).min(id);
        }
        *d
    };
    let mut component = vec![None; m];
    for c in 0..g.num_cells() as u32 {
        let cr = core_range(c);
        if all_whole {
            // One union-find unit per cell: its core points share its root.
            let Some(&min_id) = ids[cr.clone()].iter().min() else {
                continue;
            };
            let d = dense_of(uf.find(c), min_id);
            component[cr].fill(Some(d));
        } else {
            for i in cr {
                component[i] = Some(dense_of(uf.find(i as u32), ids[i]));
            }
        }
    }
    let reach2 = th.same2.max(th.diff2);
    let mut listed = 0;
    for c in 0..g.num_cells() as u32 {
        let r = g.grid.range(c);
        let border = core_end[c as usize] as usize..r.end;
        if border.is_empty() {
            continue;
        }
        debug_assert_eq!(border_cells.cells[listed], c);
        let nbrs = border_cells.list(listed);
        listed += 1;
        for i in border {
            let p = g.grid.pts()[i];
            // (distance², index of the core point, its union-find unit)
            let mut best: Option<(f32, u32, u32)> = None;
            for &d in nbrs {
                let bound = core_box[d as usize].dist2(p);
                if bound > reach2 || best.is_some_and(|(b2, _, _)| bound > b2) {
                    continue;
                }
                for j in core_range(d) {
                    let d2 = dist2(p, g.grid.pts()[j]);
                    if d2 > g.threshold(th, i, j) {
                        continue;
                    }
                    let oj = g.grid.ids()[j];
                    let better = match best {
                        None => true,
                        Some((b2, bo, _)) => d2 < b2 || (d2 == b2 && oj < bo),
                    };
                    if better {
                        best = Some((d2, oj, unit(d, j)));
                    }
                }
            }
            if let Some((_, _, u)) = best {
                component[i] = Some(dense_of(uf.find(u), ids[i]));
            }
        }
    }
    GroupResult {
        ids: Vec::new(),
        component,
        first,
        is_core: core,
        grid: Some((g.grid, g.bbox)),
    }
}

/// Reorders each cell so its core points come first (with `core`); returns per cell the
/// end of its core points.
fn core_first(g: &mut GroupGrid, core: &mut [bool]) -> Vec<u32> {
    let mut core_end = vec![0u32; g.num_cells()];
    for c in 0..g.num_cells() as u32 {
        let r = g.grid.range(c);
        // The leading core points stay where they are (a swap with itself): most cells are
        // all core, and then nothing moves.
        let lead = core[r.clone()].iter().take_while(|&&k| k).count();
        let first_other = r.start + lead;
        let mut w = first_other;
        let (ids, pts) = g.grid.points_mut();
        for i in first_other..r.end {
            if core[i] {
                ids.swap(w, i);
                pts.swap(w, i);
                if !g.lbl.is_empty() {
                    g.lbl.swap(w, i);
                }
                core.swap(w, i);
                w += 1;
            }
        }
        core_end[c as usize] = w as u32;
    }
    core_end
}

/// Per cell, the tight box of its core points (the cell's box when all are core).
fn core_boxes(g: &GroupGrid, core_end: &[u32]) -> Vec<Aabb> {
    (0..g.num_cells() as u32)
        .map(|c| {
            let r = g.grid.range(c);
            let end = core_end[c as usize] as usize;
            if end == r.end {
                g.bbox[c as usize]
            } else {
                Aabb::of(&g.grid.pts()[r.start..end])
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::group::{NEAR_OFFSETS, Neighbours, forward_offsets};
    use super::*;

    /// The near lists read by rows of the table (core counting's, connecting's forward
    /// ones) are the lists looked up offset by offset, in the same order.
    #[test]
    fn near_lists_by_rows_equal_the_lookups_by_offset() {
        // Points at the centres of a 7×7×7 block of cells, a third of the cells empty.
        let eps = 0.05f32;
        let side = cell_side_m(eps) as f32;
        // (A point at the origin puts the frame's corner there: the centres are then half
        // a cell from every cell boundary.)
        let mut pos: Vec<Vec3> = vec![[0.0; 3]];
        for z in 0..7 {
            for y in 0..7 {
                for x in 0..7 {
                    if (x * 7 + y * 3 + z * 5) % 3 != 0 {
                        pos.push([x, y, z].map(|k| (k as f32 + 0.5) * side));
                    }
                }
            }
        }
        let labels = vec![Label::BACKGROUND; pos.len()];
        let idx: Vec<u32> = (0..pos.len() as u32).collect();
        let bounds = Aabb::of(&pos);
        let frame = GridFrame::covering_box(bounds, cell_side_m(eps));
        let g = GroupGrid::build(&pos, &labels, &idx, eps, &frame, &bounds, false);
        assert!(g.num_cells() > 200, "{} cells", g.num_cells());
        let (forward, near) = forward_offsets();
        let forward_offs = g.grid.offsets(forward);
        let mut nbrs = Neighbours::new();
        let (mut by_offset, mut by_rows) = (vec![0u32; 125], vec![0u32; 125]);
        for c in 0..g.num_cells() as u32 {
            let at = g.grid.anchor(c);
            let n = g
                .grid
                .near_cells(at, &g.offs, 0..NEAR_OFFSETS, &mut by_offset);
            assert_eq!(nbrs.at(&g, c).near(), &by_offset[..n], "near, cell {c}");
            let n = g
                .grid
                .near_cells(at, &forward_offs, 0..near, &mut by_offset);
            let m = connect::forward_near_cells(&g, at, &forward_offs, near, &mut by_rows);
            assert_eq!(&by_rows[..m], &by_offset[..n], "forward, cell {c}");
        }
    }
}
