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
//! Speed: points are binned into a grid of cell side slightly under eps/√3, so a cell's
//! diagonal is below eps: a cell holding ≥ `min_points` points makes them all core without
//! a single distance computation, and only the 5×5×5 block of cells around a point can hold
//! its neighbours. Neighbour counting adds whole cells that lie entirely within eps and
//! stops as soon as `min_points` is reached.

use bodyseg_core::math::{Vec3, dist2};
use bodyseg_core::{Label, NUM_CLASSES};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

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

/// Half-width of the neighbour block in cells: with side < eps/√3, cells 3 steps away along
/// any axis are more than eps away, so offsets −2..=2 cover every neighbour.
const REACH: i32 = 2;

/// Runs label-aware DBSCAN on `positions_m` (any frame, metres) with their `labels`.
///
/// # Panics
/// Never for valid parameters; `positions_m` and `labels` must have equal length (checked
/// by the caller, `refine` validates its input).
pub fn dbscan(positions_m: &[Vec3], labels: &[Label], params: &DbscanParams) -> Clustering {
    debug_assert_eq!(positions_m.len(), labels.len());
    let n = positions_m.len();
    let separate_labels = params.label_penalty_m >= params.eps_m;
    let groups: Vec<Vec<u32>> = if separate_labels {
        let mut g: Vec<Vec<u32>> = vec![Vec::new(); NUM_CLASSES];
        for (i, l) in labels.iter().enumerate() {
            if let Some(c) = l.class() {
                g[c.index()].push(i as u32);
            }
        }
        g.retain(|v| !v.is_empty());
        g
    } else {
        let all: Vec<u32> = (0..n as u32)
            .filter(|&i| !labels[i as usize].is_unknown())
            .collect();
        vec![all]
    };
    let group_results: Vec<GroupResult> = groups
        .par_iter()
        .map(|idx| cluster_group(positions_m, labels, idx, params))
        .collect();
    assemble(n, labels, &groups, &group_results)
}

/// Per-group output: for each point of the group (group order) its local component and
/// whether it is core.
struct GroupResult {
    component: Vec<Option<u32>>,
    is_core: Vec<bool>,
}

/// Gives global cluster ids (ordered by smallest point index) and cluster labels.
fn assemble(
    n: usize,
    labels: &[Label],
    groups: &[Vec<u32>],
    results: &[GroupResult],
) -> Clustering {
    let mut is_core = vec![false; n];
    // (smallest point index, group, local component) for every component.
    let mut comps: Vec<(u32, usize, u32)> = Vec::new();
    for (g, (idx, res)) in groups.iter().zip(results).enumerate() {
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
    }
    comps.sort_unstable();
    let mut global: Vec<Vec<u32>> = results
        .iter()
        .map(|r| {
            vec![
                u32::MAX;
                r.component
                    .iter()
                    .flatten()
                    .map(|&c| c as usize + 1)
                    .max()
                    .unwrap_or(0)
            ]
        })
        .collect();
    for (id, &(_, g, c)) in comps.iter().enumerate() {
        global[g][c as usize] = id as u32;
    }
    let mut cluster_of = vec![None; n];
    let mut votes = vec![[0u32; NUM_CLASSES]; comps.len()];
    for (g, (idx, res)) in groups.iter().zip(results).enumerate() {
        for (&i, &c) in idx.iter().zip(&res.component) {
            if let Some(c) = c {
                let id = global[g][c as usize];
                cluster_of[i as usize] = Some(id);
                if let Some(class) = labels[i as usize].class() {
                    votes[id as usize][class.index()] += 1;
                }
            }
        }
    }
    let cluster_labels = votes.iter().map(majority_label).collect();
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
}

/// A grid over one group's points, sorted by cell so that each cell is a contiguous range
/// and, after classification, each cell's core points come first in its range.
struct Grid {
    side: f64,
    origin: [f64; 3],
    /// Per sorted point: position and label.
    pts: Vec<Vec3>,
    lbl: Vec<Label>,
    /// Per sorted point: its index within the group.
    local: Vec<u32>,
    /// Per cell: integer coordinates, start of its range (len = cells + 1 for `start`).
    keys: Vec<[i32; 3]>,
    start: Vec<u32>,
    /// Per cell: true when all its points share one label.
    uniform: Vec<bool>,
    /// Per cell: its bounds, metres, widened by a hair (see [`Grid::cell_bounds`]).
    bounds: Vec<(Vec3, Vec3)>,
    /// CSR adjacency: the non-empty cells of each cell's 5×5×5 block (itself included).
    nbr_start: Vec<u32>,
    /// Per cell: end (in `nbr`) of the neighbours in its 3×3×3 block, which come first.
    nbr_near_end: Vec<u32>,
    nbr: Vec<u32>,
}

impl Grid {
    fn build(positions: &[Vec3], labels: &[Label], idx: &[u32], eps: f32) -> Grid {
        let side = f64::from(eps) / 3f64.sqrt() * CELL_SIDE_FRACTION;
        // Gather the group's points first (sequential reads), then work on the copy.
        let gpos: Vec<Vec3> = idx.iter().map(|&i| positions[i as usize]).collect();
        let mut lo = [f32::INFINITY; 3];
        for p in &gpos {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
            }
        }
        let origin = lo.map(f64::from);
        // Cell keys in f32: coordinates minus the minimum are ≥ 0, so truncation is floor.
        // The relative error (~1e-7 of a few hundred cells) is far inside the 0.1% slack of
        // CELL_SIDE_FRACTION and of the widened cell bounds.
        let inv_side = (1.0 / side) as f32;
        let pkeys: Vec<[i32; 3]> = gpos
            .iter()
            .map(|p| [0, 1, 2].map(|a| ((p[a] - lo[a]) * inv_side) as i32))
            .collect();
        let order = sort_by_cell(&pkeys);
        let mut pts = Vec::with_capacity(order.len());
        let mut lbl = Vec::with_capacity(order.len());
        let mut local = Vec::with_capacity(order.len());
        let mut keys = Vec::new();
        let mut start = Vec::new();
        let mut uniform = Vec::new();
        let mut last = u64::MAX;
        for &l in &order {
            let k = pack(pkeys[l as usize]);
            if k != last {
                keys.push(pkeys[l as usize]);
                start.push(pts.len() as u32);
                uniform.push(true);
                last = k;
            } else if labels[idx[l as usize] as usize] != lbl[lbl.len() - 1]
                && let Some(u) = uniform.last_mut()
            {
                *u = false;
            }
            pts.push(gpos[l as usize]);
            lbl.push(labels[idx[l as usize] as usize]);
            local.push(l);
        }
        start.push(pts.len() as u32);
        let lookup = CellLookup::new(&keys);
        let mut nbr_start = Vec::with_capacity(keys.len() + 1);
        let mut nbr = Vec::new();
        let mut nbr_near_end = Vec::with_capacity(keys.len());
        lookup.neighbour_lists(
            &keys,
            &neighbour_offsets(),
            &mut nbr_start,
            &mut nbr_near_end,
            &mut nbr,
        );
        nbr_start.push(nbr.len() as u32);
        let mut grid = Grid {
            side,
            origin,
            pts,
            lbl,
            local,
            keys,
            start,
            uniform,
            bounds: Vec::new(),
            nbr_start,
            nbr_near_end,
            nbr,
        };
        grid.bounds = (0..grid.num_cells() as u32)
            .map(|c| grid.cell_bounds(c))
            .collect();
        grid
    }

    fn num_cells(&self) -> usize {
        self.keys.len()
    }

    fn range(&self, c: u32) -> std::ops::Range<usize> {
        self.start[c as usize] as usize..self.start[c as usize + 1] as usize
    }

    fn neighbours(&self, c: usize) -> &[u32] {
        &self.nbr[self.nbr_start[c] as usize..self.nbr_start[c + 1] as usize]
    }

    /// The neighbours of cell `c` in its 3×3×3 block (`near`) or beyond it.
    fn neighbours_part(&self, c: usize, near: bool) -> &[u32] {
        let mid = self.nbr_near_end[c] as usize;
        if near {
            &self.nbr[self.nbr_start[c] as usize..mid]
        } else {
            &self.nbr[mid..self.nbr_start[c + 1] as usize]
        }
    }

    /// Axis-aligned bounds of a cell, metres (f32, widened by a hair so that the
    /// "whole cell within eps" shortcut stays conservative).
    fn cell_bounds(&self, c: u32) -> (Vec3, Vec3) {
        let k = self.keys[c as usize];
        let mut lo = [0f32; 3];
        let mut hi = [0f32; 3];
        for a in 0..3 {
            let l = self.origin[a] + f64::from(k[a]) * self.side;
            lo[a] = (l - self.side * 1e-3) as f32;
            hi[a] = (l + self.side * (1.0 + 1e-3)) as f32;
        }
        (lo, hi)
    }
}

/// The offsets of the 5×5×5 neighbour block, nearest first (the cell itself first), so
/// that neighbour counting reaches `min_points` as early as possible.
fn neighbour_offsets() -> Vec<[i32; 3]> {
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
}

/// Local point indices ordered by cell (z, then y, then x): a counting sort over the
/// cells' bounding block when it is small, a comparison sort of packed keys otherwise.
fn sort_by_cell(pkeys: &[[i32; 3]]) -> Vec<u32> {
    let m = pkeys.len();
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for k in pkeys {
        for a in 0..3 {
            lo[a] = lo[a].min(k[a]);
            hi[a] = hi[a].max(k[a]);
        }
    }
    let dims = [0, 1, 2].map(|a| i64::from(hi[a]) - i64::from(lo[a]) + 1);
    let volume = dims.iter().product::<i64>();
    if m > 0 && volume <= (m as i64 * 16).max(1 << 16) {
        let lin = |k: &[i32; 3]| -> usize {
            let x = i64::from(k[0] - lo[0]);
            let y = i64::from(k[1] - lo[1]);
            let z = i64::from(k[2] - lo[2]);
            ((z * dims[1] + y) * dims[0] + x) as usize
        };
        let mut start = vec![0u32; volume as usize + 1];
        for k in pkeys {
            start[lin(k) + 1] += 1;
        }
        for c in 0..volume as usize {
            start[c + 1] += start[c];
        }
        let mut order = vec![0u32; m];
        for (l, k) in pkeys.iter().enumerate() {
            let c = lin(k);
            order[start[c] as usize] = l as u32;
            start[c] += 1;
        }
        order
    } else {
        let mut keyed: Vec<(u64, u32)> = pkeys
            .iter()
            .enumerate()
            .map(|(l, &k)| (pack(k), l as u32))
            .collect();
        keyed.sort_unstable();
        keyed.into_iter().map(|(_, l)| l).collect()
    }
}

/// Packs three cell coordinates (each within ±2^20) into one sortable u64.
fn pack(k: [i32; 3]) -> u64 {
    const OFF: i64 = 1 << 20;
    let f = |v: i32| ((i64::from(v) + OFF) as u64) & 0x1F_FFFF;
    (f(k[2]) << 42) | (f(k[1]) << 21) | f(k[0])
}

/// Cell lookup by integer coordinates: a dense table (padded by [`REACH`] cells on every
/// side, so neighbour look-ups need no bounds test) when the cells' bounding block is small
/// (one person), a hash map otherwise (a whole scene).
enum CellLookup {
    Dense {
        lo: [i32; 3],
        /// Padded dimensions.
        dims: [i64; 3],
        table: Vec<u32>,
    },
    Hashed(FxHashMap<[i32; 3], u32>),
}

impl CellLookup {
    /// Largest dense table, in cells, per occupied cell: a person's cells fill a few
    /// percent of their bounding block (a surface in a volume), a scene's far less.
    const DENSE_FACTOR: i64 = 256;
    /// A dense table this small (4 MiB) is always fine.
    const DENSE_ALWAYS: i64 = 1 << 20;

    fn new(keys: &[[i32; 3]]) -> Self {
        let mut lo = [i32::MAX; 3];
        let mut hi = [i32::MIN; 3];
        for k in keys {
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let pad = i64::from(REACH);
        let dims = [0, 1, 2].map(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1 + 2 * pad).max(0));
        let volume = dims.iter().product::<i64>();
        if !keys.is_empty()
            && volume <= (keys.len() as i64 * Self::DENSE_FACTOR).max(Self::DENSE_ALWAYS)
        {
            let mut table = vec![u32::MAX; volume as usize];
            let lookup_lo = lo;
            for (c, k) in keys.iter().enumerate() {
                table[Self::lin(lookup_lo, dims, *k)] = c as u32;
            }
            CellLookup::Dense {
                lo: lookup_lo,
                dims,
                table,
            }
        } else {
            CellLookup::Hashed(
                keys.iter()
                    .enumerate()
                    .map(|(c, &k)| (k, c as u32))
                    .collect(),
            )
        }
    }

    /// Index of cell `k` in the padded table.
    #[inline]
    fn lin(lo: [i32; 3], dims: [i64; 3], k: [i32; 3]) -> usize {
        let pad = i64::from(REACH);
        let [x, y, z] = [0, 1, 2].map(|a| i64::from(k[a] - lo[a]) + pad);
        ((z * dims[1] + y) * dims[0] + x) as usize
    }

    /// For each cell, appends the occupied cells at `key + offset` for each offset, in the
    /// offsets' order (CSR: `start` gets one entry per cell, `out` the lists).
    fn neighbour_lists(
        &self,
        keys: &[[i32; 3]],
        offsets: &[[i32; 3]],
        start: &mut Vec<u32>,
        near_end: &mut Vec<u32>,
        out: &mut Vec<u32>,
    ) {
        // Offsets come nearest first; the 3×3×3 block is the first NEAR_OFFSETS of them.
        const NEAR_OFFSETS: usize = 27;
        match self {
            CellLookup::Dense { lo, dims, table } => {
                let deltas: Vec<i64> = offsets
                    .iter()
                    .map(|o| {
                        (i64::from(o[2]) * dims[1] + i64::from(o[1])) * dims[0] + i64::from(o[0])
                    })
                    .collect();
                // Branch-free append: about half the look-ups are empty and a branch on
                // them mispredicts; write every slot and advance only on a hit.
                out.reserve(keys.len() * deltas.len());
                let mut buf = [0u32; 125];
                for k in keys {
                    start.push(out.len() as u32);
                    let base = Self::lin(*lo, *dims, *k) as i64;
                    let mut n = 0;
                    let (near_deltas, far_deltas) = deltas.split_at(NEAR_OFFSETS);
                    for d in near_deltas {
                        let c = table[(base + d) as usize];
                        buf[n] = c;
                        n += usize::from(c != u32::MAX);
                    }
                    near_end.push((out.len() + n) as u32);
                    for d in far_deltas {
                        let c = table[(base + d) as usize];
                        buf[n] = c;
                        n += usize::from(c != u32::MAX);
                    }
                    out.extend_from_slice(&buf[..n]);
                }
            }
            CellLookup::Hashed(m) => {
                for k in keys {
                    start.push(out.len() as u32);
                    for (i, o) in offsets.iter().enumerate() {
                        if i == NEAR_OFFSETS {
                            near_end.push(out.len() as u32);
                        }
                        if let Some(&c) = m.get(&[k[0] + o[0], k[1] + o[1], k[2] + o[2]]) {
                            out.push(c);
                        }
                    }
                }
            }
        }
    }
}

/// Squared distance from `p` to the nearest and farthest points of the box `[lo, hi]`.
#[inline]
fn box_dist2(p: Vec3, lo: Vec3, hi: Vec3) -> (f32, f32) {
    let mut near = 0.0;
    let mut far = 0.0;
    for a in 0..3 {
        let d_lo = p[a] - lo[a];
        let d_hi = hi[a] - p[a];
        let gap = (-d_lo).max(-d_hi).max(0.0);
        near += gap * gap;
        let reach = d_lo.abs().max(d_hi.abs());
        far += reach * reach;
    }
    (near, far)
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
) -> GroupResult {
    let m = idx.len();
    let min_pts = params.min_points;
    if m == 0 || min_pts > m {
        return GroupResult {
            component: vec![None; m],
            is_core: vec![false; m],
        };
    }
    let th = Thresholds::new(params);
    // One label in the group: no label test in the inner loops.
    let separate = params.label_penalty_m >= params.eps_m;
    let grid = Grid::build(positions, labels, idx, params.eps_m);
    let ncells = grid.num_cells();

    // 1. Core points (per sorted point).
    let mut core = vec![false; m];
    for c in 0..ncells {
        let r = grid.range(c as u32);
        if r.len() >= min_pts && grid.uniform[c] {
            core[r].fill(true);
            continue;
        }
        if separate {
            for i in r {
                core[i] = is_core_point::<false>(&grid, c, i, min_pts, th);
            }
        } else {
            for i in r {
                core[i] = is_core_point::<true>(&grid, c, i, min_pts, th);
            }
        }
    }

    // 2. Reorder each cell so its core points come first; `core_end[c]` ends them.
    let mut grid = grid;
    let mut core_end = vec![0u32; ncells];
    for c in 0..ncells {
        let r = grid.range(c as u32);
        let (s, e) = (r.start, r.end);
        let mut w = s;
        for i in s..e {
            if core[i] {
                grid.pts.swap(w, i);
                grid.lbl.swap(w, i);
                grid.local.swap(w, i);
                core.swap(w, i);
                w += 1;
            }
        }
        core_end[c] = w as u32;
    }
    let core_range = |c: u32| grid.start[c as usize] as usize..core_end[c as usize] as usize;
    let has_core = |c: u32| core_end[c as usize] > grid.start[c as usize];

    // Bounding boxes of each cell's core points, to skip hopeless cell pairs quickly.
    let core_box: Vec<(Vec3, Vec3)> = (0..ncells as u32)
        .map(|c| {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for p in &grid.pts[core_range(c)] {
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            (lo, hi)
        })
        .collect();

    // 3. Connect core points. In a cell of one label all core points are within eps of
    //    each other, so the cell is the unit of the union-find (a small array that stays
    //    in L1); cells of several labels (finite label penalty) fall back to points.
    let reach2 = th.same2.max(th.diff2);
    let gap2 = |a: usize, b: usize| -> f32 {
        let ((alo, ahi), (blo, bhi)) = (core_box[a], core_box[b]);
        let mut g2 = 0.0;
        for k in 0..3 {
            let g = (blo[k] - ahi[k]).max(alo[k] - bhi[k]).max(0.0);
            g2 += g * g;
        }
        g2
    };
    let all_uniform = grid.uniform.iter().all(|&u| u);
    // Union-find elements: cells when all are uniform, else sorted points.
    let unit = |c: u32, i: usize| -> u32 { if all_uniform { c } else { i as u32 } };
    let mut uf = UnionFind::new(if all_uniform { ncells } else { m });
    if !all_uniform {
        for c in 0..ncells as u32 {
            let r = core_range(c);
            for i in r.clone() {
                for j in r.start..i {
                    if grid.uniform[c as usize]
                        || dist2(grid.pts[i], grid.pts[j]) <= th.get(grid.lbl[i], grid.lbl[j])
                    {
                        uf.union(i as u32, j as u32);
                    }
                }
            }
        }
    }
    // Two passes: the 3×3×3 blocks first, which join almost everything, so that the
    // farther pairs of the second pass are mostly settled by one `find`.
    for near in [true, false] {
        for c in 0..ncells as u32 {
            if !has_core(c) {
                continue;
            }
            let ra = core_range(c);
            let uniform_c = grid.uniform[c as usize];
            for &d in grid.neighbours_part(c as usize, near) {
                if d <= c || !has_core(d) {
                    continue;
                }
                let rb = core_range(d);
                if uniform_c && grid.uniform[d as usize] {
                    // Already joined (the common case on a surface): nothing to test.
                    if uf.find(unit(c, ra.start)) == uf.find(unit(d, rb.start)) {
                        continue;
                    }
                    if gap2(c as usize, d as usize) > reach2 {
                        continue;
                    }
                    if let Some((i, j)) = any_pair(&grid, ra.clone(), rb, core_box[d as usize], th)
                    {
                        uf.union(unit(c, i), unit(d, j));
                    }
                } else {
                    if gap2(c as usize, d as usize) > reach2 {
                        continue;
                    }
                    for i in ra.clone() {
                        for j in rb.clone() {
                            if dist2(grid.pts[i], grid.pts[j]) <= th.get(grid.lbl[i], grid.lbl[j]) {
                                uf.union(i as u32, j as u32);
                            }
                        }
                    }
                }
            }
        }
    }

    // 4. Components of core points, border points to their nearest core point.
    let mut component = vec![None; m];
    let mut is_core = vec![false; m];
    for c in 0..ncells as u32 {
        for i in core_range(c) {
            let l = grid.local[i] as usize;
            component[l] = Some(uf.find(unit(c, i)));
            is_core[l] = true;
        }
    }
    for c in 0..ncells as u32 {
        let r = grid.range(c);
        for i in core_end[c as usize] as usize..r.end {
            let p = grid.pts[i];
            let li = grid.lbl[i];
            // (distance², original index of the core point, its union-find unit)
            let mut best: Option<(f32, u32, u32)> = None;
            for &d in grid.neighbours(c as usize) {
                for j in core_range(d) {
                    let d2 = dist2(p, grid.pts[j]);
                    if d2 > th.get(li, grid.lbl[j]) {
                        continue;
                    }
                    let oj = idx[grid.local[j] as usize];
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
                component[grid.local[i] as usize] = Some(uf.find(u));
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
    GroupResult { component, is_core }
}

/// True when sorted point `i` (in cell `c`) has at least `min_pts` neighbours within eps.
/// `MIXED = false` when the group holds one label (no label test needed).
#[inline]
fn is_core_point<const MIXED: bool>(
    grid: &Grid,
    c: usize,
    i: usize,
    min_pts: usize,
    th: Thresholds,
) -> bool {
    let p = grid.pts[i];
    let li = grid.lbl[i];
    let reach2 = th.same2.max(th.diff2);
    let mut count = 0usize;
    let nbrs = grid.neighbours(c);
    debug_assert_eq!(nbrs.first(), Some(&(c as u32)), "own cell first");
    let mut rest = nbrs;
    // The point's own cell comes first; its diameter is below eps, so when it holds one
    // label all of it counts.
    if !MIXED || grid.uniform[c] {
        count = grid.range(c as u32).len();
        if count >= min_pts {
            return true;
        }
        rest = &nbrs[1..];
    }
    for &d in rest {
        let (lo, hi) = grid.bounds[d as usize];
        let (near2, far2) = box_dist2(p, lo, hi);
        if near2 > reach2 {
            continue;
        }
        let r = grid.range(d);
        if far2 <= th.same2 && (!MIXED || (grid.uniform[d as usize] && grid.lbl[r.start] == li)) {
            count += r.len();
        } else if MIXED {
            for j in r {
                if dist2(p, grid.pts[j]) <= th.get(li, grid.lbl[j]) {
                    count += 1;
                }
            }
        } else {
            count += grid.pts[r]
                .iter()
                .filter(|&&q| dist2(p, q) <= th.same2)
                .count();
        }
        if count >= min_pts {
            return true;
        }
    }
    false
}

/// Some pair of core points, one from each range, within eps (uniform single-label cells).
fn any_pair(
    grid: &Grid,
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
    core_box: (Vec3, Vec3),
    th: Thresholds,
) -> Option<(usize, usize)> {
    let t = th.get(grid.lbl[a.start], grid.lbl[b.start]);
    let (blo, bhi) = core_box;
    for i in a {
        let p = grid.pts[i];
        // Most points of A are too far from all of B: one box test skips them.
        if box_dist2(p, blo, bhi).0 > t {
            continue;
        }
        for j in b.clone() {
            if dist2(p, grid.pts[j]) <= t {
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
    let res = GroupResult { component, is_core };
    assemble(n, labels, &[idx], &[res])
}
