//! Connecting core points into clusters (moved out of `dbscan.rs` to keep that file under
//! the 1000-line limit).

use super::group::{GroupGrid, NEAR_OFFSETS, Thresholds, UnionFind, forward_offsets};
use crate::grid::{Aabb, Anchor, EMPTY, Offsets, compact_block3};
use bodyseg_core::math::dist2;

/// Connects core points (core q within eps of core p): the union-find over cells when
/// every cell is whole (all its core points are neighbours of one another, a small array
/// that stays in L1), over stored points otherwise; true in the first case.
pub(super) fn connect(
    g: &GroupGrid,
    core_end: &[u32],
    core_box: &[Aabb],
    th: Thresholds,
) -> (UnionFind, bool) {
    let ncells = g.num_cells();
    let core_range = |c: u32| g.grid.range(c).start..core_end[c as usize] as usize;
    // Per cell: whether it holds a core point (read for every neighbour of every cell).
    let core_cells: Vec<bool> = (0..ncells as u32)
        .map(|c| core_end[c as usize] as usize > g.grid.range(c).start)
        .collect();
    let has_core = |c: u32| core_cells[c as usize];
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
                    if g.whole[c as usize] || dist2(pts[i], pts[j]) <= g.threshold(th, i, j) {
                        uf.union(i as u32, j as u32);
                    }
                }
            }
        }
    }
    let (forward, near) = forward_offsets();
    let offs = g.grid.offsets(forward);
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
                    if dist2(pts[i], pts[j]) <= g.threshold(th, i, j) {
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
        let n = forward_near_cells(g, g.grid.anchor(c), &offs, near, &mut found);
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
    // Per component of the near pass (by its root): its cells, and the box of its core
    // points.
    let mut size = vec![0u32; ncells];
    let mut comp_box = vec![Aabb::EMPTY; ncells];
    let mut near_root = vec![u32::MAX; ncells];
    for c in 0..ncells as u32 {
        if has_core(c) {
            let r = uf.find(c) as usize;
            near_root[c as usize] = r as u32;
            size[r] += 1;
            comp_box[r].union(&core_box[c as usize]);
        }
    }
    // A cell of the largest component (its root may change as others join it).
    let Some(largest) = (0..ncells as u32).max_by_key(|&r| size[r as usize]) else {
        return (uf, all_whole);
    };
    // The components whose box lies within reach of another's: only they can be joined
    // by a far pair (its core points lie in both boxes). With many components the
    // pairwise test costs more than it saves, and every component counts as near one.
    let roots: Vec<u32> = (0..ncells as u32)
        .filter(|&r| size[r as usize] > 0)
        .collect();
    let mut near_other = vec![roots.len() > MAX_COMPONENT_PAIRS_OF; ncells];
    if roots.len() <= MAX_COMPONENT_PAIRS_OF {
        for (i, &a) in roots.iter().enumerate() {
            for &b in &roots[i + 1..] {
                if comp_box[a as usize].gap2(&comp_box[b as usize]) <= reach2 {
                    near_other[a as usize] = true;
                    near_other[b as usize] = true;
                }
            }
        }
    }
    for c in 0..ncells as u32 {
        // Skipped: `c` is joined to the largest component, so is every cell skipped, and
        // a pair of cells not both skipped is met from the other one. Also skipped: `c`'s
        // component of the near pass has no other within reach (no far pair joins it).
        if !has_core(c) || uf.find(c) == uf.find(largest) {
            continue;
        }
        if !near_other[near_root[c as usize] as usize] {
            continue;
        }
        let n = g
            .grid
            .shell2_cells(g.grid.anchor(c), &g.offs, NEAR_OFFSETS..125, &mut found);
        // As in the near pass: most far cells are in `c`'s component already (a small
        // cluster of another label, say), settled by one `find` without a call to `link`.
        let mut root_c = uf.find(c);
        for &d in &found[..n] {
            if has_core(d) && uf.find(d) != root_c {
                link(&mut uf, c, d);
                root_c = uf.find(c);
            }
        }
    }
    (uf, all_whole)
}

/// Writes to `found` (at least 27 long) the cells holding points at the first `near`
/// offsets of `offs` (the forward offsets of the 3×3×3 block, [`forward_offsets`], made
/// for `g`'s grid) from `at`, in their order; returns how many. With a dense look-up the
/// block is read by rows of the table and the cells are taken in that order by index
/// (a test checks that both ways give the same list).
#[inline(always)]
pub(super) fn forward_near_cells(
    g: &GroupGrid,
    at: Anchor,
    offs: &Offsets,
    near: usize,
    found: &mut [u32],
) -> usize {
    let mut block = [EMPTY; 27];
    if !g.grid.block3(at, &mut block) {
        return g.grid.near_cells(at, offs, 0..near, found);
    }
    let out: &mut [u32; 27] = (&mut found[..27])
        .try_into()
        .expect("a slice of 27 is an array of 27");
    let mut n = 0;
    compact_block3!(
        block,
        out,
        n,
        [14, 16, 22, 15, 17, 19, 21, 23, 25, 18, 20, 24, 26]
    );
    n
}

/// The far pass tests the components' boxes pairwise (to skip those with no other within
/// reach) when there are at most this many components.
const MAX_COMPONENT_PAIRS_OF: usize = 128;

/// Some pair of core points, one from each range, within eps (whole single-label cells).
fn any_pair(
    g: &GroupGrid,
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
    b_box: Aabb,
    th: Thresholds,
) -> Option<(usize, usize)> {
    let t = g.threshold(th, a.start, b.start);
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
