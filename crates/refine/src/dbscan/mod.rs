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
//! Speed: points are binned into the crate's grid (`grid/`) with cells of side
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

use crate::grid::{Aabb, CellGrid, GridFrame};
use bodyseg_core::math::{Vec3, dist2};
use bodyseg_core::{Label, NUM_CLASSES};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

mod core_points;
mod group;
use core_points::core_points;
pub use group::DbscanParams;
use group::{GroupGrid, NEAR_OFFSETS, Neighbours, Thresholds, cell_side_m, forward_offsets};

/// The result of a clustering: per point its cluster (or noise), whether it is core, and
/// per cluster its label.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Clustering {
    /// Per input point: cluster id, or `None` for noise (and for every unknown point).
    pub cluster_of: Vec<Option<u32>>,
    /// Per input point: true when it is a core point.
    pub is_core: Vec<bool>,
    /// Per cluster id: its label (never unknown).
    pub cluster_labels: Vec<Label>,
}

impl Clustering {
    /// Number of clusters.
    pub fn num_clusters(&self) -> usize {
        self.cluster_labels.len()
    }

    /// Number of noise points.
    pub fn num_noise(&self) -> usize {
        self.cluster_of.iter().filter(|c| c.is_none()).count()
    }
}

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
    let mut bounds = Aabb::EMPTY;
    let groups: Vec<Vec<u32>> = if separate_labels {
        let mut g: Vec<Vec<u32>> = vec![Vec::new(); NUM_CLASSES];
        for (i, l) in labels.iter().enumerate() {
            if let Some(c) = l.class() {
                g[c.index()].push(i as u32);
                bounds.grow(positions_m[i]);
            }
        }
        g.retain(|v| !v.is_empty());
        g
    } else {
        let all: Vec<u32> = (0..n as u32)
            .filter(|&i| !labels[i as usize].is_unknown())
            .collect();
        bounds = Aabb::of_ids(positions_m, &all);
        vec![all]
    };
    let frame = GridFrame::covering_box(bounds, cell_side_m(params.eps_m));
    let group_results: Vec<GroupResult> = groups
        .par_iter()
        .map(|idx| cluster_group(positions_m, labels, idx, params, &frame))
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

/// Per-group output: for each point of the group (in any order) its index, its local
/// component and whether it is core; the group's grid, whose stored points are in the
/// order of `ids`, with the box of each cell's points (none for a group too small to
/// cluster).
struct GroupResult {
    ids: Vec<u32>,
    component: Vec<Option<u32>>,
    is_core: Vec<bool>,
    grid: Option<(CellGrid, Vec<Aabb>)>,
}

/// Gives global cluster ids (ordered by smallest point index) and cluster labels.
/// `one_label`: every group holds one label (so does each of its clusters, whose label is
/// then its points' without a vote).
fn assemble(n: usize, labels: &[Label], results: &[GroupResult], one_label: bool) -> Clustering {
    let mut is_core = vec![false; n];
    // (smallest point index, group, local component) for every component.
    let mut comps: Vec<(u32, usize, u32)> = Vec::new();
    // Per group, per local component: its global id (set below).
    let mut global: Vec<Vec<u32>> = Vec::with_capacity(results.len());
    for (g, res) in results.iter().enumerate() {
        let idx = &res.ids;
        let ncomp = res
            .component
            .iter()
            .flatten()
            .map(|&c| c + 1)
            .max()
            .unwrap_or(0);
        let mut first = vec![u32::MAX; ncomp as usize];
        for (&i, (&c, &core)) in idx.iter().zip(res.component.iter().zip(&res.is_core)) {
            is_core[i as usize] = core;
            if let Some(c) = c {
                first[c as usize] = first[c as usize].min(i);
            }
        }
        comps.extend(first.iter().enumerate().map(|(c, &f)| (f, g, c as u32)));
        global.push(vec![u32::MAX; ncomp as usize]);
    }
    comps.sort_unstable();
    for (id, &(_, g, c)) in comps.iter().enumerate() {
        global[g][c as usize] = id as u32;
    }
    let mut cluster_of = vec![None; n];
    let cluster_labels = if one_label {
        for (g, res) in results.iter().enumerate() {
            for (&i, &c) in res.ids.iter().zip(&res.component) {
                if let Some(c) = c {
                    cluster_of[i as usize] = Some(global[g][c as usize]);
                }
            }
        }
        // The majority of one label is that label (as `majority_label` names it).
        comps
            .iter()
            .map(|&(first, _, _)| {
                let class = labels[first as usize].class().map_or(0, |c| c.index());
                Label::from_id(class as u8).unwrap_or(Label::BACKGROUND)
            })
            .collect()
    } else {
        let mut votes = vec![[0u32; NUM_CLASSES]; comps.len()];
        for (g, res) in results.iter().enumerate() {
            for (&i, &c) in res.ids.iter().zip(&res.component) {
                if let Some(c) = c {
                    let id = global[g][c as usize];
                    cluster_of[i as usize] = Some(id);
                    if let Some(class) = labels[i as usize].class() {
                        votes[id as usize][class.index()] += 1;
                    }
                }
            }
        }
        votes.iter().map(majority_label).collect()
    };
    Clustering {
        cluster_of,
        is_core,
        cluster_labels,
    }
}

/// Most common class (ties: smaller id).
fn majority_label(votes: &[u32; NUM_CLASSES]) -> Label {
    let mut best = 0;
    for c in 1..NUM_CLASSES {
        if votes[c] > votes[best] {
            best = c;
        }
    }
    Label::from_id(best as u8).unwrap_or(Label::BACKGROUND)
}

/// Minimal union-find over cells (path halving, union by index).
struct UnionFind(Vec<u32>);

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind((0..n as u32).collect())
    }
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let up = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = up;
            x = up;
        }
        x
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// Clusters one group of points (one label, or all points in the finite-penalty mode).
fn cluster_group(
    positions: &[Vec3],
    labels: &[Label],
    idx: &[u32],
    params: &DbscanParams,
    frame: &GridFrame,
) -> GroupResult {
    let m = idx.len();
    let min_pts = params.min_points;
    if m == 0 || min_pts > m {
        return GroupResult {
            ids: idx.to_vec(),
            component: vec![None; m],
            is_core: vec![false; m],
            grid: None,
        };
    }
    let th = Thresholds::new(params);
    // One label in the group: no label test in the inner loops.
    let mixed = params.label_penalty_m < params.eps_m;
    let mut g = GroupGrid::build(positions, labels, idx, params.eps_m, frame);
    let mut core = if mixed {
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

    // Components of core points, border points to their nearest core point.
    let mut component = vec![None; m];
    for c in 0..g.num_cells() as u32 {
        for i in core_range(c) {
            component[i] = Some(uf.find(unit(c, i)));
        }
    }
    let reach2 = th.same2.max(th.diff2);
    let mut nbrs = Neighbours::new();
    for c in 0..g.num_cells() as u32 {
        let r = g.grid.range(c);
        let border = core_end[c as usize] as usize..r.end;
        if border.is_empty() {
            continue;
        }
        let nbrs = nbrs.at(&g, c).all(&g);
        for i in border {
            let p = g.grid.pts()[i];
            let li = g.lbl[i];
            // (distance², index of the core point, its union-find unit)
            let mut best: Option<(f32, u32, u32)> = None;
            for &d in nbrs {
                let bound = core_box[d as usize].dist2(p);
                if bound > reach2 || best.is_some_and(|(b2, _, _)| bound > b2) {
                    continue;
                }
                for j in core_range(d) {
                    let d2 = dist2(p, g.grid.pts()[j]);
                    if d2 > th.get(li, g.lbl[j]) {
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
                component[i] = Some(uf.find(u));
            }
        }
    }
    // Renumber roots densely (any order; global ids are assigned later). Roots are
    // union-find elements, so a table over them replaces a hash map.
    let mut dense = vec![u32::MAX; uf.0.len()];
    let mut next = 0u32;
    for c in component.iter_mut().flatten() {
        let d = &mut dense[*c as usize];
        if *d == u32::MAX {
            *d = next;
            next += 1;
        }
        *c = *d;
    }
    GroupResult {
        ids: g.grid.ids().to_vec(),
        component,
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
        let (ids, pts) = g.grid.points_mut();
        let mut w = r.start;
        for i in r {
            if core[i] {
                ids.swap(w, i);
                pts.swap(w, i);
                g.lbl.swap(w, i);
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

/// Connects core points (core q within eps of core p): the union-find over cells when
/// every cell is whole (all its core points are neighbours of one another, a small array
/// that stays in L1), over stored points otherwise; true in the first case.
fn connect(
    g: &GroupGrid,
    core_end: &[u32],
    core_box: &[Aabb],
    th: Thresholds,
) -> (UnionFind, bool) {
    let ncells = g.num_cells();
    let core_range = |c: u32| g.grid.range(c).start..core_end[c as usize] as usize;
    let has_core = |c: u32| core_end[c as usize] as usize > g.grid.range(c).start;
    let reach2 = th.same2.max(th.diff2);
    let all_whole = g.whole.iter().all(|&w| w);
    let unit = |c: u32, i: usize| -> u32 { if all_whole { c } else { i as u32 } };
    let mut uf = UnionFind::new(if all_whole {
        ncells
    } else {
        g.grid.pts().len()
    });
    let pts = g.grid.pts();
    if !all_whole {
        for c in 0..ncells as u32 {
            let r = core_range(c);
            for i in r.clone() {
                for j in r.start..i {
                    if g.whole[c as usize] || dist2(pts[i], pts[j]) <= th.get(g.lbl[i], g.lbl[j]) {
                        uf.union(i as u32, j as u32);
                    }
                }
            }
        }
    }
    let (forward, near) = forward_offsets();
    let offs = g.grid.offsets(&forward);
    // Joins the core points of cells `c` and `d` that lie within eps of each other.
    let link = |uf: &mut UnionFind, c: u32, d: u32| {
        let (ra, rb) = (core_range(c), core_range(d));
        let whole_c = g.whole[c as usize];
        if whole_c && g.whole[d as usize] {
            // Already joined (the common case on a surface): nothing to test.
            if uf.find(unit(c, ra.start)) == uf.find(unit(d, rb.start)) {
                return;
            }
            if core_box[c as usize].gap2(&core_box[d as usize]) > reach2 {
                return;
            }
            if let Some((i, j)) = any_pair(g, ra, rb, core_box[d as usize], th) {
                uf.union(unit(c, i), unit(d, j));
            }
        } else {
            if core_box[c as usize].gap2(&core_box[d as usize]) > reach2 {
                return;
            }
            for i in ra {
                for j in rb.clone() {
                    if dist2(pts[i], pts[j]) <= th.get(g.lbl[i], g.lbl[j]) {
                        uf.union(i as u32, j as u32);
                    }
                }
            }
        }
    };
    // The 3×3×3 blocks first (forward offsets: each pair once), which join almost
    // everything, so that the farther pairs are mostly settled by one `find`.
    let mut found = vec![0u32; 125];
    for c in 0..ncells as u32 {
        if !has_core(c) {
            continue;
        }
        let n = g
            .grid
            .near_cells(g.grid.anchor(c), &offs, 0..near, &mut found);
        // With all cells whole the union-find is over cells: `c`'s root, found again only
        // after a join, settles most pairs (joined already) with one `find`.
        let mut root_c = if all_whole { uf.find(c) } else { u32::MAX };
        for &d in &found[..n] {
            if !has_core(d) || (all_whole && uf.find(d) == root_c) {
                continue;
            }
            link(&mut uf, c, d);
            if all_whole {
                root_c = uf.find(c);
            }
        }
    }
    if !all_whole {
        for c in 0..ncells as u32 {
            if !has_core(c) {
                continue;
            }
            let n = g
                .grid
                .near_cells(g.grid.anchor(c), &offs, near..forward.len(), &mut found);
            for &d in &found[..n] {
                if has_core(d) {
                    link(&mut uf, c, d);
                }
            }
        }
        return (uf, all_whole);
    }
    // The far shells (5×5×5 blocks less their 3×3×3), from the cells outside the largest
    // component only, in both directions: a pair with a cell outside it is met from that
    // cell, and a pair inside it is joined already. On a body surface the largest
    // component holds almost every cell, so few cells look their far shell up.
    let mut size = vec![0u32; ncells];
    for c in 0..ncells as u32 {
        if has_core(c) {
            size[uf.find(c) as usize] += 1;
        }
    }
    // A cell of the largest component (its root may change as others join it).
    let Some(largest) = (0..ncells as u32).max_by_key(|&r| size[r as usize]) else {
        return (uf, all_whole);
    };
    for c in 0..ncells as u32 {
        // Skipped: `c` is joined to the largest component, so is every cell skipped, and
        // a pair of cells not both skipped is met from the other one.
        if !has_core(c) || uf.find(c) == uf.find(largest) {
            continue;
        }
        let n = g
            .grid
            .shell2_cells(g.grid.anchor(c), &g.offs, NEAR_OFFSETS..125, &mut found);
        for &d in &found[..n] {
            if has_core(d) {
                link(&mut uf, c, d);
            }
        }
    }
    (uf, all_whole)
}

/// Some pair of core points, one from each range, within eps (whole single-label cells).
fn any_pair(
    g: &GroupGrid,
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
    b_box: Aabb,
    th: Thresholds,
) -> Option<(usize, usize)> {
    let t = th.get(g.lbl[a.start], g.lbl[b.start]);
    let pts = g.grid.pts();
    for i in a {
        let p = pts[i];
        // Most points of A are too far from all of B: one box test skips them.
        if b_box.dist2(p) > t {
            continue;
        }
        for j in b.clone() {
            if dist2(p, pts[j]) <= t {
                return Some((i, j));
            }
        }
    }
    None
}

/// Reference DBSCAN with the same definitions, O(n²): the oracle of the property tests.
pub fn dbscan_brute_force(
    positions_m: &[Vec3],
    labels: &[Label],
    params: &DbscanParams,
) -> Clustering {
    let n = positions_m.len();
    let th = Thresholds::new(params);
    let ok = |i: usize| !labels[i].is_unknown();
    let nb =
        |i: usize, j: usize| dist2(positions_m[i], positions_m[j]) <= th.get(labels[i], labels[j]);
    let is_core: Vec<bool> = (0..n)
        .map(|i| ok(i) && (0..n).filter(|&j| ok(j) && nb(i, j)).count() >= params.min_points)
        .collect();
    // Components of core points by flood fill.
    let mut root = vec![u32::MAX; n];
    for s in 0..n {
        if !is_core[s] || root[s] != u32::MAX {
            continue;
        }
        root[s] = s as u32;
        let mut stack = vec![s];
        while let Some(i) = stack.pop() {
            for j in 0..n {
                if is_core[j] && root[j] == u32::MAX && nb(i, j) {
                    root[j] = s as u32;
                    stack.push(j);
                }
            }
        }
    }
    let mut comp = root.clone();
    for i in 0..n {
        if is_core[i] || !ok(i) {
            continue;
        }
        let mut best: Option<(f32, usize)> = None;
        for j in 0..n {
            if is_core[j] && nb(i, j) {
                let d2 = dist2(positions_m[i], positions_m[j]);
                if best.is_none_or(|(b2, bj)| d2 < b2 || (d2 == b2 && j < bj)) {
                    best = Some((d2, j));
                }
            }
        }
        if let Some((_, j)) = best {
            comp[i] = root[j];
        }
    }
    let idx: Vec<u32> = (0..n as u32).collect();
    let mut dense: FxHashMap<u32, u32> = FxHashMap::default();
    let component: Vec<Option<u32>> = comp
        .iter()
        .map(|&r| {
            (r != u32::MAX).then(|| {
                let next = dense.len() as u32;
                *dense.entry(r).or_insert(next)
            })
        })
        .collect();
    let res = GroupResult {
        ids: idx,
        component,
        is_core,
        grid: None,
    };
    assemble(n, labels, &[res], false)
}
