//! The one spatial grid of the crate: points binned into cubic cells, stored sorted by cell
//! (each cell a contiguous range), with a look-up of a cell by its integer key, and the
//! exact nearest-neighbour and radius queries built on it ([`nn::NnIndex`]).
//!
//! Every spatial search of the refinement uses it: DBSCAN's neighbour counting
//! ([`crate::dbscan`], cells of side eps/√3), N's nearest clustered point and its votes
//! ([`nn::NnIndex`]), the wide votes and smoothing's cell counts (`steps::LabelCells`), R's
//! bridges through noise (`steps::restore_bridged`) and the contact graph
//! (`graph::ContactIndex`). Each user keeps its own rule for which cell a point falls in
//! (relative to the points' corner with [`GridFrame`], or absolute, `⌊x / side⌋`, where
//! the cells' placement is part of the result); the binning, the ordering and the look-up
//! are this module's.
//!
//! Why one structure matters beyond tidiness: every grid here must survive any finite
//! input. Keys are computed in f64 and clamped to the points' extent, the cells per axis
//! are capped ([`MAX_CELLS_PER_AXIS`], the side grows past it), sizes are multiplied with
//! checked arithmetic, and a look-up table is dense only when its size is bounded by the
//! number of points; every loop of a query is bounded by the cells that exist.

use bodyseg_core::math::Vec3;
use rustc_hash::FxHashMap;

pub(crate) mod nn;
#[cfg(test)]
pub(crate) mod tests;

/// Most cells along one axis of a [`GridFrame`]: keys and their neighbours' keys (± a few
/// cells) stay far inside `i32`, and any side is made at least the extent over this.
pub(crate) const MAX_CELLS_PER_AXIS: f64 = (1u64 << 30) as f64;

/// [`CellGrid::new`] counts points in a table over their block when it holds at most this
/// many slots per point...
const COUNTING_FACTOR: u64 = 32;
/// ...or this many in any case (1 MiB).
const COUNTING_ALWAYS: u64 = 1 << 18;

/// A dense look-up table may hold this many slots per occupied cell (a person's cells
/// fill a few percent of their bounding block: a surface in a volume)...
const DENSE_FACTOR: u64 = 256;
/// ...or this many in any case (4 MiB).
const DENSE_ALWAYS: u64 = 1 << 20;

/// The larger of two finite values, as one `maxss`: `f32::max`'s NaN handling costs five
/// more instructions, and on the distance bounds below (called per point and neighbour
/// cell) that was ~6M instructions per refinement at 100k points. For finite operands the
/// value is `f32::max`'s (at most the sign of a zero differs, which squares away).
#[inline(always)]
pub(crate) fn max_finite(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of two finite values, as one `minss` (see [`max_finite`]).
#[inline(always)]
pub(crate) fn min_finite(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// Axis-aligned box, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Aabb {
    pub(crate) lo: Vec3,
    pub(crate) hi: Vec3,
}

impl Aabb {
    /// The empty box (grows to the first point).
    pub(crate) const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    /// The tight box of `pts` ([`Aabb::EMPTY`] when there are none).
    pub(crate) fn of(pts: &[Vec3]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in pts {
            b.grow(p);
        }
        b
    }

    /// The tight box of the points `ids` of `positions` (the point box at the origin when
    /// there are none, so that frames built on it stay finite).
    pub(crate) fn of_ids(positions: &[Vec3], ids: &[u32]) -> Aabb {
        if ids.is_empty() {
            return Aabb {
                lo: [0.0; 3],
                hi: [0.0; 3],
            };
        }
        let mut b = Aabb::EMPTY;
        for &i in ids {
            b.grow(positions[i as usize]);
        }
        b
    }

    #[inline]
    pub(crate) fn grow(&mut self, p: Vec3) {
        // Selects, not `f32::min` (coordinates are finite; its NaN handling costs several
        // instructions) nor branches (they mispredict on points in no order): one
        // `minss` / `maxss` each.
        for a in 0..3 {
            self.lo[a] = if p[a] < self.lo[a] { p[a] } else { self.lo[a] };
            self.hi[a] = if p[a] > self.hi[a] { p[a] } else { self.hi[a] };
        }
    }

    pub(crate) fn union(&mut self, o: &Aabb) {
        self.grow(o.lo);
        self.grow(o.hi);
    }

    /// Squared distances from `q` to the nearest and the farthest point of the box, in the
    /// operation order of [`dist2`], so that for every point `p` inside it
    /// `near ≤ dist2(q, p) ≤ far` holds exactly in f32 (rounding is monotonic).
    #[inline]
    pub(crate) fn near_far2(&self, q: Vec3) -> (f32, f32) {
        // One pair of differences per axis serves both bounds: `|q − lo| = |lo − q|`
        // exactly (rounding is symmetric).
        let gf = |a: usize| {
            let (below, above) = (self.lo[a] - q[a], q[a] - self.hi[a]);
            (
                max_finite(max_finite(below, above), 0.0),
                max_finite(below.abs(), above.abs()),
            )
        };
        let ((g0, f0), (g1, f1), (g2, f2)) = (gf(0), gf(1), gf(2));
        (g0 * g0 + g1 * g1 + g2 * g2, f0 * f0 + f1 * f1 + f2 * f2)
    }

    /// [`Aabb::near_far2`] of four points given by axis (`x[l], y[l], z[l]`): each lane
    /// runs the same operations in the same order, so the bounds are the same bits, four
    /// at a time.
    #[inline(always)]
    pub(crate) fn near_far2_x4(
        &self,
        x: &[f32; 4],
        y: &[f32; 4],
        z: &[f32; 4],
    ) -> ([f32; 4], [f32; 4]) {
        let gf = |a: usize, q: &[f32; 4]| {
            let (mut g, mut f) = ([0f32; 4], [0f32; 4]);
            for l in 0..4 {
                let (below, above) = (self.lo[a] - q[l], q[l] - self.hi[a]);
                g[l] = max_finite(max_finite(below, above), 0.0);
                f[l] = max_finite(below.abs(), above.abs());
            }
            (g, f)
        };
        let ((g0, f0), (g1, f1), (g2, f2)) = (gf(0, x), gf(1, y), gf(2, z));
        let (mut near, mut far) = ([0f32; 4], [0f32; 4]);
        for l in 0..4 {
            near[l] = g0[l] * g0[l] + g1[l] * g1[l] + g2[l] * g2[l];
            far[l] = f0[l] * f0[l] + f1[l] * f1[l] + f2[l] * f2[l];
        }
        (near, far)
    }

    /// Squared distance from `q` to the box (0 inside): a lower bound of [`dist2`] to any
    /// point inside it, exact in f32 as [`Aabb::near_far2`]'s.
    #[inline]
    pub(crate) fn dist2(&self, q: Vec3) -> f32 {
        let g = |a: usize| max_finite(max_finite(self.lo[a] - q[a], q[a] - self.hi[a]), 0.0);
        let (g0, g1, g2) = (g(0), g(1), g(2));
        g0 * g0 + g1 * g1 + g2 * g2
    }

    /// Squared gap between two boxes (0 when they overlap): a lower bound of [`dist2`]
    /// between any point of one and any point of the other.
    #[inline]
    pub(crate) fn gap2(&self, o: &Aabb) -> f32 {
        let g = |a: usize| max_finite(max_finite(self.lo[a] - o.hi[a], o.lo[a] - self.hi[a]), 0.0);
        let (g0, g1, g2) = (g(0), g(1), g(2));
        g0 * g0 + g1 * g1 + g2 * g2
    }
}

/// Cells placed relative to the lowest corner of a set of points: key
/// `⌊(p − corner) / side⌋` per axis, in f64, clamped to the points' extent, so no key
/// overflows whatever the coordinates and the side.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GridFrame {
    corner: [f64; 3],
    side: f64,
    inv_side: f64,
    /// Largest key per axis.
    max_key: [i64; 3],
    /// Keys in f32 suffice: at most [`F32_KEYS`] cells per axis.
    fast: Option<(Vec3, f32)>,
}

/// Up to this many cells per axis a [`GridFrame`] computes keys in f32: the relative error
/// of `(p − corner) / side` (~2⁻²³) misplaces a point by at most ~5·10⁻⁴ of a cell across
/// a boundary, far inside the slack its users leave (DBSCAN's cells are 0.1 % under
/// eps/√3).
const F32_KEYS: i64 = 1 << 12;

impl GridFrame {
    /// The frame of cells of side `side_m` over the points `ids` of `positions` (at least
    /// one), the side made larger when the extent would need more than
    /// [`MAX_CELLS_PER_AXIS`] cells ([`GridFrame::side_m`] says the side used).
    #[cfg(test)]
    pub(crate) fn covering(positions: &[Vec3], ids: &[u32], side_m: f64) -> GridFrame {
        Self::covering_box(Aabb::of_ids(positions, ids), side_m)
    }

    /// [`GridFrame::covering`] the points whose box is `b` (the point box at the origin
    /// when `b` is empty, as [`Aabb::of_ids`] gives for no point).
    pub(crate) fn covering_box(b: Aabb, side_m: f64) -> GridFrame {
        let b = if b.lo[0] > b.hi[0] {
            Aabb {
                lo: [0.0; 3],
                hi: [0.0; 3],
            }
        } else {
            b
        };
        let extent = [0, 1, 2].map(|a| f64::from(b.hi[a]) - f64::from(b.lo[a]));
        let widest = extent.iter().copied().fold(0.0, f64::max);
        let side = side_m
            .max(widest / MAX_CELLS_PER_AXIS)
            .max(f64::MIN_POSITIVE);
        let inv_side = 1.0 / side;
        let max_key = extent.map(|e| (e * inv_side) as i64);
        GridFrame {
            corner: b.lo.map(f64::from),
            side,
            inv_side,
            max_key,
            fast: max_key
                .iter()
                .all(|&k| k <= F32_KEYS)
                .then_some((b.lo, inv_side as f32)),
        }
    }

    /// The side of the cells, metres (≥ the side asked).
    pub(crate) fn side_m(&self) -> f64 {
        self.side
    }

    /// When keys are computed in f32 (at most [`F32_KEYS`] cells per axis): the corner,
    /// the inverse of the side (1/m) and the largest key per axis, with which
    /// [`GridFrame::key`] gives `((p − corner) · inv) as i32` clamped to `0..=max_key`.
    pub(crate) fn f32_keys(&self) -> Option<(Vec3, f32, [i32; 3])> {
        self.fast
            .map(|(lo, inv)| (lo, inv, self.max_key.map(|k| k as i32)))
    }

    /// [`GridFrame::key`] of a point not below the corner on any axis (a point of the
    /// box the frame was made from): `p − corner ≥ 0` is exact in f32, so the key needs no
    /// lower clamp (the same key, one compare and branch fewer per axis).
    #[inline]
    pub(crate) fn key_above_corner(&self, p: Vec3) -> [i32; 3] {
        if let Some((lo, inv)) = self.fast {
            debug_assert!((0..3).all(|a| p[a] >= lo[a]));
            let k = |a: usize| (((p[a] - lo[a]) * inv) as i32).min(self.max_key[a] as i32);
            return [k(0), k(1), k(2)];
        }
        self.key(p)
    }

    /// The key of `p`'s cell (clamped into the frame, so a point outside the points it
    /// was made from gets the nearest border cell).
    #[inline]
    pub(crate) fn key(&self, p: Vec3) -> [i32; 3] {
        // Written out per axis: `[0, 1, 2].map` is not always inlined on this hot path.
        // `as` saturates (NaN to 0); the min/max keep outside points on the border.
        if let Some((lo, inv)) = self.fast {
            let k = |a: usize| {
                (((p[a] - lo[a]) * inv) as i32)
                    .max(0)
                    .min(self.max_key[a] as i32)
            };
            return [k(0), k(1), k(2)];
        }
        let k = |a: usize| {
            let k = ((f64::from(p[a]) - self.corner[a]) * self.inv_side) as i64;
            k.max(0).min(self.max_key[a]) as i32
        };
        [k(0), k(1), k(2)]
    }
}

/// Points binned by cell key, each cell a contiguous run of them, cells in key order
/// (z, then y, then x).
#[derive(Clone, Debug)]
pub(crate) struct CellGrid {
    /// Per cell: its key.
    keys: Vec<[i32; 3]>,
    /// Per cell, the start of its points; one more entry ends the last.
    start: Vec<u32>,
    /// Per stored point: the id it was given (its index in the caller's arrays).
    ids: Vec<u32>,
    /// Per stored point: its position.
    pts: Vec<Vec3>,
    lookup: CellLookup,
}

/// Cell look-up by key: a dense table over the cells' bounding block (padded by `pad`
/// cells on every side, so that the neighbours of a cell within `pad` steps need no range
/// test) when its size is bounded by the number of cells, a hash map otherwise.
#[derive(Clone, Debug)]
enum CellLookup {
    Dense {
        /// Key of the table's first slot (the block's corner minus the padding).
        lo: [i32; 3],
        /// Padded dimensions.
        dims: [i64; 3],
        table: Vec<u32>,
    },
    Hashed(FxHashMap<[i32; 3], u32>),
}

/// The slot of key `k` in a dense table whose first slot has the key `corner` and whose
/// dimensions are `dims` (x fastest). Slots fit in u32: the tables [`CellGrid::new`] makes
/// are bounded by [`COUNTING_FACTOR`] slots per point.
#[inline]
fn slot_of(k: [i32; 3], corner: [i64; 3], dims: [u64; 3]) -> u32 {
    let (dx, dy) = (dims[0] as u32, dims[1] as u32);
    let x = (i64::from(k[0]) - corner[0]) as u32;
    let y = (i64::from(k[1]) - corner[1]) as u32;
    let z = (i64::from(k[2]) - corner[2]) as u32;
    (z * dy + y) * dx + x
}

/// Marks an empty slot of a dense table.
pub(crate) const EMPTY: u32 = u32::MAX;

/// Numbers the cells of a dense table over a block of `dims` slots per axis (x fastest)
/// that holds each slot's point count: the non-empty slots become cells in slot (= key)
/// order, and the table then holds each slot's cell ([`EMPTY`] where no point lies).
/// Returns each cell's key (`key_of` its slot's coordinates in the block) and where its
/// points start (CSR, one more entry than cells).
pub(crate) fn number_cells(
    table: &mut [u32],
    dims: [u64; 3],
    key_of: impl Fn([u64; 3]) -> [i32; 3],
) -> (Vec<[i32; 3]>, Vec<u32>) {
    let mut keys = Vec::new();
    let mut start = Vec::new();
    let mut n = 0u32;
    // Most slots are empty (a surface's cells fill a few percent of their block): a run
    // of them is found by one OR over the run (vectorised) and marked in one fill, and
    // only runs holding a cell are walked slot by slot.
    const RUN: usize = 16;
    for (r, run) in table.chunks_mut(RUN).enumerate() {
        if run.iter().fold(0, |a, &t| a | t) == 0 {
            run.fill(EMPTY);
            continue;
        }
        for (j, t) in run.iter_mut().enumerate() {
            if *t == 0 {
                *t = EMPTY;
                continue;
            }
            let s = (r * RUN + j) as u64;
            keys.push(key_of([
                s % dims[0],
                (s / dims[0]) % dims[1],
                s / (dims[0] * dims[1]),
            ]));
            start.push(n);
            n += *t;
            *t = keys.len() as u32 - 1;
        }
    }
    start.push(n);
    (keys, start)
}

impl CellGrid {
    /// Bins the points `ids` of `positions`, point `ids[k]` in cell `keys[k]`. Within a
    /// cell the points keep the order of `ids`. `pad`: neighbours within this many cells
    /// of a cell are found by [`CellGrid::near_cell`] (≤ 4).
    ///
    /// When the keys' bounding block (padded) holds at most [`COUNTING_FACTOR`] slots per
    /// point, one table over it does everything: it counts the points per slot, numbers
    /// the cells in slot order (= key order), and stays as the dense look-up; the points
    /// are then scattered to their places in one pass. Otherwise the keys are sorted and
    /// looked up in a hash map.
    pub(crate) fn new(positions: &[Vec3], ids: &[u32], keys: &[[i32; 3]], pad: i32) -> Self {
        debug_assert_eq!(ids.len(), keys.len());
        let pad = pad.clamp(0, 4);
        let (lo, hi) = key_bounds(keys);
        match counting_table(lo, hi, pad, ids.len()) {
            Some((corner, dims, volume)) => {
                let slots = keys.iter().map(|k| slot_of(*k, corner, dims)).collect();
                Self::counted(positions, ids, slots, corner, dims, volume)
            }
            _ => Self::sorted(positions, ids, keys, pad),
        }
    }

    /// [`CellGrid::new`] with the keys of `frame` (`ids[k]` in cell
    /// `frame.key(positions[ids[k]])`), `bounds` being the tight box of those points and
    /// lying in the box `frame` was made from:
    /// the same grid, built without a key array. Keys are monotonic in each coordinate, so
    /// the keys of the box's corners are the smallest and largest keys exactly, and in the
    /// counted case each point's table slot comes straight from its position.
    pub(crate) fn binned(
        positions: &[Vec3],
        ids: &[u32],
        frame: &GridFrame,
        bounds: &Aabb,
        pad: i32,
    ) -> Self {
        let pad = pad.clamp(0, 4);
        let (lo, hi) = (frame.key(bounds.lo), frame.key(bounds.hi));
        match counting_table(lo, hi, pad, ids.len()) {
            Some((corner, dims, volume)) => {
                let slots = ids
                    .iter()
                    .map(|&id| {
                        let p = positions[id as usize];
                        slot_of(frame.key_above_corner(p), corner, dims)
                    })
                    .collect();
                Self::counted(positions, ids, slots, corner, dims, volume)
            }
            _ => {
                let keys: Vec<[i32; 3]> = ids
                    .iter()
                    .map(|&id| frame.key(positions[id as usize]))
                    .collect();
                debug_assert_eq!(key_bounds(&keys), (lo, hi));
                Self::sorted(positions, ids, &keys, pad)
            }
        }
    }

    /// [`CellGrid::new`] through one dense table over the padded block of the keys,
    /// whose first slot has the key `corner`; `slots[k]` is point `ids[k]`'s slot.
    fn counted(
        positions: &[Vec3],
        ids: &[u32],
        slots: Vec<u32>,
        corner: [i64; 3],
        dims: [u64; 3],
        volume: usize,
    ) -> Self {
        let m = ids.len();
        let mut table = vec![0u32; volume];
        for &s in &slots {
            table[s as usize] += 1;
        }
        let (cell_keys, start) = number_cells(&mut table, dims, |key| {
            [0, 1, 2].map(|a| (key[a] as i64 + corner[a]) as i32)
        });
        let mut fill = start.clone();
        let mut sorted_ids = vec![0u32; m];
        let mut pts = vec![[0f32; 3]; m];
        for (&s, &id) in slots.iter().zip(ids) {
            let f = &mut fill[table[s as usize] as usize];
            sorted_ids[*f as usize] = id;
            pts[*f as usize] = positions[id as usize];
            *f += 1;
        }
        CellGrid {
            keys: cell_keys,
            start,
            ids: sorted_ids,
            pts,
            lookup: CellLookup::Dense {
                lo: corner.map(|c| c as i32),
                dims: dims.map(|d| d as i64),
                table,
            },
        }
    }

    /// [`CellGrid::new`] by sorting the keys (a block too large for a table).
    fn sorted(positions: &[Vec3], ids: &[u32], keys: &[[i32; 3]], pad: i32) -> Self {
        let m = ids.len();
        let mut order: Vec<u32> = (0..m as u32).collect();
        order.sort_by_key(|&l| {
            let k = keys[l as usize];
            (k[2], k[1], k[0])
        });
        let mut cell_keys = Vec::new();
        let mut start = Vec::new();
        let mut sorted_ids = Vec::with_capacity(m);
        let mut pts = Vec::with_capacity(m);
        for (n, &k) in order.iter().enumerate() {
            let key = keys[k as usize];
            if cell_keys.last() != Some(&key) {
                cell_keys.push(key);
                start.push(n as u32);
            }
            let id = ids[k as usize];
            sorted_ids.push(id);
            pts.push(positions[id as usize]);
        }
        start.push(m as u32);
        let lookup = CellLookup::new(&cell_keys, pad);
        CellGrid {
            keys: cell_keys,
            start,
            ids: sorted_ids,
            pts,
            lookup,
        }
    }

    /// A grid whose cells (keys `keys`, in key order, points `start[c]..start[c + 1]` of
    /// `ids` and `pts`) are numbered in `table`, a dense table over the keys `0..dims`
    /// (x fastest; [`EMPTY`] where no point lies), as [`CellGrid::new`] makes with no
    /// padding.
    pub(crate) fn from_table(
        keys: Vec<[i32; 3]>,
        start: Vec<u32>,
        ids: Vec<u32>,
        pts: Vec<Vec3>,
        dims: [i64; 3],
        table: Vec<u32>,
    ) -> Self {
        debug_assert_eq!(start.len(), keys.len() + 1);
        debug_assert_eq!(table.len() as i64, dims.iter().product::<i64>());
        CellGrid {
            keys,
            start,
            ids,
            pts,
            lookup: CellLookup::Dense {
                lo: [0; 3],
                dims,
                table,
            },
        }
    }

    /// Number of (non-empty) cells.
    pub(crate) fn num_cells(&self) -> usize {
        self.keys.len()
    }

    /// The key of cell `c`.
    pub(crate) fn key(&self, c: u32) -> [i32; 3] {
        self.keys[c as usize]
    }

    /// The stored points of cell `c` (indices into [`CellGrid::ids`], [`CellGrid::pts`]).
    #[inline]
    pub(crate) fn range(&self, c: u32) -> std::ops::Range<usize> {
        self.start[c as usize] as usize..self.start[c as usize + 1] as usize
    }

    /// Per stored point, its id.
    pub(crate) fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// Per stored point, its position.
    pub(crate) fn pts(&self) -> &[Vec3] {
        &self.pts
    }

    /// The stored ids and positions, for a caller that reorders points within cells.
    pub(crate) fn points_mut(&mut self) -> (&mut [u32], &mut [Vec3]) {
        (&mut self.ids, &mut self.pts)
    }

    /// The cell of key `k`, if any point lies in it.
    #[inline]
    pub(crate) fn cell(&self, k: [i32; 3]) -> Option<u32> {
        match &self.lookup {
            CellLookup::Dense { lo, dims, table } => {
                let mut idx = 0i64;
                for a in (0..3).rev() {
                    let o = i64::from(k[a]) - i64::from(lo[a]);
                    if o < 0 || o >= dims[a] {
                        return None;
                    }
                    idx = idx * dims[a] + o;
                }
                let c = table[idx as usize];
                (c != EMPTY).then_some(c)
            }
            CellLookup::Hashed(m) => m.get(&k).copied(),
        }
    }

    /// Calls `f` with every cell holding points in the 3×3×3 block of keys around `k`,
    /// `k`'s own cell left out, in key order, reading the dense table by rows; false
    /// (nothing called) when the look-up is hashed or the block is not wholly inside the
    /// table.
    #[inline]
    pub(crate) fn for_each_in_block3(&self, k: [i32; 3], mut f: impl FnMut(u32)) -> bool {
        let CellLookup::Dense { lo, dims, table } = &self.lookup else {
            return false;
        };
        let o = [0, 1, 2].map(|a| i64::from(k[a]) - i64::from(lo[a]));
        if (0..3).any(|a| o[a] < 1 || o[a] + 1 >= dims[a]) {
            return false;
        }
        let centre = (o[2] * dims[1] + o[1]) * dims[0] + o[0];
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                let mid = (centre + (dz * dims[1] + dy) * dims[0]) as usize;
                for (dx, &c) in table[mid - 1..=mid + 1].iter().enumerate() {
                    if c != EMPTY && (dz, dy, dx) != (0, 0, 1) {
                        f(c);
                    }
                }
            }
        }
        true
    }

    /// Neighbourhood walker for `offsets` (each within the grid's padding on every axis):
    /// see [`CellGrid::near_cell`].
    pub(crate) fn offsets(&self, offsets: &[[i32; 3]]) -> Offsets {
        match &self.lookup {
            CellLookup::Dense { dims, .. } => Offsets::Dense(
                offsets
                    .iter()
                    .map(|o| {
                        (i64::from(o[2]) * dims[1] + i64::from(o[1])) * dims[0] + i64::from(o[0])
                    })
                    .collect(),
            ),
            CellLookup::Hashed(_) => Offsets::Hashed(offsets.to_vec()),
        }
    }

    /// Where cell `c` sits, for [`CellGrid::near_cell`].
    #[inline]
    pub(crate) fn anchor(&self, c: u32) -> Anchor {
        let k = self.keys[c as usize];
        match &self.lookup {
            CellLookup::Dense { lo, dims, .. } => {
                let [x, y, z] = [0, 1, 2].map(|a| i64::from(k[a]) - i64::from(lo[a]));
                Anchor {
                    key: k,
                    slot: (z * dims[1] + y) * dims[0] + x,
                }
            }
            CellLookup::Hashed(_) => Anchor { key: k, slot: 0 },
        }
    }

    /// Appends to `out` the cells at offsets `range` of `offs` from `at` that hold points,
    /// in the offsets' order; returns how many it appended.
    #[inline]
    pub(crate) fn near_cells(
        &self,
        at: Anchor,
        offs: &Offsets,
        range: std::ops::Range<usize>,
        out: &mut [u32],
    ) -> usize {
        let mut n = 0;
        match (&self.lookup, offs) {
            (CellLookup::Dense { table, .. }, Offsets::Dense(d)) => {
                // Branch-free: about half the slots are empty and a branch on them
                // mispredicts; write every one and advance only on a hit.
                for &delta in &d[range] {
                    let c = table[(at.slot + delta) as usize];
                    out[n] = c;
                    n += usize::from(c != EMPTY);
                }
            }
            _ => {
                for i in range {
                    if let Some(c) = self.near_cell(at, offs, i) {
                        out[n] = c;
                        n += 1;
                    }
                }
            }
        }
        n
    }

    /// Writes to `block` the cells of the 3×3×3 block around `at` ([`EMPTY`] where no
    /// point lies) in key order (index `(dz + 1)·9 + (dy + 1)·3 + dx + 1`), read by rows of
    /// the dense table (one bounds check a row, where a look-up by offset checks every
    /// slot); false (nothing written) for a hashed look-up. The grid must have been built
    /// with a padding of at least 1.
    #[inline(always)]
    pub(crate) fn block3(&self, at: Anchor, block: &mut [u32; 27]) -> bool {
        let CellLookup::Dense { table, dims, .. } = &self.lookup else {
            return false;
        };
        for (row, out) in block.chunks_exact_mut(3).enumerate() {
            let (dz, dy) = (row as i64 / 3 - 1, row as i64 % 3 - 1);
            let mid = (at.slot + (dz * dims[1] + dy) * dims[0]) as usize;
            out.copy_from_slice(&table[mid - 1..mid + 2]);
        }
        true
    }

    /// Writes to `out` the cells holding points in the shell of the 5×5×5 block around
    /// `at` (keys within 2 of `at`'s on every axis, 2 away on at least one), in key order;
    /// returns how many. The grid must have been built with a padding of at least 2. A
    /// dense look-up reads the shell by rows of the table (25 rows, one bounds check
    /// each, instead of one look-up per offset); a hashed one looks up `fallback`'s
    /// offsets at `range` (the same cells, in their order).
    #[inline]
    pub(crate) fn shell2_cells(
        &self,
        at: Anchor,
        fallback: &Offsets,
        range: std::ops::Range<usize>,
        out: &mut [u32],
    ) -> usize {
        let CellLookup::Dense { table, dims, .. } = &self.lookup else {
            return self.near_cells(at, fallback, range, out);
        };
        let mut n = 0;
        for dz in -2i64..=2 {
            for dy in -2i64..=2 {
                let mid = (at.slot + (dz * dims[1] + dy) * dims[0]) as usize;
                if dz.abs() == 2 || dy.abs() == 2 {
                    for &c in &table[mid - 2..=mid + 2] {
                        out[n] = c;
                        n += usize::from(c != EMPTY);
                    }
                } else {
                    for c in [table[mid - 2], table[mid + 2]] {
                        out[n] = c;
                        n += usize::from(c != EMPTY);
                    }
                }
            }
        }
        n
    }

    /// The cell at offset `i` of `offs` from `at`, if any point lies in it.
    #[inline]
    pub(crate) fn near_cell(&self, at: Anchor, offs: &Offsets, i: usize) -> Option<u32> {
        match (&self.lookup, offs) {
            (CellLookup::Dense { table, .. }, Offsets::Dense(d)) => {
                let c = table[(at.slot + d[i]) as usize];
                (c != EMPTY).then_some(c)
            }
            (CellLookup::Hashed(m), Offsets::Hashed(o)) => {
                let o = o[i];
                let k = [0, 1, 2].map(|a| at.key[a].saturating_add(o[a]));
                m.get(&k).copied()
            }
            // Offsets are made by the grid they are used with.
            _ => None,
        }
    }
}

/// Writes the cells of `$block` (a [`CellGrid::block3`]) that hold points, taken at the
/// key-order indices listed (literals, so the copy is unrolled and needs no bounds
/// checks), to `$out` from index `$n` on, advancing `$n`.
macro_rules! compact_block3 {
    ($block:expr, $out:expr, $n:ident, [$($k:literal),* $(,)?]) => {
        $(
            let c = $block[$k];
            $out[$n] = c;
            $n += usize::from(c != $crate::grid::EMPTY);
        )*
    };
}
pub(crate) use compact_block3;

/// A cell's place for neighbour look-ups ([`CellGrid::anchor`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Anchor {
    key: [i32; 3],
    slot: i64,
}

/// Offsets to neighbouring cells, prepared for one grid ([`CellGrid::offsets`]).
#[derive(Clone, Debug)]
pub(crate) enum Offsets {
    /// Differences of dense table slots.
    Dense(Vec<i64>),
    /// Key differences.
    Hashed(Vec<[i32; 3]>),
}

impl CellLookup {
    fn new(keys: &[[i32; 3]], pad: i32) -> Self {
        let (lo, hi) = key_bounds(keys);
        let pad = i64::from(pad);
        let dims = [0, 1, 2].map(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1 + 2 * pad).max(1));
        let volume = dims
            .iter()
            .try_fold(1u64, |v, &d| v.checked_mul(u64::try_from(d).ok()?));
        let limit = (keys.len() as u64)
            .saturating_mul(DENSE_FACTOR)
            .max(DENSE_ALWAYS);
        match volume {
            Some(v) if !keys.is_empty() && v <= limit => {
                let corner = [0, 1, 2].map(|a| (i64::from(lo[a]) - pad) as i32);
                let mut table = vec![EMPTY; v as usize];
                for (c, k) in keys.iter().enumerate() {
                    let [x, y, z] = [0, 1, 2].map(|a| i64::from(k[a]) - i64::from(corner[a]));
                    table[((z * dims[1] + y) * dims[0] + x) as usize] = c as u32;
                }
                // The corner is within `pad` of an i32 key, and pad ≤ 4 keeps it in i32
                // for every key a frame makes ([`MAX_CELLS_PER_AXIS`]); absolute keys of
                // extreme coordinates saturate, and their block is never dense.
                CellLookup::Dense {
                    lo: corner,
                    dims,
                    table,
                }
            }
            _ => CellLookup::Hashed(
                keys.iter()
                    .enumerate()
                    .map(|(c, &k)| (k, c as u32))
                    .collect(),
            ),
        }
    }
}

/// The dense table of a grid of `m` points with keys in `lo..=hi` padded by `pad` cells on
/// every side: its first slot's key (`corner`), its dimensions and its number of slots,
/// or `None` when it would be too sparse for counting (more than `COUNTING_FACTOR` slots
/// per point beyond `COUNTING_ALWAYS`) or there are no points: then the keys are sorted.
fn counting_table(
    lo: [i32; 3],
    hi: [i32; 3],
    pad: i32,
    m: usize,
) -> Option<([i64; 3], [u64; 3], usize)> {
    let dims = [0, 1, 2]
        .map(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1 + 2 * i64::from(pad)).max(1) as u64);
    let volume = dims.iter().try_fold(1u64, |v, &d| v.checked_mul(d))?;
    let limit = (m as u64)
        .saturating_mul(COUNTING_FACTOR)
        .max(COUNTING_ALWAYS);
    (m > 0 && volume <= limit).then(|| {
        let corner = [0, 1, 2].map(|a| i64::from(lo[a]) - i64::from(pad));
        (corner, dims, volume as usize)
    })
}

/// The smallest and largest key per axis (`i32::MAX` and `i32::MIN` when there is none).
fn key_bounds(keys: &[[i32; 3]]) -> ([i32; 3], [i32; 3]) {
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for k in keys {
        for a in 0..3 {
            lo[a] = lo[a].min(k[a]);
            hi[a] = hi[a].max(k[a]);
        }
    }
    (lo, hi)
}

/// Positions in `keys` ordered by key (z, then y, then x), equal keys in their order: a
/// counting sort over the keys' bounding block when it is small, a comparison sort
/// otherwise.
pub(super) fn sort_by_key(keys: &[[i32; 3]]) -> Vec<u32> {
    let m = keys.len();
    let (lo, hi) = key_bounds(keys);
    let dims = [0, 1, 2].map(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1).max(1) as u64);
    let volume = dims.iter().try_fold(1u64, |v, &d| v.checked_mul(d));
    match volume {
        Some(volume) if m > 0 && volume <= (m as u64 * 16).max(1 << 16) => {
            // Slots fit in u32: the volume is at most 16 per point (or 2^16).
            let (dx, dy) = (dims[0] as u32, dims[1] as u32);
            let slots: Vec<u32> = keys
                .iter()
                .map(|k| {
                    let [x, y, z] = [0, 1, 2].map(|a| k[a].wrapping_sub(lo[a]) as u32);
                    (z * dy + y) * dx + x
                })
                .collect();
            let mut start = vec![0u32; volume as usize + 1];
            for &s in &slots {
                start[s as usize + 1] += 1;
            }
            for c in 0..volume as usize {
                start[c + 1] += start[c];
            }
            let mut order = vec![0u32; m];
            for (l, &s) in slots.iter().enumerate() {
                let c = &mut start[s as usize];
                order[*c as usize] = l as u32;
                *c += 1;
            }
            order
        }
        _ => {
            let mut order: Vec<u32> = (0..m as u32).collect();
            order.sort_by_key(|&l| {
                let k = keys[l as usize];
                (k[2], k[1], k[0])
            });
            order
        }
    }
}
