//! Core counting: which points have at least `min_points` neighbours within eps (moved
//! out of `dbscan.rs` to keep that file under the 1000-line limit).

use super::group::{GroupGrid, Neighbours, Thresholds};
use crate::grid::Aabb;
use bodyseg_core::Label;
use bodyseg_core::math::{Vec3, dist2};

/// Per stored point: whether it is core. `MIXED = false` when the group holds one label.
/// Also the neighbour lists of the cells left with a non-core point.
pub(super) fn core_points<const MIXED: bool>(
    g: &GroupGrid,
    min_pts: usize,
    th: Thresholds,
) -> (Vec<bool>, BorderCells) {
    if !MIXED {
        return core_points_one_label(g, min_pts, th.same2);
    }
    let mut core = vec![false; g.grid.pts().len()];
    let mut border = BorderCells::default();
    let mut nbrs = Neighbours::new();
    for c in 0..g.num_cells() as u32 {
        let r = g.grid.range(c);
        if r.len() >= min_pts && g.whole[c as usize] {
            core[r].fill(true);
            continue;
        }
        let nbrs = nbrs.at(g, c);
        let mut all_core = true;
        for i in r {
            core[i] = is_core_point::<MIXED>(g, c, i, min_pts, th, nbrs);
            all_core &= core[i];
        }
        if !all_core {
            border.push(c, nbrs.all(g));
        }
    }
    (core, border)
}

/// The full neighbour lists (as [`Neighbours::all`] gives them) of the cells where core
/// counting left a non-core point, in cell order: the cells the border pass visits. A
/// point is found non-core only after its count walked every neighbour cell, so the list
/// is at hand then, and the border pass does not look the 125 cells up again.
#[derive(Default)]
pub(super) struct BorderCells {
    pub(super) cells: Vec<u32>,
    start: Vec<u32>,
    nbrs: Vec<u32>,
}

impl BorderCells {
    fn push(&mut self, c: u32, nbrs: &[u32]) {
        self.cells.push(c);
        self.start.push(self.nbrs.len() as u32);
        self.nbrs.extend_from_slice(nbrs);
    }

    /// The list of the `k`-th cell pushed.
    pub(super) fn list(&self, k: usize) -> &[u32] {
        let end = self
            .start
            .get(k + 1)
            .map_or(self.nbrs.len(), |&e| e as usize);
        &self.nbrs[self.start[k] as usize..end]
    }
}

/// A neighbour cell as the core test of one cell's points reads it: copied once per cell
/// into a short list that stays in L1 while each of the cell's points walks it.
#[derive(Clone, Copy)]
struct NearCell {
    bbox: Aabb,
    start: u32,
    end: u32,
}

/// [`core_points`] for a group of one label (every pair of points within eps are
/// neighbours): the hot loop of the clustering.
/// At the end of a walk's list: appends `nbrs`' far cells (beyond the 3×3×3 block) to
/// `cells` the first time, returning true (walk on); false once they were listed (the walk
/// is over). One function for the one-point and four-lane walks.
#[inline(always)]
fn list_far_cells(
    cells: &mut Vec<NearCell>,
    far_listed: &mut bool,
    nbrs: &mut Neighbours,
    g: &GroupGrid,
    table: &[NearCell],
) -> bool {
    if *far_listed {
        return false;
    }
    let near = nbrs.near().len();
    cells.extend(nbrs.all(g)[near..].iter().map(|&d| table[d as usize]));
    *far_listed = true;
    true
}

fn core_points_one_label(g: &GroupGrid, min_pts: usize, eps2: f32) -> (Vec<bool>, BorderCells) {
    let pts = g.grid.pts();
    let mut core = vec![false; pts.len()];
    let mut border = BorderCells::default();
    // The coordinates by axis (structure of arrays), so that the distance tests of a
    // neighbour cell's run are counted [`LANES`] at a time (see `Soa::count_within`).
    let soa = Soa::of(pts);
    let mut nbrs = Neighbours::new();
    let mut cells: Vec<NearCell> = Vec::with_capacity(125);
    // Every cell's entry made once (a cell is the neighbour of ~13 others): listing a
    // neighbour is then one copy.
    let table: Vec<NearCell> = (0..g.num_cells() as u32)
        .map(|d| {
            let r = g.grid.range(d);
            NearCell {
                bbox: g.bbox[d as usize],
                start: r.start as u32,
                end: r.end as u32,
            }
        })
        .collect();
    for c in 0..g.num_cells() as u32 {
        let r = g.grid.range(c);
        let whole = g.whole[c as usize];
        if r.len() >= min_pts && whole {
            core[r].fill(true);
            continue;
        }
        // The own cell comes first among the neighbours; when whole it counts at once.
        let nbrs = nbrs.at(g, c);
        let skip = usize::from(whole);
        cells.clear();
        cells.extend(nbrs.near()[skip..].iter().map(|&d| table[d as usize]));
        let mut far_listed = false;
        let own = if whole { r.len() } else { 0 };
        let mut all_core = true;
        // Cells of a few points or more: their points four at a time (cell-major), each
        // neighbour cell's box tested against four points in one pass
        // ([`Aabb::near_far2_x4`]). Each point still walks the cells in the same order and
        // stops where it would alone (a lane is left once its count reaches `min_pts`),
        // so every count is the same.
        if r.len() < LANE_CELL_POINTS {
            for i in r {
                let p = pts[i];
                let mut count = own;
                let mut k = 0;
                while count < min_pts {
                    if k == cells.len() {
                        if !list_far_cells(&mut cells, &mut far_listed, nbrs, g, &table) {
                            break;
                        }
                        continue;
                    }
                    let n = cells[k];
                    k += 1;
                    let (near2, far2) = n.bbox.near_far2(p);
                    if near2 > eps2 {
                        continue;
                    }
                    let run = n.start as usize..n.end as usize;
                    if far2 <= eps2 {
                        count += run.len();
                    } else {
                        count = soa.count_within(p, run, eps2, count, min_pts);
                    }
                }
                core[i] = count >= min_pts;
                all_core &= core[i];
            }
        } else {
            // Counts and lane masks in u32 (four to a vector): counts are at most the
            // group's points (u32 ids), and `min_pts` is at most their number here.
            let need = min_pts as u32;
            for s in r.clone().step_by(4) {
                let lanes = (r.end - s).min(4);
                let (mut x, mut y, mut z) = ([0f32; 4], [0f32; 4], [0f32; 4]);
                if lanes == 4 {
                    // Four whole lanes (most groups): fixed-size loads, no call to memcpy.
                    let four = |v: &[f32]| <[f32; 4]>::try_from(&v[s..s + 4]).unwrap_or_default();
                    (x, y, z) = (four(&soa.x), four(&soa.y), four(&soa.z));
                } else {
                    x[..lanes].copy_from_slice(&soa.x[s..s + lanes]);
                    y[..lanes].copy_from_slice(&soa.y[s..s + lanes]);
                    z[..lanes].copy_from_slice(&soa.z[s..s + lanes]);
                }
                let mut count = [own as u32; 4];
                // The lanes holding a point (`lanes` of them), when the own cell does not
                // make them core already.
                let live = mask(own < min_pts);
                let mut active = FIRST_LANES[lanes];
                for a in &mut active {
                    *a &= live;
                }
                let mut k = 0;
                while active != [0; 4] {
                    if k == cells.len() {
                        if !list_far_cells(&mut cells, &mut far_listed, nbrs, g, &table) {
                            break;
                        }
                        continue;
                    }
                    let n = cells[k];
                    k += 1;
                    let (near2, far2) = n.bbox.near_far2_x4(&x, &y, &z);
                    let len = n.end - n.start;
                    let mut partial = [0u32; 4];
                    for l in 0..4 {
                        let reach = active[l] & mask(near2[l] <= eps2);
                        let all = reach & mask(far2[l] <= eps2);
                        count[l] += all & len;
                        partial[l] = reach & !all;
                    }
                    if partial != [0; 4] {
                        let run = n.start as usize..n.end as usize;
                        for l in 0..4 {
                            if partial[l] != 0 {
                                let p = [x[l], y[l], z[l]];
                                count[l] = soa.count_within(
                                    p,
                                    run.clone(),
                                    eps2,
                                    count[l] as usize,
                                    min_pts,
                                ) as u32;
                            }
                        }
                    }
                    for l in 0..4 {
                        active[l] &= mask(count[l] < need);
                    }
                }
                for l in 0..lanes {
                    core[s + l] = count[l] >= need;
                    all_core &= core[s + l];
                }
            }
        }
        if !all_core {
            border.push(c, nbrs.all(g));
        }
    }
    (core, border)
}

/// Cells of at least this many points count their points four at a time in core counting.
const LANE_CELL_POINTS: usize = 3;

/// Per number of points in a group of lanes (0 to 4): the masks of its first lanes.
const FIRST_LANES: [[u32; 4]; 5] = [
    [0, 0, 0, 0],
    [u32::MAX, 0, 0, 0],
    [u32::MAX, u32::MAX, 0, 0],
    [u32::MAX, u32::MAX, u32::MAX, 0],
    [u32::MAX; 4],
];

/// All ones when `b`, else zero: a lane mask.
#[inline(always)]
fn mask(b: bool) -> u32 {
    0u32.wrapping_sub(u32::from(b))
}

/// Point coordinates split by axis, m, in the grid's stored order.
struct Soa {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

/// Lanes of one branch-free block of distance tests in [`Soa::count_within`]. Four, not
/// eight: most runs are short (a median of 2–19 points per cell on sensor clouds), and a
/// run's tail past the last block is tested one point at a time (callgrind, synth 100k:
/// 170.83M instructions per refinement with 4, 171.45M with 8).
const LANES: usize = 4;

impl Soa {
    fn of(pts: &[Vec3]) -> Soa {
        Soa {
            x: pts.iter().map(|p| p[0]).collect(),
            y: pts.iter().map(|p| p[1]).collect(),
            z: pts.iter().map(|p| p[2]).collect(),
        }
    }

    /// `count` plus the stored points of `run` within `eps2` of `p`, counted in blocks of
    /// [`LANES`] and stopping after the block that reaches `need` (a core test only needs
    /// to know that the count reached it). Each test computes [`dist2`]'s expression in
    /// its order (`p - q` per axis, `dx² + dy² + dz²`), so the answers are the same bits.
    #[inline(always)]
    fn count_within(
        &self,
        p: Vec3,
        run: std::ops::Range<usize>,
        eps2: f32,
        mut count: usize,
        need: usize,
    ) -> usize {
        let (xs, ys, zs) = (&self.x[run.clone()], &self.y[run.clone()], &self.z[run]);
        let within = |x: f32, y: f32, z: f32| usize::from(dist2(p, [x, y, z]) <= eps2);
        let blocks = xs.len() / LANES;
        for b in 0..blocks {
            let s = b * LANES;
            let (bx, by, bz) = (&xs[s..s + LANES], &ys[s..s + LANES], &zs[s..s + LANES]);
            let mut hits = 0;
            for l in 0..LANES {
                hits += within(bx[l], by[l], bz[l]);
            }
            count += hits;
            if count >= need {
                return count;
            }
        }
        for t in blocks * LANES..xs.len() {
            count += within(xs[t], ys[t], zs[t]);
        }
        count
    }
}

/// True when stored point `i` (in cell `c`, whose neighbours are `nbrs`) has at least
/// `min_pts` neighbours within eps.
#[inline]
fn is_core_point<const MIXED: bool>(
    g: &GroupGrid,
    c: u32,
    i: usize,
    min_pts: usize,
    th: Thresholds,
    nbrs: &mut Neighbours,
) -> bool {
    let p = g.grid.pts()[i];
    let li = g.lbl[i];
    let mut count = 0usize;
    // The point's own cell comes first among its neighbours; when its diameter is below
    // eps and it holds one label, all of it counts and it is not visited again.
    let mut skip = 0;
    if g.whole[c as usize] {
        count = g.grid.range(c).len();
        if count >= min_pts {
            return true;
        }
        skip = 1;
    }
    for &d in &nbrs.near()[skip..] {
        count += neighbours_in::<MIXED>(g, p, li, d, th);
        if count >= min_pts {
            return true;
        }
    }
    let near = nbrs.near().len();
    for &d in &nbrs.all(g)[near..] {
        count += neighbours_in::<MIXED>(g, p, li, d, th);
        if count >= min_pts {
            return true;
        }
    }
    false
}

/// How many points of cell `d` are neighbours of `p` (label `li`): none when the cell's
/// box lies beyond eps, all when it lies within (and holds `li` only), else counted.
#[inline(always)]
fn neighbours_in<const MIXED: bool>(
    g: &GroupGrid,
    p: Vec3,
    li: Label,
    d: u32,
    th: Thresholds,
) -> usize {
    let d = d as usize;
    let (near2, far2) = g.bbox[d].near_far2(p);
    if near2 > th.reach2() {
        return 0;
    }
    let r = g.grid.range(d as u32);
    if far2 <= th.same2 && (!MIXED || (g.uniform[d] && g.lbl[r.start] == li)) {
        r.len()
    } else if MIXED {
        g.grid.pts()[r.clone()]
            .iter()
            .zip(&g.lbl[r])
            .filter(|&(&q, &l)| dist2(p, q) <= th.get(li, l))
            .count()
    } else {
        let t = th.same2;
        g.grid.pts()[r]
            .iter()
            .filter(|&&q| dist2(p, q) <= t)
            .count()
    }
}
