//! DBSCAN's shared pieces: parameters and result ([`DbscanParams`], [`Clustering`]), the
//! cell side and neighbour offsets, a label group's grid ([`GroupGrid`]) and its neighbour
//! lists, the distance thresholds, union-find, and the assembly of the groups' results.
//! The algorithm's files (`dbscan.rs`, `counting.rs`, `connect.rs`, `brute_force.rs`) use
//! these and not one another's items, so the files import in one direction only.

use crate::grid::{Aabb, Anchor, CellGrid, EMPTY, GridFrame, Offsets, compact_block3};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, NUM_CLASSES};

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
pub(super) const CELL_SIDE_FRACTION: f64 = 0.999;

/// DBSCAN's cell side for `eps_m` (m): the diagonal just under eps ([`CELL_SIDE_FRACTION`]).
pub(super) fn cell_side_m(eps_m: f32) -> f64 {
    f64::from(eps_m) / 3f64.sqrt() * CELL_SIDE_FRACTION
}

/// Offsets of the 3×3×3 block come first among [`neighbour_offsets`].
pub(super) const NEAR_OFFSETS: usize = 27;

/// Half-width of the neighbour block in cells: with side < eps/√3, cells 3 steps away along
/// any axis are more than eps away, so offsets −2..=2 cover every neighbour.
pub(super) const REACH: i32 = 2;

/// Per-group output: for each point of the group (in any order) its index, its local
/// component and whether it is core; the group's grid, whose stored points are in the
/// order of [`GroupResult::ids`], with the box of each cell's points (none for a group
/// too small to cluster).
pub(super) struct GroupResult {
    /// The group's point indices when it has no grid (with a grid: [`GroupResult::ids`]
    /// reads the grid's, which are in this order, rather than a copy).
    pub(super) ids: Vec<u32>,
    pub(super) component: Vec<Option<u32>>,
    /// Per local component (they are `0..first.len()`), its smallest point index.
    pub(super) first: Vec<u32>,
    pub(super) is_core: Vec<bool>,
    pub(super) grid: Option<(CellGrid, Vec<Aabb>)>,
}

impl GroupResult {
    /// Per point of the group, its index (in the order of `component` and `is_core`).
    pub(super) fn ids(&self) -> &[u32] {
        self.grid.as_ref().map_or(&self.ids, |(g, _)| g.ids())
    }
}

/// Gives global cluster ids (ordered by smallest point index) and cluster labels.
/// `one_label`: every group holds one label (so does each of its clusters, whose label is
/// then its points' without a vote).
pub(super) fn assemble(
    n: usize,
    labels: &[Label],
    results: &[GroupResult],
    one_label: bool,
) -> Clustering {
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
pub(super) fn majority_label(votes: &[u32; NUM_CLASSES]) -> Label {
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
pub(super) struct Thresholds {
    pub(super) same2: f32,
    pub(super) diff2: f32,
}

impl Thresholds {
    pub(super) fn new(p: &DbscanParams) -> Self {
        let same2 = p.eps_m * p.eps_m;
        let rest = p.eps_m - p.label_penalty_m;
        let diff2 = if rest >= 0.0 { rest * rest } else { -1.0 };
        Thresholds { same2, diff2 }
    }
    #[inline]
    pub(super) fn get(&self, a: Label, b: Label) -> f32 {
        if a == b { self.same2 } else { self.diff2 }
    }
    /// The larger threshold: no neighbour of any label lies farther.
    #[inline]
    pub(super) fn reach2(&self) -> f32 {
        self.same2.max(self.diff2)
    }
}

/// The offsets of the 5×5×5 neighbour block, nearest first (the cell itself first, then
/// the rest of its 3×3×3 block), so that neighbour counting reaches `min_points` as early
/// as possible. Sorted once per process: every label group of every clustering uses them
/// (sorting them per group cost ~1M instructions per refinement at 100k points).
pub(super) fn neighbour_offsets() -> &'static [[i32; 3]] {
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
pub(super) fn forward_offsets() -> (&'static [[i32; 3]], usize) {
    static FORWARD: std::sync::LazyLock<(Vec<[i32; 3]>, usize)> = std::sync::LazyLock::new(|| {
        let all = neighbour_offsets();
        let forward = |o: &&[i32; 3]| (o[2], o[1], o[0]) > (0, 0, 0);
        let near = all[..NEAR_OFFSETS].iter().filter(forward).count();
        (all.iter().filter(forward).copied().collect(), near)
    });
    (&FORWARD.0, FORWARD.1)
}

/// One group's points in the grid, with what every phase needs per cell.
pub(super) struct GroupGrid {
    pub(super) grid: CellGrid,
    /// Per stored point: its label; empty for a group of one label (no label test then:
    /// see [`GroupGrid::threshold`]).
    pub(super) lbl: Vec<Label>,
    /// Per cell: all its points share one label.
    pub(super) uniform: Vec<bool>,
    /// Per cell: uniform, and its diagonal is below eps (the grid's cells are not wider
    /// than eps/√3), so all its points are neighbours of one another.
    pub(super) whole: Vec<bool>,
    /// Per cell: the tight box of its points.
    pub(super) bbox: Vec<Aabb>,
    /// The 125 neighbour offsets, nearest first, prepared for this grid.
    pub(super) offs: Offsets,
}

impl GroupGrid {
    /// The points `idx` in `frame`'s cells (made for this `eps`: [`dbscan_with_cells`]);
    /// `bounds` is their tight box.
    pub(super) fn build(
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
    pub(super) fn threshold(&self, th: Thresholds, i: usize, j: usize) -> f32 {
        if self.lbl.is_empty() {
            th.same2
        } else {
            th.get(self.lbl[i], self.lbl[j])
        }
    }

    pub(super) fn num_cells(&self) -> usize {
        self.grid.num_cells()
    }
}

/// The existing neighbour cells of one cell, nearest first, looked up only as far as a
/// caller walks them: the 3×3×3 block first, the rest of the 5×5×5 block when asked.
pub(super) struct Neighbours {
    pub(super) at: Anchor,
    pub(super) cells: Vec<u32>,
    pub(super) len: usize,
    /// Offsets looked up so far (`NEAR_OFFSETS` or all of them once the far ones are).
    pub(super) looked: usize,
}

impl Neighbours {
    pub(super) fn new() -> Self {
        Neighbours {
            at: Anchor::default(),
            cells: vec![0; 125],
            len: 0,
            looked: 0,
        }
    }

    /// Starts over at cell `c` (its 3×3×3 block looked up).
    #[inline(always)]
    pub(super) fn at(&mut self, g: &GroupGrid, c: u32) -> &mut Self {
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

    pub(super) fn look(&mut self, g: &GroupGrid, until: usize) {
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
    pub(super) fn near(&self) -> &[u32] {
        &self.cells[..self.len]
    }

    /// All neighbours (the far ones looked up now if they were not).
    pub(super) fn all(&mut self, g: &GroupGrid) -> &[u32] {
        if self.looked < 125 {
            self.look(g, 125);
        }
        &self.cells[..self.len]
    }
}

/// Minimal union-find over cells (path halving, union by index).
pub(super) struct UnionFind(pub(super) Vec<u32>);

impl UnionFind {
    pub(super) fn new(n: usize) -> Self {
        UnionFind((0..n as u32).collect())
    }
    pub(super) fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let up = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = up;
            x = up;
        }
        x
    }
    pub(super) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}
