//! The one spatial grid of the crate: points binned into cubic cells, stored sorted by cell
//! (each cell a contiguous range), with a look-up of a cell by its integer key, and the
//! exact nearest-neighbour and radius queries built on it ([`NnIndex`]).
//!
//! Every spatial search of the refinement uses it: DBSCAN's neighbour counting
//! ([`crate::dbscan`], cells of side eps/√3), N's nearest clustered point and its votes
//! ([`NnIndex`]), the wide votes and smoothing's cell counts (`steps::LabelCells`), R's
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

use bodyseg_core::math::{Vec3, dist2};
use rustc_hash::FxHashMap;

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
        let g = |a: usize| (self.lo[a] - q[a]).max(q[a] - self.hi[a]).max(0.0);
        let f = |a: usize| (q[a] - self.lo[a]).abs().max((self.hi[a] - q[a]).abs());
        let (g0, g1, g2) = (g(0), g(1), g(2));
        let (f0, f1, f2) = (f(0), f(1), f(2));
        (g0 * g0 + g1 * g1 + g2 * g2, f0 * f0 + f1 * f1 + f2 * f2)
    }

    /// Squared distance from `q` to the box (0 inside): a lower bound of [`dist2`] to any
    /// point inside it, exact in f32 as [`Aabb::near_far2`]'s.
    #[inline]
    pub(crate) fn dist2(&self, q: Vec3) -> f32 {
        let g = |a: usize| (self.lo[a] - q[a]).max(q[a] - self.hi[a]).max(0.0);
        let (g0, g1, g2) = (g(0), g(1), g(2));
        g0 * g0 + g1 * g1 + g2 * g2
    }

    /// Squared gap between two boxes (0 when they overlap): a lower bound of [`dist2`]
    /// between any point of one and any point of the other.
    #[inline]
    pub(crate) fn gap2(&self, o: &Aabb) -> f32 {
        let g = |a: usize| (self.lo[a] - o.hi[a]).max(o.lo[a] - self.hi[a]).max(0.0);
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
    pub(crate) fn covering(positions: &[Vec3], ids: &[u32], side_m: f64) -> GridFrame {
        let mut b = Aabb::EMPTY;
        for &i in ids {
            b.grow(positions[i as usize]);
        }
        if ids.is_empty() {
            b = Aabb {
                lo: [0.0; 3],
                hi: [0.0; 3],
            };
        }
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

    /// The key of `p`'s cell (clamped into the frame, so a point outside the points it
    /// was made from gets the nearest border cell).
    #[inline]
    pub(crate) fn key(&self, p: Vec3) -> [i32; 3] {
        if let Some((lo, inv)) = self.fast {
            // `as` saturates (NaN to 0); the clamp keeps outside points on the border.
            return [0, 1, 2]
                .map(|a| (((p[a] - lo[a]) * inv) as i32).clamp(0, self.max_key[a] as i32));
        }
        [0, 1, 2].map(|a| {
            let k = ((f64::from(p[a]) - self.corner[a]) * self.inv_side) as i64;
            k.clamp(0, self.max_key[a]) as i32
        })
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

/// Marks an empty slot of a dense table.
const EMPTY: u32 = u32::MAX;

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
        let m = ids.len();
        let pad = pad.clamp(0, 4);
        let mut lo = [i32::MAX; 3];
        let mut hi = [i32::MIN; 3];
        for k in keys {
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let dims = [0, 1, 2]
            .map(|a| (i64::from(hi[a]) - i64::from(lo[a]) + 1 + 2 * i64::from(pad)).max(1) as u64);
        let volume = dims.iter().try_fold(1u64, |v, &d| v.checked_mul(d));
        let limit = (m as u64)
            .saturating_mul(COUNTING_FACTOR)
            .max(COUNTING_ALWAYS);
        match volume {
            Some(volume) if m > 0 && volume <= limit => {
                Self::counted(positions, ids, keys, lo, pad, dims, volume as usize)
            }
            _ => Self::sorted(positions, ids, keys, pad),
        }
    }

    /// [`CellGrid::new`] through one dense table over the padded block of the keys.
    fn counted(
        positions: &[Vec3],
        ids: &[u32],
        keys: &[[i32; 3]],
        lo: [i32; 3],
        pad: i32,
        dims: [u64; 3],
        volume: usize,
    ) -> Self {
        let m = ids.len();
        // The table's first slot is the key `lo - pad`; slots fit in u32 (the volume is
        // bounded by COUNTING_FACTOR per point).
        let corner = [0, 1, 2].map(|a| i64::from(lo[a]) - i64::from(pad));
        let (dx, dy) = (dims[0] as u32, dims[1] as u32);
        let slots: Vec<u32> = keys
            .iter()
            .map(|k| {
                let [x, y, z] = [0, 1, 2].map(|a| (i64::from(k[a]) - corner[a]) as u32);
                (z * dy + y) * dx + x
            })
            .collect();
        let mut table = vec![0u32; volume];
        for &s in &slots {
            table[s as usize] += 1;
        }
        // Non-empty slots become cells, in slot order; the table then holds cell numbers.
        let mut cell_keys = Vec::new();
        let mut start = Vec::new();
        let mut fill = Vec::new();
        let mut n = 0u32;
        for (s, t) in table.iter_mut().enumerate() {
            if *t == 0 {
                *t = EMPTY;
                continue;
            }
            let s = s as u64;
            let key = [
                s % dims[0],
                (s / dims[0]) % dims[1],
                s / (dims[0] * dims[1]),
            ];
            cell_keys.push([0, 1, 2].map(|a| (key[a] as i64 + corner[a]) as i32));
            start.push(n);
            fill.push(n);
            n += *t;
            *t = cell_keys.len() as u32 - 1;
        }
        start.push(n);
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
        let mut lo = [i32::MAX; 3];
        let mut hi = [i32::MIN; 3];
        for k in keys {
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
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

/// Positions in `keys` ordered by key (z, then y, then x), equal keys in their order: a
/// counting sort over the keys' bounding block when it is small, a comparison sort
/// otherwise.
fn sort_by_key(keys: &[[i32; 3]]) -> Vec<u32> {
    let m = keys.len();
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for k in keys {
        for a in 0..3 {
            lo[a] = lo[a].min(k[a]);
            hi[a] = hi[a].max(k[a]);
        }
    }
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

/// Fine cells per block edge in [`NnIndex`].
const NN_BLOCK_CELLS: i32 = 4;

/// Exact nearest-neighbour and radius queries over a fixed point set: a [`CellGrid`] of
/// side `eps` (at least 1/64 of the points' extent, at most 64 cells along the longest
/// axis), each cell with the tight box of its points, cells grouped into blocks of 4×4×4
/// with their boxes, so a far query ranks the blocks and opens only those that can hold a
/// nearer point.
pub(crate) struct NnIndex {
    grid: CellGrid,
    /// Cells are placed relative to `lo`, side `1 / inv_side`, `dims` per axis.
    lo: Vec3,
    inv_side: f32,
    dims: [i32; 3],
    cell_box: Vec<Aabb>,
    /// Cells grouped by block (CSR over the non-empty blocks).
    block_cells: Vec<u32>,
    block_start: Vec<u32>,
    block_box: Vec<Aabb>,
}

impl NnIndex {
    /// Indexes the points `idx` of `positions` (cells of side `eps_m`, or 1/64 of the
    /// points' extent when that is larger).
    pub(crate) fn new(positions: &[Vec3], idx: &[u32], eps_m: f32) -> Self {
        let mut bounds = Aabb::EMPTY;
        for &i in idx {
            bounds.grow(positions[i as usize]);
        }
        if idx.is_empty() {
            bounds = Aabb {
                lo: [0.0; 3],
                hi: [0.0; 3],
            };
        }
        let extent = (0..3)
            .map(|a| bounds.hi[a] - bounds.lo[a])
            .fold(0.0f32, f32::max);
        // Cells of side eps, but never more than ~64 along the longest axis (the block
        // scan of a far query stays short, and the cells per axis stay bounded whatever
        // the radius or the coordinates).
        let side = eps_m.max(extent / 64.0).max(1e-6);
        let inv_side = 1.0 / side;
        let dims = [0, 1, 2].map(|a| {
            (((bounds.hi[a] - bounds.lo[a]) * inv_side) as i32)
                .saturating_add(1)
                .clamp(1, 1 << 16)
        });
        let keys: Vec<[i32; 3]> = idx
            .iter()
            .map(|&i| {
                let p = positions[i as usize];
                [0, 1, 2].map(|a| (((p[a] - bounds.lo[a]) * inv_side) as i32).clamp(0, dims[a] - 1))
            })
            .collect();
        let grid = CellGrid::new(positions, idx, &keys, 0);
        let ncells = grid.num_cells();
        let cell_box: Vec<Aabb> = (0..ncells as u32)
            .map(|c| Aabb::of(&grid.pts()[grid.range(c)]))
            .collect();
        // Blocks: the cells are in key order, so bucket them by block key.
        let bdims = dims.map(|d| (d + NN_BLOCK_CELLS - 1) / NN_BLOCK_CELLS);
        let block_keys: Vec<[i32; 3]> = (0..ncells as u32)
            .map(|c| grid.key(c).map(|v| v / NN_BLOCK_CELLS))
            .collect();
        let cell_ids: Vec<u32> = (0..ncells as u32).collect();
        let order = sort_by_key(&block_keys);
        let mut block_cells = Vec::with_capacity(ncells);
        let mut block_start = vec![0u32];
        let mut block_box = Vec::new();
        let mut last = None;
        for &o in &order {
            let bk = block_keys[o as usize];
            if last.is_some_and(|l| l != bk) {
                block_start.push(block_cells.len() as u32);
            }
            if last != Some(bk) {
                block_box.push(Aabb::EMPTY);
                last = Some(bk);
            }
            let c = cell_ids[o as usize];
            block_cells.push(c);
            if let Some(b) = block_box.last_mut() {
                b.union(&cell_box[c as usize]);
            }
        }
        block_start.push(block_cells.len() as u32);
        if block_box.is_empty() {
            block_start = vec![0];
        }
        debug_assert!(bdims.iter().all(|&d| d >= 1));
        NnIndex {
            grid,
            lo: bounds.lo,
            inv_side,
            dims,
            cell_box,
            block_cells,
            block_start,
            block_box,
        }
    }

    /// The key of `q`'s cell, unclamped (may lie outside `0..dims`).
    #[inline]
    fn key_of(&self, q: Vec3) -> [i32; 3] {
        [0, 1, 2].map(|a| ((q[a] - self.lo[a]) * self.inv_side).floor() as i32)
    }

    fn inside(&self, k: [i32; 3]) -> bool {
        (0..3).all(|a| k[a] >= 0 && k[a] < self.dims[a])
    }

    /// The nearest indexed point to `q` (ties: smaller id); `None` when the index is
    /// empty.
    ///
    /// Near the points (most noise: unknown points on a body, points at its edges) the
    /// answer lies in the query's own 3×3×3 block of cells: the own cell is scanned, then
    /// the block, stopping as soon as the best point is nearer than the block's walls.
    /// Farther, the block nearest to `q` is opened first so the bound is tight, then every
    /// other block is checked against it in one linear pass (a few hundred box tests).
    pub(crate) fn nearest(&self, q: Vec3) -> Option<u32> {
        self.nearest_with(q, &mut Vec::new())
    }

    /// [`NnIndex::nearest`] with `scratch` for the far search's block bounds (no
    /// allocation per query).
    pub(crate) fn nearest_with(&self, q: Vec3, scratch: &mut Vec<f32>) -> Option<u32> {
        let mut best: Option<(f32, u32)> = None;
        let k = self.key_of(q);
        if self.inside(k) {
            if let Some(own) = self.grid.cell(k) {
                self.scan_cell(q, own as usize, &mut best);
                if best.is_some_and(|(b2, _)| b2 <= self.wall_dist2(q, k, 0)) {
                    return best.map(|(_, j)| j);
                }
            }
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let n = [k[0] + dx, k[1] + dy, k[2] + dz];
                        if (dx, dy, dz) == (0, 0, 0) {
                            continue;
                        }
                        if let Some(c) = self.grid.cell(n)
                            && best.is_none_or(|(b2, _)| self.cell_box[c as usize].dist2(q) <= b2)
                        {
                            self.scan_cell(q, c as usize, &mut best);
                        }
                    }
                }
            }
            if best.is_some_and(|(b2, _)| b2 <= self.wall_dist2(q, k, 1)) {
                return best.map(|(_, j)| j);
            }
        }
        let blb = scratch;
        blb.clear();
        blb.extend(self.block_box.iter().map(|bx| bx.dist2(q)));
        let b0 = (0..blb.len()).min_by(|&a, &b| blb[a].total_cmp(&blb[b]))?;
        let c0 = self
            .cells_of_block(b0)
            .iter()
            .min_by(|&&a, &&b| {
                self.cell_box[a as usize]
                    .dist2(q)
                    .total_cmp(&self.cell_box[b as usize].dist2(q))
            })
            .copied()?;
        self.scan_cell(q, c0 as usize, &mut best);
        for (b, &lb) in blb.iter().enumerate() {
            if best.is_some_and(|(b2, _)| lb > b2) {
                continue;
            }
            for &c in self.cells_of_block(b) {
                if c != c0 && best.is_none_or(|(b2, _)| self.cell_box[c as usize].dist2(q) <= b2) {
                    self.scan_cell(q, c as usize, &mut best);
                }
            }
        }
        best.map(|(_, j)| j)
    }

    /// Calls `f(squared distance, id)` for every indexed point within `r2` of `q`, in no
    /// particular order (the same for the same query): for votes that sum all of them;
    /// `cells` is scratch.
    pub(crate) fn for_each_within(
        &self,
        q: Vec3,
        r2: f32,
        cells: &mut Vec<(f32, u32)>,
        mut f: impl FnMut(f32, u32),
    ) {
        self.cells_within(q, r2, cells);
        for &(_, c) in cells.iter() {
            let r = self.grid.range(c);
            for (&j, &p) in self.grid.ids()[r.clone()].iter().zip(&self.grid.pts()[r]) {
                let d2 = dist2(q, p);
                if d2 <= r2 {
                    f(d2, j);
                }
            }
        }
    }

    /// The non-empty cells whose box lies within `r2` of `q`, as (squared distance, cell),
    /// in the order of their keys (z, y, x). The block of cells walked is bounded by the
    /// grid's cells per axis, whatever the radius.
    fn cells_within(&self, q: Vec3, r2: f32, cells: &mut Vec<(f32, u32)>) {
        cells.clear();
        let kc = self.key_of(q);
        // In cells; a huge (or NaN) radius walks the whole grid, never more.
        let reach = (r2.sqrt() * self.inv_side).ceil();
        let reach = if reach < (1u32 << 30) as f32 {
            (reach as i64).max(1)
        } else {
            i64::from(i32::MAX)
        };
        let range = |a: usize| {
            let lo = (i64::from(kc[a]) - reach).max(0);
            let hi = (i64::from(kc[a]) + reach).min(i64::from(self.dims[a]) - 1);
            lo as i32..=hi as i32
        };
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    let Some(c) = self.grid.cell([x, y, z]) else {
                        continue;
                    };
                    let d = self.cell_box[c as usize].dist2(q);
                    if d <= r2 {
                        cells.push((d, c));
                    }
                }
            }
        }
    }

    /// The at most `k` indexed points nearest to `q` within squared distance `r2`, as
    /// `(squared distance, id)` sorted by distance then id, into `out`. Every cell within
    /// reach of `r2` is searched, nearest first; `cells` is scratch.
    pub(crate) fn knn_within(
        &self,
        q: Vec3,
        k: usize,
        r2: f32,
        out: &mut Vec<(f32, u32)>,
        cells: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        self.cells_within(q, r2, cells);
        cells.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(d, c) in cells.iter() {
            if out.len() == k && out.last().is_some_and(|&(w, _)| d > w) {
                break;
            }
            let r = self.grid.range(c);
            for (&j, &p) in self.grid.ids()[r.clone()].iter().zip(&self.grid.pts()[r]) {
                let d2 = dist2(q, p);
                if d2 > r2 {
                    continue;
                }
                let beats = |&(w, wj): &(f32, u32)| d2 < w || (d2 == w && j < wj);
                if out.len() == k && !out.last().is_some_and(beats) {
                    continue;
                }
                let at = out.partition_point(|e| !beats(e));
                out.insert(at, (d2, j));
                out.truncate(k);
            }
        }
    }

    /// Squared distance from `q` (in cell `k`) to the walls of the block of cells within
    /// `r` cells of `k`, shaved by a hair: no point outside that block is nearer.
    fn wall_dist2(&self, q: Vec3, k: [i32; 3], r: i32) -> f32 {
        let side = 1.0 / self.inv_side;
        let mut m = f32::INFINITY;
        for a in 0..3 {
            let lo = self.lo[a] + (k[a] - r) as f32 * side;
            let hi = self.lo[a] + (k[a] + r + 1) as f32 * side;
            m = m.min(q[a] - lo).min(hi - q[a]);
        }
        let m = m.max(0.0);
        m * m * (1.0 - 1e-4)
    }

    fn cells_of_block(&self, b: usize) -> &[u32] {
        &self.block_cells[self.block_start[b] as usize..self.block_start[b + 1] as usize]
    }

    #[inline]
    fn scan_cell(&self, q: Vec3, c: usize, best: &mut Option<(f32, u32)>) {
        let r = self.grid.range(c as u32);
        for (&j, &p) in self.grid.ids()[r.clone()].iter().zip(&self.grid.pts()[r]) {
            let d2 = dist2(q, p);
            if best.is_none_or(|(b2, bj)| d2 < b2 || (d2 == b2 && j < bj)) {
                *best = Some((d2, j));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny xorshift so these unit tests need no dev-dependency; the seed is printed by
    /// every assertion message (`case`), and fixed so that a failure reproduces.
    fn rng_from(seed: u64) -> impl FnMut() -> f32 {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Random points: a cluttered box, sometimes with a few far strays (kilometres away:
    /// the hashed look-up) or many duplicates.
    fn cloud(rng: &mut impl FnMut() -> f32, case: usize) -> Vec<Vec3> {
        let n = 1 + (case * 53) % 700;
        let mut pos: Vec<Vec3> = (0..n)
            .map(|_| [rng() * 0.6, rng() * 0.4, rng() * 0.3])
            .collect();
        if case % 5 == 1 {
            pos.push([3_000.0, -2_000.0, 1.0]);
            pos.push([-120_000.0, 120_000.0, -120_000.0]);
        }
        if case % 7 == 3 {
            let p = pos[0];
            pos.extend(std::iter::repeat_n(p, 50));
        }
        pos
    }

    #[test]
    fn the_grid_holds_every_point_once_in_its_cell_and_finds_every_cell() {
        let mut rng = rng_from(3);
        for case in 0..60 {
            let pos = cloud(&mut rng, case);
            let ids: Vec<u32> = (0..pos.len() as u32).filter(|i| i % 3 != 1).collect();
            // Relative cells (tiny to coarse), and absolute ones as the votes use them.
            let side = [1e-9, 0.003, 0.02, 0.3][case % 4];
            let frame = GridFrame::covering(&pos, &ids, side);
            let keys: Vec<[i32; 3]> = if case % 2 == 0 {
                ids.iter().map(|&i| frame.key(pos[i as usize])).collect()
            } else {
                let s = side as f32;
                ids.iter()
                    .map(|&i| pos[i as usize].map(|x| (x / s).floor() as i32))
                    .collect()
            };
            let grid = CellGrid::new(&pos, &ids, &keys, 2);
            let mut seen = vec![0usize; pos.len()];
            let mut prev: Option<[i32; 3]> = None;
            for c in 0..grid.num_cells() as u32 {
                let k = grid.key(c);
                assert!(
                    prev.is_none_or(|p| (p[2], p[1], p[0]) < (k[2], k[1], k[0])),
                    "case {case}: cells in key order"
                );
                prev = Some(k);
                assert_eq!(grid.cell(k), Some(c), "case {case}: look-up");
                let r = grid.range(c);
                assert!(!r.is_empty());
                for n in r.clone() {
                    let id = grid.ids()[n];
                    seen[id as usize] += 1;
                    assert_eq!(grid.pts()[n], pos[id as usize]);
                    let want = keys[ids.iter().position(|&i| i == id).unwrap_or(0)];
                    assert_eq!(want, k, "case {case}: point {id} in its cell");
                }
                // Within a cell, the order of `ids`.
                assert!(grid.ids()[r].windows(2).all(|w| w[0] < w[1]));
            }
            for (i, &s) in seen.iter().enumerate() {
                assert_eq!(
                    s,
                    usize::from(ids.contains(&(i as u32))),
                    "case {case}: {i}"
                );
            }
            // Keys of no point: none, near and far (the padded border, the hashed map).
            for k in [[-5, 0, 0], [i32::MAX, i32::MIN, 0], [1 << 29, 0, 3]] {
                if !keys.contains(&k) {
                    assert_eq!(grid.cell(k), None, "case {case}: {k:?}");
                }
            }
            // Neighbours through offsets equal neighbours through keys.
            let offsets: Vec<[i32; 3]> = (-2..=2)
                .flat_map(|z| (-2..=2).flat_map(move |y| (-2..=2).map(move |x| [x, y, z])))
                .collect();
            let offs = grid.offsets(&offsets);
            for c in 0..grid.num_cells() as u32 {
                let at = grid.anchor(c);
                let k = grid.key(c);
                for (o, d) in offsets.iter().enumerate() {
                    let want = grid.cell([k[0] + d[0], k[1] + d[1], k[2] + d[2]]);
                    assert_eq!(grid.near_cell(at, &offs, o), want, "case {case}");
                }
            }
        }
    }

    #[test]
    fn a_frame_never_overflows_and_keeps_its_side_when_it_can() {
        let pos = vec![
            [-3.0e38f32, 0.0, 1.0],
            [3.0e38, 1e-30, -1.0],
            [0.0, 0.0, 0.0],
        ];
        let ids = [0u32, 1, 2];
        let f = GridFrame::covering(&pos, &ids, 1e-12);
        assert!(f.side_m() >= 6.0e38 / MAX_CELLS_PER_AXIS);
        let keys: Vec<[i32; 3]> = pos.iter().map(|&p| f.key(p)).collect();
        assert_eq!(keys[0][0], 0);
        assert!(keys[1][0] > 0 && f64::from(keys[1][0]) <= MAX_CELLS_PER_AXIS);
        let grid = CellGrid::new(&pos, &ids, &keys, 2);
        assert_eq!(grid.num_cells(), 3);
        // A small extent keeps the asked side.
        let near = vec![[0.0f32, 0.0, 0.0], [1.0, 2.0, 3.0]];
        let f = GridFrame::covering(&near, &[0, 1], 0.01);
        assert_eq!(f.side_m(), 0.01);
        assert_eq!(f.key([1.0, 2.0, 3.0]), [100, 200, 300]);
        // A point outside the frame gets the nearest border cell.
        assert_eq!(f.key([-7.0, 99.0, 1.5]), [0, 200, 150]);
    }

    #[test]
    fn radius_queries_equal_brute_force() {
        let mut rng = rng_from(7);
        for case in 0..40 {
            let pos = cloud(&mut rng, case);
            let idx: Vec<u32> = (0..pos.len() as u32).filter(|i| i % 4 != 0).collect();
            if idx.is_empty() {
                continue;
            }
            let index = NnIndex::new(&pos, &idx, 0.05);
            let mut cells = Vec::new();
            for _ in 0..20 {
                let q = [rng() * 0.8 - 0.1, rng() * 0.6 - 0.1, rng() * 0.5 - 0.1];
                for r in [0.0, 0.01, 0.05, 0.13, 1e3, f32::INFINITY] {
                    let r2 = r * r;
                    let mut want: Vec<(f32, u32)> = idx
                        .iter()
                        .map(|&j| (dist2(q, pos[j as usize]), j))
                        .filter(|&(d2, _)| d2 <= r2)
                        .collect();
                    want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    let mut got = Vec::new();
                    index.for_each_within(q, r2, &mut cells, |d2, j| got.push((d2, j)));
                    got.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    assert_eq!(got, want, "case {case}, r {r}");
                }
            }
        }
    }

    #[test]
    fn nearest_neighbour_index_equals_brute_force() {
        let mut rng = rng_from(11);
        for case in 0..50 {
            let n = 1 + (case * 37) % 400;
            let pos: Vec<Vec3> = (0..n)
                .map(|_| {
                    [
                        rng() * 2.0,
                        rng() * 1.0,
                        rng() * 0.5 + if case % 3 == 0 { 5.0 } else { 0.0 },
                    ]
                })
                .collect();
            let is_noise: Vec<bool> = (0..n).map(|_| rng() < 0.3).collect();
            let clustered: Vec<u32> = (0..n as u32).filter(|&i| !is_noise[i as usize]).collect();
            if clustered.is_empty() {
                continue;
            }
            let index = NnIndex::new(&pos, &clustered, 0.05);
            for _ in 0..20 {
                let q = [rng() * 4.0 - 1.0, rng() * 3.0 - 1.0, rng() * 7.0 - 1.0];
                let want = clustered.iter().copied().min_by(|&a, &b| {
                    dist2(q, pos[a as usize])
                        .total_cmp(&dist2(q, pos[b as usize]))
                        .then(a.cmp(&b))
                });
                assert_eq!(index.nearest(q), want, "case {case}");
            }
        }
    }

    #[test]
    fn knn_within_equals_brute_force() {
        let mut rng = rng_from(5);
        for case in 0..40 {
            let n = 1 + (case * 53) % 600;
            let pos: Vec<Vec3> = (0..n)
                .map(|_| [rng() * 0.5, rng() * 0.4, rng() * 0.3])
                .collect();
            let idx: Vec<u32> = (0..n as u32).filter(|i| i % 4 != 0).collect();
            if idx.is_empty() {
                continue;
            }
            let eps = 0.05;
            let index = NnIndex::new(&pos, &idx, eps);
            let (mut out, mut cells) = (Vec::new(), Vec::new());
            for _ in 0..20 {
                let q = [rng() * 0.7 - 0.1, rng() * 0.6 - 0.1, rng() * 0.5 - 0.1];
                // Within one cell's side, beyond it (a wide N), and every point within reach
                // (smoothing: k larger than the cells hold).
                for (k, r) in [
                    (1 + case % 9, eps),
                    (5 + 7 * (case % 13), 2.6 * eps),
                    (usize::MAX / 2, 2.6 * eps),
                ] {
                    index.knn_within(q, k, r * r, &mut out, &mut cells);
                    let mut want: Vec<(f32, u32)> = idx
                        .iter()
                        .map(|&j| (dist2(q, pos[j as usize]), j))
                        .filter(|&(d2, _)| d2 <= r * r)
                        .collect();
                    want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    let mut all = Vec::new();
                    index.for_each_within(q, r * r, &mut cells, |d2, j| all.push((d2, j)));
                    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    assert_eq!(all, want, "case {case}, all within {r}");
                    want.truncate(k);
                    assert_eq!(out, want, "case {case}, k {k}, r {r}");
                }
            }
        }
    }
}
