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

use crate::grid::{Aabb, Anchor, CellGrid, EMPTY, GridFrame, Offsets, compact_block3};
use bodyseg_core::math::{Vec3, dist2};
use bodyseg_core::{Label, NUM_CLASSES};
use rayon::prelude::*;

mod brute_force;
mod connect;
mod counting;
pub use brute_force::dbscan_brute_force;
use connect::connect;
use counting::core_points;

/// DBSCAN parameters (a subset of `RefineConfig`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DbscanParams {
    /// Neighbourhood radius, metres (> 0).
    pub eps_m: f32,
    /// Minimum number of points within eps, the point itself included, for a core point (≥ 1).
    pub min_points: usize,
    /// Distance added between points of different labels, metres; ∞ (or any value ≥ eps)
    /// keeps labels apart.
    pub label_penalty_m: f32,
}

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

/// Cell side as a fraction of eps/√3: just under 1 so that the f32 distance between any two
/// points of one cell stays ≤ eps after rounding of coordinates up to ~1 km.
const CELL_SIDE_FRACTION: f64 = 0.999;

/// DBSCAN's cell side for `eps_m` (m): the diagonal just under eps ([`CELL_SIDE_FRACTION`]).
fn cell_side_m(eps_m: f32) -> f64 {
    f64::from(eps_m) / 3f64.sqrt() * CELL_SIDE_FRACTION
}

/// Offsets of the 3×3×3 block come first among [`neighbour_offsets`].
const NEAR_OFFSETS: usize = 27;

/// Half-width of the neighbour block in cells: with side < eps/√3, cells 3 steps away along
/// any axis are more than eps away, so offsets −2..=2 cover every neighbour.
const REACH: i32 = 2;

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

/// Per-group output: for each point of the group (in any order) its index, its local
/// component and whether it is core; the group's grid, whose stored points are in the
/// order of [`GroupResult::ids`], with the box of each cell's points (none for a group
/// too small to cluster).
struct GroupResult {
    /// The group's point indices when it has no grid (with a grid: [`GroupResult::ids`]
    /// reads the grid's, which are in this order, rather than a copy).
    ids: Vec<u32>,
    component: Vec<Option<u32>>,
    /// Per local component (they are `0..first.len()`), its smallest point index.
    first: Vec<u32>,
    is_core: Vec<bool>,
    grid: Option<(CellGrid, Vec<Aabb>)>,
}

impl GroupResult {
    /// Per point of the group, its index (in the order of `component` and `is_core`).
    fn ids(&self) -> &[u32] {
        self.grid.as_ref().map_or(&self.ids, |(g, _)| g.ids())
    }
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
        comps.extend(res.first.iter().enumerate().map(|(c, &f)| (f, g, c as u32)));
        global.push(vec![u32::MAX; res.first.len()]);
    }
    comps.sort_unstable();
    for (id, &(_, g, c)) in comps.iter().enumerate() {
        global[g][c as usize] = id as u32;
    }
    let mut cluster_of = vec![None; n];
    let cluster_labels = if one_label {
        // Each group's table of global ids borrowed once (not looked up again per point).
        for (res, global) in results.iter().zip(&global) {
            let global = global.as_slice();
            for (&i, (&c, &core)) in res.ids().iter().zip(res.component.iter().zip(&res.is_core)) {
                is_core[i as usize] = core;
                if let Some(c) = c {
                    cluster_of[i as usize] = Some(global[c as usize]);
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
        for (res, global) in results.iter().zip(&global) {
            let global = global.as_slice();
            for (&i, (&c, &core)) in res.ids().iter().zip(res.component.iter().zip(&res.is_core)) {
                is_core[i as usize] = core;
                if let Some(c) = c {
                    let id = global[c as usize];
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

/// Neighbour test thresholds between two labels, as squared distances (m²); negative
/// means "never neighbours".
#[derive(Clone, Copy)]
struct Thresholds {
    same2: f32,
    diff2: f32,
}

impl Thresholds {
    fn new(p: &DbscanParams) -> Self {
        let same2 = p.eps_m * p.eps_m;
        let rest = p.eps_m - p.label_penalty_m;
        let diff2 = if rest >= 0.0 { rest * rest } else { -1.0 };
        Thresholds { same2, diff2 }
    }
    #[inline]
    fn get(&self, a: Label, b: Label) -> f32 {
        if a == b { self.same2 } else { self.diff2 }
    }
    /// The larger threshold: no neighbour of any label lies farther.
    #[inline]
    fn reach2(&self) -> f32 {
        self.same2.max(self.diff2)
    }
}

/// The offsets of the 5×5×5 neighbour block, nearest first (the cell itself first, then
/// the rest of its 3×3×3 block), so that neighbour counting reaches `min_points` as early
/// as possible. Sorted once per process: every label group of every clustering uses them
/// (sorting them per group cost ~1M instructions per refinement at 100k points).
fn neighbour_offsets() -> &'static [[i32; 3]] {
    static OFFSETS: std::sync::LazyLock<Vec<[i32; 3]>> = std::sync::LazyLock::new(|| {
        let mut o = Vec::with_capacity(125);
        for dz in -REACH..=REACH {
            for dy in -REACH..=REACH {
                for dx in -REACH..=REACH {
                    o.push([dx, dy, dz]);
                }
            }
        }
        let gap = |v: &[i32; 3]| -> (i32, i32) {
            let g: i32 = v.iter().map(|c| (c.abs() - 1).max(0).pow(2)).sum();
            let d: i32 = v.iter().map(|c| c * c).sum();
            (g, d)
        };
        o.sort_by_key(gap);
        o
    });
    &OFFSETS
}

/// The offsets of [`neighbour_offsets`] that lead to a later cell in key order (z, then
/// y, then x): each pair of neighbouring cells is met once from its first cell. The first
/// `near` of them lie in the 3×3×3 block.
fn forward_offsets() -> (&'static [[i32; 3]], usize) {
    static FORWARD: std::sync::LazyLock<(Vec<[i32; 3]>, usize)> = std::sync::LazyLock::new(|| {
        let all = neighbour_offsets();
        let forward = |o: &&[i32; 3]| (o[2], o[1], o[0]) > (0, 0, 0);
        let near = all[..NEAR_OFFSETS].iter().filter(forward).count();
        (all.iter().filter(forward).copied().collect(), near)
    });
    (&FORWARD.0, FORWARD.1)
}

/// One group's points in the grid, with what every phase needs per cell.
struct GroupGrid {
    grid: CellGrid,
    /// Per stored point: its label; empty for a group of one label (no label test then:
    /// see [`GroupGrid::threshold`]).
    lbl: Vec<Label>,
    /// Per cell: all its points share one label.
    uniform: Vec<bool>,
    /// Per cell: uniform, and its diagonal is below eps (the grid's cells are not wider
    /// than eps/√3), so all its points are neighbours of one another.
    whole: Vec<bool>,
    /// Per cell: the tight box of its points.
    bbox: Vec<Aabb>,
    /// The 125 neighbour offsets, nearest first, prepared for this grid.
    offs: Offsets,
}

impl GroupGrid {
    /// The points `idx` in `frame`'s cells (made for this `eps`: [`dbscan_with_cells`]);
    /// `bounds` is their tight box.
    fn build(
        positions: &[Vec3],
        labels: &[Label],
        idx: &[u32],
        eps: f32,
        frame: &GridFrame,
        bounds: &Aabb,
        mixed: bool,
    ) -> GroupGrid {
        let fine = frame.side_m() <= cell_side_m(eps);
        let grid = CellGrid::binned(positions, idx, frame, bounds, REACH);
        let lbl: Vec<Label> = if mixed {
            grid.ids().iter().map(|&i| labels[i as usize]).collect()
        } else {
            Vec::new()
        };
        let ncells = grid.num_cells();
        let mut uniform = Vec::with_capacity(ncells);
        let mut bbox = Vec::with_capacity(ncells);
        for c in 0..ncells as u32 {
            let r = grid.range(c);
            uniform.push(!mixed || lbl[r.clone()].iter().all(|&l| l == lbl[r.start]));
            bbox.push(Aabb::of(&grid.pts()[r]));
        }
        let whole = uniform.iter().map(|&u| u && fine).collect();
        let offs = grid.offsets(neighbour_offsets());
        GroupGrid {
            grid,
            lbl,
            uniform,
            whole,
            bbox,
            offs,
        }
    }

    /// The neighbour threshold (squared, m²) between stored points `i` and `j`.
    #[inline]
    fn threshold(&self, th: Thresholds, i: usize, j: usize) -> f32 {
        if self.lbl.is_empty() {
            th.same2
        } else {
            th.get(self.lbl[i], self.lbl[j])
        }
    }

    fn num_cells(&self) -> usize {
        self.grid.num_cells()
    }
}

/// The existing neighbour cells of one cell, nearest first, looked up only as far as a
/// caller walks them: the 3×3×3 block first, the rest of the 5×5×5 block when asked.
struct Neighbours {
    at: Anchor,
    cells: Vec<u32>,
    len: usize,
    /// Offsets looked up so far (`NEAR_OFFSETS` or all of them once the far ones are).
    looked: usize,
}

impl Neighbours {
    fn new() -> Self {
        Neighbours {
            at: Anchor::default(),
            cells: vec![0; 125],
            len: 0,
            looked: 0,
        }
    }

    /// Starts over at cell `c` (its 3×3×3 block looked up).
    #[inline(always)]
    fn at(&mut self, g: &GroupGrid, c: u32) -> &mut Self {
        self.at = g.grid.anchor(c);
        self.len = 0;
        self.looked = 0;
        let mut block = [EMPTY; 27];
        if g.grid.block3(self.at, &mut block) {
            // The 3×3×3 block by rows of the table, listed in the order of
            // `neighbour_offsets` (nearest first; the indices checked by a test).
            let out: &mut [u32; 27] = (&mut self.cells[..27])
                .try_into()
                .expect("a slice of 27 is an array of 27");
            let mut n = 0;
            compact_block3!(
                block,
                out,
                n,
                [
                    13, 4, 10, 12, 14, 16, 22, 1, 3, 5, 7, 9, 11, 15, 17, 19, 21, 23, 25, 0, 2, 6,
                    8, 18, 20, 24, 26
                ]
            );
            self.len = n;
            self.looked = NEAR_OFFSETS;
        } else {
            self.look(g, NEAR_OFFSETS);
        }
        self
    }

    fn look(&mut self, g: &GroupGrid, until: usize) {
        let out = &mut self.cells[self.len..];
        self.len += if self.looked == NEAR_OFFSETS && until == 125 {
            // The far cells, by rows of the look-up table (in key order).
            g.grid
                .shell2_cells(self.at, &g.offs, NEAR_OFFSETS..125, out)
        } else {
            g.grid.near_cells(self.at, &g.offs, self.looked..until, out)
        };
        self.looked = until;
    }

    /// The near neighbours, and a way to the far ones.
    fn near(&self) -> &[u32] {
        &self.cells[..self.len]
    }

    /// All neighbours (the far ones looked up now if they were not).
    fn all(&mut self, g: &GroupGrid) -> &[u32] {
        if self.looked < 125 {
            self.look(g, 125);
        }
        &self.cells[..self.len]
    }
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
