//! One label group's grid for DBSCAN: the parameters, the cell side, the neighbour offsets,
//! the per-cell facts every phase needs ([`GroupGrid`]) and the lazily looked-up neighbour
//! cells ([`Neighbours`]). Shared by the core counting (`core_points.rs`) and the
//! clustering (`mod.rs`), so neither uses the other.

use crate::grid::{Aabb, Anchor, CellGrid, GridFrame, Offsets};
use bodyseg_core::Label;
use bodyseg_core::math::Vec3;

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
/// as possible.
pub(super) fn neighbour_offsets() -> Vec<[i32; 3]> {
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

/// The offsets of [`neighbour_offsets`] that lead to a later cell in key order (z, then
/// y, then x): each pair of neighbouring cells is met once from its first cell. The first
/// `near` of them lie in the 3×3×3 block.
pub(super) fn forward_offsets() -> (Vec<[i32; 3]>, usize) {
    let all = neighbour_offsets();
    let forward = |o: &[i32; 3]| (o[2], o[1], o[0]) > (0, 0, 0);
    let near = all[..NEAR_OFFSETS].iter().filter(|o| forward(o)).count();
    (all.into_iter().filter(forward).collect(), near)
}

/// One group's points in the grid, with what every phase needs per cell.
pub(super) struct GroupGrid {
    pub(super) grid: CellGrid,
    /// Per stored point: its label.
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
    /// The points `idx` in `frame`'s cells (made for this `eps`: [`dbscan_with_cells`]).
    pub(super) fn build(
        positions: &[Vec3],
        labels: &[Label],
        idx: &[u32],
        eps: f32,
        frame: &GridFrame,
    ) -> GroupGrid {
        let fine = frame.side_m() <= cell_side_m(eps);
        let mut keys: Vec<[i32; 3]> = Vec::with_capacity(idx.len());
        for &i in idx {
            keys.push(frame.key(positions[i as usize]));
        }
        let grid = CellGrid::new(positions, idx, &keys, REACH);
        let lbl: Vec<Label> = grid.ids().iter().map(|&i| labels[i as usize]).collect();
        let ncells = grid.num_cells();
        let mut uniform = Vec::with_capacity(ncells);
        let mut bbox = Vec::with_capacity(ncells);
        for c in 0..ncells as u32 {
            let r = grid.range(c);
            let first = lbl[r.start];
            uniform.push(lbl[r.clone()].iter().all(|&l| l == first));
            bbox.push(Aabb::of(&grid.pts()[r]));
        }
        let whole = uniform.iter().map(|&u| u && fine).collect();
        let offs = grid.offsets(&neighbour_offsets());
        GroupGrid {
            grid,
            lbl,
            uniform,
            whole,
            bbox,
            offs,
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
    pub(super) fn at(&mut self, g: &GroupGrid, c: u32) -> &mut Self {
        self.at = g.grid.anchor(c);
        self.len = 0;
        self.looked = 0;
        self.look(g, NEAR_OFFSETS);
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
