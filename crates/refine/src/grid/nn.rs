//! [`NnIndex`]: exact nearest-neighbour and radius queries on a [`CellGrid`].

use super::{Aabb, CellGrid, EMPTY, GridFrame, min_finite, number_cells, sort_by_key};
use bodyseg_core::math::{Vec3, dist2};

/// N's search opens this many blocks by linear passes for the nearest one before sorting
/// the rest (most searches end within the first few; a pass is cheaper than a sort then).
const SELECTED_BLOCKS: usize = 4;

/// Scratch space of [`NnIndex::nearest_with`], kept between queries.
#[derive(Debug, Default)]
pub(crate) struct NnScratch {
    /// Per block: the squared distance from the query to its box.
    blocks: Vec<f32>,
    /// Cells to scan: (squared distance to the box, cell).
    cells: Vec<(f32, u32)>,
    /// Blocks to open: (squared distance to the box, block).
    open: Vec<(f32, u32)>,
}

/// `x.floor() as i32` without a call to `floorf` (the default x86-64 target has no
/// rounding instruction): the truncation, one less when it lies above `x`. Equal for every
/// `x`: both saturate beyond i32 (`saturating_sub` keeps `i32::MIN`), NaN gives 0 in both.
#[inline(always)]
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    t.saturating_sub(i32::from(t as f32 > x))
}

/// Fine cells per block edge in [`NnIndex`].
const NN_BLOCK_CELLS: i32 = 4;

/// [`NnIndex::from_cells`] merges 2×2×2 of the parts' cells into one of its cells: DBSCAN's
/// cells (eps/√3·0.999) then make cells of 1.15·eps, about [`NnIndex::new`]'s (eps), with
/// which the near search of most noise points ends in the 3×3×3 block. (DBSCAN's cells
/// as they are: 166.2M instructions per refinement at 100k, the far search opening many
/// small cells, against 172.2M before; merged 2×2×2: see docs/notes, fourth round.)
const MERGE_SHIFT: i32 = 1;

/// Most slots of the dense table [`NnIndex::from_cells`] lays over the whole frame, per
/// point (a person's cells fill a few percent of their block)...
const FROM_CELLS_FACTOR: u64 = 64;
/// ...or this many in any case (4 MiB).
const FROM_CELLS_ALWAYS: u64 = 1 << 20;

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
    /// Per block key (x fastest, `block_dims` per axis): its block, or [`EMPTY`]; empty
    /// when that table would be large (then the far search checks every block).
    block_table: Vec<u32>,
    block_dims: [i32; 3],
    /// Per cell, its points in runs, each with a box holding them (CSR: the runs of cell
    /// `c` are `runs[run_start[c]..run_start[c + 1]]`), so that a scan passes over the
    /// runs beyond the best point; empty when the cells are scanned whole.
    runs: Vec<Run>,
    run_start: Vec<u32>,
}

/// One DBSCAN group's cells for [`NnIndex::from_cells`]: its grid, the box of each cell's
/// points, and per stored point its component (`None`: not indexed).
pub(crate) type CellPart<'a> = (&'a CellGrid, &'a [Aabb], &'a [Option<u32>]);

/// Stored points `start..end` of an [`NnIndex`] cell, all inside `bbox`.
#[derive(Clone, Copy, Debug)]
struct Run {
    bbox: Aabb,
    start: u32,
    end: u32,
}

/// [`NnIndex`] lays a table over its blocks' keys when it holds at most this many slots per
/// block, or [`BLOCK_TABLE_ALWAYS`] in any case.
const BLOCK_TABLE_FACTOR: usize = 8;
const BLOCK_TABLE_ALWAYS: usize = 1 << 12;

impl NnIndex {
    /// Indexes the points `idx` of `positions` (cells of side `eps_m`, or 1/64 of the
    /// points' extent when that is larger).
    pub(crate) fn new(positions: &[Vec3], idx: &[u32], eps_m: f32) -> Self {
        let bounds = Aabb::of_ids(positions, idx);
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
        let lo = bounds.lo;
        let max = [dims[0] - 1, dims[1] - 1, dims[2] - 1];
        let mut keys: Vec<[i32; 3]> = Vec::with_capacity(idx.len());
        for &i in idx {
            let p = positions[i as usize];
            let k = |a: usize| (((p[a] - lo[a]) * inv_side) as i32).max(0).min(max[a]);
            keys.push([k(0), k(1), k(2)]);
        }
        let grid = CellGrid::new(positions, idx, &keys, 0);
        let cell_box: Vec<Aabb> = (0..grid.num_cells() as u32)
            .map(|c| Aabb::of(&grid.pts()[grid.range(c)]))
            .collect();
        Self::with_blocks(grid, lo, inv_side, dims, cell_box)
    }

    /// The index of the points that `parts` keep, each part a grid in `frame`'s cells
    /// (DBSCAN's label groups: [`crate::dbscan`]) with, per stored point, `Some` when the
    /// index holds it (a clustered point). The parts' cells are merged by key (one table
    /// over the frame, no key computed again); within a cell the points come part by
    /// part. `None` when the frame computes keys in f64 or is too large for one table
    /// (the caller then uses [`NnIndex::new`]: the answers are the same, exact).
    pub(crate) fn from_cells(frame: &GridFrame, parts: &[CellPart<'_>]) -> Option<Self> {
        let (lo, inv_side, max_key) = frame.f32_keys()?;
        // A part's key `k` is `⌊(p − lo)·inv⌋`; halving `inv` is exact in f32, so
        // `k >> 1` is `⌊(p − lo)·inv/2⌋`, the key [`NnIndex::key_of`] computes.
        let inv_side = inv_side / (1 << MERGE_SHIFT) as f32;
        let merged = |k: [i32; 3]| k.map(|v| v >> MERGE_SHIFT);
        let dims = merged(max_key).map(|k| i64::from(k) + 1);
        let m: usize = parts.iter().map(|(_, _, keep)| keep.len()).sum();
        let volume = dims
            .iter()
            .try_fold(1u64, |v, &d| v.checked_mul(u64::try_from(d).ok()?))?;
        if volume
            > (m as u64)
                .saturating_mul(FROM_CELLS_FACTOR)
                .max(FROM_CELLS_ALWAYS)
        {
            return None;
        }
        let slot = |k: [i32; 3]| {
            ((i64::from(k[2]) * dims[1] + i64::from(k[1])) * dims[0] + i64::from(k[0])) as usize
        };
        // Kept points per slot, then cells numbered in slot (= key) order. Per part
        // cell: its kept points (a run of the merged cell when any).
        let mut table = vec![0u32; volume as usize];
        // Per part cell: its kept points and its merged cell's slot (computed once).
        let mut kept: Vec<(u32, u32)> =
            Vec::with_capacity(parts.iter().map(|(g, _, _)| g.num_cells()).sum());
        for (g, _, keep) in parts {
            for c in 0..g.num_cells() as u32 {
                let k = keep[g.range(c)].iter().filter(|k| k.is_some()).count() as u32;
                let s = slot(merged(g.key(c)));
                table[s] += k;
                kept.push((k, s as u32));
            }
        }
        let (keys, start) =
            number_cells(&mut table, dims.map(|d| d as u64), |k| k.map(|v| v as i32));
        let n = start[keys.len()];
        // Runs per merged cell (CSR), then the points and runs in place.
        let mut run_start = vec![0u32; keys.len() + 1];
        for &(k, s) in &kept {
            if k > 0 {
                run_start[table[s as usize] as usize + 1] += 1;
            }
        }
        for c in 0..keys.len() {
            run_start[c + 1] += run_start[c];
        }
        let mut run_fill = run_start.clone();
        let empty = Run {
            bbox: Aabb::EMPTY,
            start: 0,
            end: 0,
        };
        let mut runs = vec![empty; run_start[keys.len()] as usize];
        let mut fill = start.clone();
        let mut ids = vec![0u32; n as usize];
        let mut pts = vec![[0f32; 3]; n as usize];
        let mut cell_box = vec![Aabb::EMPTY; keys.len()];
        let mut kept = kept.iter();
        for (g, part_box, keep) in parts {
            for c in 0..g.num_cells() as u32 {
                let Some(&(n_kept, s)) = kept.next() else {
                    break;
                };
                if n_kept == 0 {
                    continue;
                }
                let r = g.range(c);
                let cell = table[s as usize] as usize;
                let f = &mut fill[cell];
                let first = *f;
                if n_kept as usize == r.len() {
                    // Every point kept (most cells): the run copied whole.
                    let to = first as usize..first as usize + r.len();
                    ids[to.clone()].copy_from_slice(&g.ids()[r.clone()]);
                    pts[to].copy_from_slice(&g.pts()[r]);
                    *f += n_kept;
                } else {
                    for ((&id, &p), k) in g.ids()[r.clone()]
                        .iter()
                        .zip(&g.pts()[r.clone()])
                        .zip(&keep[r])
                    {
                        if k.is_some() {
                            ids[*f as usize] = id;
                            pts[*f as usize] = p;
                            *f += 1;
                        }
                    }
                }
                // The part's box holds all of its cell's points, the kept ones among them:
                // a looser bound than theirs, never a wrong one.
                let bbox = part_box[c as usize];
                cell_box[cell].union(&bbox);
                runs[run_fill[cell] as usize] = Run {
                    bbox,
                    start: first,
                    end: *f,
                };
                run_fill[cell] += 1;
            }
        }
        let grid = CellGrid::from_table(keys, start, ids, pts, dims, table);
        let dims = dims.map(|d| d as i32);
        let mut index = Self::with_blocks(grid, lo, inv_side, dims, cell_box);
        index.runs = runs;
        index.run_start = run_start;
        Some(index)
    }

    /// The index over `grid` (cells placed from `lo`, `1 / inv_side` wide, `dims` per
    /// axis, each with the tight box of its points), cells grouped into blocks of
    /// [`NN_BLOCK_CELLS`] per edge.
    fn with_blocks(
        grid: CellGrid,
        lo: Vec3,
        inv_side: f32,
        dims: [i32; 3],
        cell_box: Vec<Aabb>,
    ) -> Self {
        let ncells = grid.num_cells();
        // Blocks: the cells are in key order, so bucket them by block key.
        let block_keys: Vec<[i32; 3]> = (0..ncells as u32)
            .map(|c| grid.key(c).map(|v| v / NN_BLOCK_CELLS))
            .collect();
        let order = sort_by_key(&block_keys);
        let mut block_cells = Vec::with_capacity(ncells);
        let mut block_start = vec![0u32];
        let mut block_box = Vec::new();
        let mut last = None;
        for &c in &order {
            let bk = block_keys[c as usize];
            if last.is_some_and(|l| l != bk) {
                block_start.push(block_cells.len() as u32);
            }
            if last != Some(bk) {
                block_box.push(Aabb::EMPTY);
                last = Some(bk);
            }
            block_cells.push(c);
            if let Some(b) = block_box.last_mut() {
                b.union(&cell_box[c as usize]);
            }
        }
        block_start.push(block_cells.len() as u32);
        if block_box.is_empty() {
            block_start = vec![0];
        }
        let block_dims = dims.map(|d| (d + NN_BLOCK_CELLS - 1) / NN_BLOCK_CELLS);
        let slots = block_dims
            .iter()
            .try_fold(1usize, |v, &d| v.checked_mul(usize::try_from(d).ok()?));
        let block_table = match slots {
            Some(n) if n <= (block_box.len() * BLOCK_TABLE_FACTOR).max(BLOCK_TABLE_ALWAYS) => {
                let mut t = vec![EMPTY; n];
                for b in 0..block_box.len() {
                    let c = block_cells[block_start[b] as usize];
                    let k = grid.key(c).map(|v| v / NN_BLOCK_CELLS);
                    let slot = (k[2] as usize * block_dims[1] as usize + k[1] as usize)
                        * block_dims[0] as usize
                        + k[0] as usize;
                    t[slot] = b as u32;
                }
                t
            }
            _ => Vec::new(),
        };
        NnIndex {
            grid,
            lo,
            inv_side,
            dims,
            cell_box,
            block_cells,
            block_start,
            block_box,
            block_table,
            block_dims,
            runs: Vec::new(),
            run_start: Vec::new(),
        }
    }

    /// The key of `q`'s cell, unclamped (may lie outside `0..dims`).
    #[inline]
    fn key_of(&self, q: Vec3) -> [i32; 3] {
        let k = |a: usize| floor_i32((q[a] - self.lo[a]) * self.inv_side);
        [k(0), k(1), k(2)]
    }

    fn inside(&self, k: [i32; 3]) -> bool {
        (0..3).all(|a| k[a] >= 0 && k[a] < self.dims[a])
    }

    /// The nearest indexed point to `q` (ties: smaller id); `None` when the index is
    /// empty.
    ///
    /// Near the points (most noise: unknown points on a body, points at its edges) the
    /// answer lies in the query's own 3×3×3 block of cells: the own cell is scanned, then
    /// the other cells of the block nearest first (by their boxes), stopping as soon as the
    /// next box is farther than the best point, and the search ends when the best point is
    /// nearer than the block's walls. Farther, the block nearest to `q` is opened first so
    /// the bound is tight, every other block is checked against it in one linear pass (a
    /// few hundred box tests), and the cells of the blocks that pass are scanned nearest
    /// first, again only while their boxes are not farther than the best point.
    pub(crate) fn nearest(&self, q: Vec3) -> Option<u32> {
        self.nearest_with(q, &mut NnScratch::default())
    }

    /// [`NnIndex::nearest`] with `scratch` for the bounds of blocks and cells (no
    /// allocation per query).
    pub(crate) fn nearest_with(&self, q: Vec3, scratch: &mut NnScratch) -> Option<u32> {
        self.nearest_from(q, None, scratch)
    }

    /// [`NnIndex::nearest_with`] starting from `hint`, an indexed point (id, position)
    /// thought to be near `q` (the answer of a previous query nearby): its distance bounds
    /// the search from the start, and the answer is the same whatever the hint.
    pub(crate) fn nearest_from(
        &self,
        q: Vec3,
        hint: Option<(u32, Vec3)>,
        scratch: &mut NnScratch,
    ) -> Option<u32> {
        let mut best: Option<(f32, u32)> = hint.map(|(j, p)| (dist2(q, p), j));
        let NnScratch {
            blocks,
            cells,
            open,
        } = scratch;
        let k = self.key_of(q);
        if self.inside(k) {
            if let Some(own) = self.grid.cell(k) {
                self.scan_cell(q, own as usize, &mut best);
                if best.is_some_and(|(b2, _)| b2 <= self.wall_dist2(q, k, 0)) {
                    return best.map(|(_, j)| j);
                }
            }
            cells.clear();
            let mut consider = |c: u32| {
                let lb = self.cell_box[c as usize].dist2(q);
                if best.is_none_or(|(b2, _)| lb <= b2) {
                    cells.push((lb, c));
                }
            };
            // The other cells of the 3×3×3 block: by rows of the table when the block lies
            // inside it (one bounds check per row), else key by key.
            if !self.grid.for_each_in_block3(k, &mut consider) {
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let n = [k[0] + dx, k[1] + dy, k[2] + dz];
                            if (dx, dy, dz) == (0, 0, 0) {
                                continue;
                            }
                            if let Some(c) = self.grid.cell(n) {
                                consider(c);
                            }
                        }
                    }
                }
            }
            self.scan_nearest_first(q, cells, &mut best);
            if best.is_some_and(|(b2, _)| b2 <= self.wall_dist2(q, k, 1)) {
                return best.map(|(_, j)| j);
            }
        }
        // With a bound, the blocks within it are found by their keys; without one, the
        // nearest cell of the nearest block gives one.
        let mut c0 = u32::MAX;
        open.clear();
        if let Some((b2, _)) = best
            && self.blocks_within(q, b2, open)
        {
        } else {
            blocks.clear();
            blocks.extend(self.block_box.iter().map(|bx| bx.dist2(q)));
            if best.is_none() {
                let b0 = (0..blocks.len()).min_by(|&a, &b| blocks[a].total_cmp(&blocks[b]))?;
                c0 = self
                    .cells_of_block(b0)
                    .iter()
                    .min_by(|&&a, &&b| {
                        self.cell_box[a as usize]
                            .dist2(q)
                            .total_cmp(&self.cell_box[b as usize].dist2(q))
                    })
                    .copied()?;
                self.scan_cell(q, c0 as usize, &mut best);
            }
            open.extend(
                blocks
                    .iter()
                    .enumerate()
                    .filter(|&(_, &lb)| best.is_none_or(|(b2, _)| lb <= b2))
                    .map(|(b, &lb)| (lb, b as u32)),
            );
        }
        // The blocks that can hold a nearer point, opened nearest first: the best point
        // found in the nearer ones rules out the cells, then the blocks, farther away
        // (exact, as in `scan_nearest_first`).
        // The first few by linear passes (most searches end there), the rest sorted.
        let mut rest = open.len();
        for _ in 0..SELECTED_BLOCKS {
            if rest == 0 {
                return best.map(|(_, j)| j);
            }
            let mut m = 0;
            for i in 1..rest {
                if open[i].0 < open[m].0 {
                    m = i;
                }
            }
            let (lb, b) = open[m];
            if best.is_some_and(|(b2, _)| lb > b2) {
                return best.map(|(_, j)| j);
            }
            self.scan_block(q, b, c0, cells, &mut best);
            rest -= 1;
            open.swap(m, rest);
        }
        let open = &mut open[..rest];
        open.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(lb, b) in open.iter() {
            if best.is_some_and(|(b2, _)| lb > b2) {
                break;
            }
            self.scan_block(q, b, c0, cells, &mut best);
        }
        best.map(|(_, j)| j)
    }

    /// Scans the cells of block `b` (but `skip`, scanned already) whose boxes are not
    /// farther than the best point, nearest first.
    fn scan_block(
        &self,
        q: Vec3,
        b: u32,
        skip: u32,
        cells: &mut Vec<(f32, u32)>,
        best: &mut Option<(f32, u32)>,
    ) {
        cells.clear();
        for &c in self.cells_of_block(b as usize) {
            if c == skip {
                continue;
            }
            let lb = self.cell_box[c as usize].dist2(q);
            if best.is_none_or(|(b2, _)| lb <= b2) {
                cells.push((lb, c));
            }
        }
        self.scan_nearest_first(q, cells, best);
    }

    /// Scans the cells of `cells` (lower bound of the squared distance to `q`, cell) in
    /// the order of their bounds, until the next bound exceeds the best point found:
    /// those cells cannot hold a nearer point, nor one as near (the bound is exact in
    /// f32, see [`Aabb::near_far2`]), so the best point is the one a scan of all of them
    /// finds. Reorders `cells`.
    ///
    /// The nearest remaining cell is picked by a linear pass each time rather than by
    /// sorting them all: the search stops after a few cells (the best point is then nearer
    /// than the rest), and the order among cells of equal bounds does not change the
    /// answer (ties between points go to the smaller id whatever the scan order).
    fn scan_nearest_first(&self, q: Vec3, cells: &mut [(f32, u32)], best: &mut Option<(f32, u32)>) {
        let mut rest = cells.len();
        while rest > 0 {
            let mut m = 0;
            for i in 1..rest {
                if cells[i].0 < cells[m].0 {
                    m = i;
                }
            }
            let (lb, c) = cells[m];
            if best.is_some_and(|(b2, _)| lb > b2) {
                break;
            }
            self.scan_cell(q, c as usize, best);
            rest -= 1;
            cells.swap(m, rest);
        }
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
    /// `r` cells of `k`, shaved by a hair: no point outside that block is nearer. The
    /// hair: a few f32 rounding steps of the coordinates and the walls (the points' keys
    /// and the walls are computed apart, each rounded), and 10⁻⁴ of the square.
    fn wall_dist2(&self, q: Vec3, k: [i32; 3], r: i32) -> f32 {
        let side = 1.0 / self.inv_side;
        let mut m = f32::INFINITY;
        for a in 0..3 {
            let lo = self.lo[a] + (k[a] - r) as f32 * side;
            let hi = self.lo[a] + (k[a] + r + 1) as f32 * side;
            let slack = 4.0 * f32::EPSILON * (q[a].abs() + self.lo[a].abs() + hi.abs() + lo.abs());
            m = m.min(q[a] - lo - slack).min(hi - q[a] - slack);
        }
        let m = m.max(0.0);
        m * m * (1.0 - 1e-4)
    }

    /// Appends to `open` (squared distance to the box, block) every block whose box lies
    /// within `b2` of `q`, found by the block keys around `q`; false (nothing appended)
    /// when there is no block table or the key range holds more slots than there are
    /// blocks (checking every block is then cheaper).
    ///
    /// Exact: a point `p` with `dist2(q, p) ≤ b2` lies within `r` of `q` on every axis,
    /// `r` being √b2 widened past f32's rounding of `dist2`, the root and `q ± r`; the
    /// key of a coordinate (`⌊(x − lo)·inv⌋`, clamped, as the points' keys are computed)
    /// never decreases with it, so `p`'s key lies between those of `q − r` and `q + r`.
    fn blocks_within(&self, q: Vec3, b2: f32, open: &mut Vec<(f32, u32)>) -> bool {
        if self.block_table.is_empty() {
            return false;
        }
        let mut range = [(0i32, 0i32); 3];
        let mut slots = 1usize;
        for a in 0..3 {
            let r = b2.sqrt() * (1.0 + 1e-5) + 4.0 * f32::EPSILON * (q[a].abs() + self.lo[a].abs());
            let key = |x: f32| {
                floor_i32((x - self.lo[a]) * self.inv_side).clamp(0, self.dims[a] - 1)
                    / NN_BLOCK_CELLS
            };
            range[a] = (key(q[a] - r), key(q[a] + r));
            slots = slots.saturating_mul((range[a].1 - range[a].0 + 1) as usize);
        }
        if slots > self.block_box.len() {
            return false;
        }
        let [dx, dy, _] = self.block_dims.map(|d| d as usize);
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                for x in range[0].0..=range[0].1 {
                    let b = self.block_table[(z as usize * dy + y as usize) * dx + x as usize];
                    if b == EMPTY {
                        continue;
                    }
                    let lb = self.block_box[b as usize].dist2(q);
                    if lb <= b2 {
                        open.push((lb, b));
                    }
                }
            }
        }
        true
    }

    fn cells_of_block(&self, b: usize) -> &[u32] {
        &self.block_cells[self.block_start[b] as usize..self.block_start[b + 1] as usize]
    }

    /// Makes `best` the nearest of itself and the points of cell `c` to `q` (ties: the
    /// smaller id), run by run when the cell has runs.
    #[inline(always)]
    fn scan_cell(&self, q: Vec3, c: usize, best: &mut Option<(f32, u32)>) {
        if self.runs.is_empty() {
            self.scan_points(q, self.grid.range(c as u32), best);
            return;
        }
        let runs = &self.runs[self.run_start[c] as usize..self.run_start[c + 1] as usize];
        for run in runs {
            // Strictly farther: the run cannot hold a nearer point, nor a tie.
            if best.is_some_and(|(b2, _)| run.bbox.dist2(q) > b2) {
                continue;
            }
            self.scan_points(q, run.start as usize..run.end as usize, best);
        }
    }

    /// Makes `best` the nearest of itself and the stored points `r` to `q` (ties: the
    /// smaller id). Points are tested four at a time: a block whose nearest point is
    /// farther than `best` (most of them once `best` is near) is passed over after four
    /// distances and one comparison; the others are updated one point at a time, with
    /// [`dist2`]'s values, so the answer is the same.
    #[inline(always)]
    fn scan_points(&self, q: Vec3, r: std::ops::Range<usize>, best: &mut Option<(f32, u32)>) {
        let (ids, pts) = (&self.grid.ids()[r.clone()], &self.grid.pts()[r]);
        let update = |best: &mut Option<(f32, u32)>, d2: f32, j: u32| {
            if best.is_none_or(|(b2, bj)| d2 < b2 || (d2 == b2 && j < bj)) {
                *best = Some((d2, j));
            }
        };
        let mut blocks_p = pts.chunks_exact(4);
        let mut blocks_i = ids.chunks_exact(4);
        for (bp, bi) in (&mut blocks_p).zip(&mut blocks_i) {
            let d = [
                dist2(q, bp[0]),
                dist2(q, bp[1]),
                dist2(q, bp[2]),
                dist2(q, bp[3]),
            ];
            let m = min_finite(min_finite(d[0], d[1]), min_finite(d[2], d[3]));
            if best.is_some_and(|(b2, _)| m > b2) {
                continue;
            }
            for l in 0..4 {
                update(best, d[l], bi[l]);
            }
        }
        for (&p, &j) in blocks_p.remainder().iter().zip(blocks_i.remainder()) {
            update(best, dist2(q, p), j);
        }
    }
}

#[cfg(test)]
mod floor_tests {
    use super::floor_i32;

    #[test]
    fn floor_i32_equals_floor_as_i32_at_the_edges_and_between() {
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - f32::EPSILON,
            -1.0 + f32::EPSILON / 2.0,
            8_388_607.5,
            -8_388_607.5,
            2_147_483_520.0,
            2_147_483_648.0,
            -2_147_483_648.0,
            -2_147_483_904.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        for x in edges {
            assert_eq!(floor_i32(x), x.floor() as i32, "x = {x:e}");
        }
        // A sweep of bit patterns across the whole range (every 65 521st).
        for bits in (0..=u32::MAX).step_by(65_521) {
            let x = f32::from_bits(bits);
            assert_eq!(floor_i32(x), x.floor() as i32, "x = {x:e} (bits {bits:#x})");
        }
    }
}
