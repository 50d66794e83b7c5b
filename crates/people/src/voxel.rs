//! Voxel downsampling, the voxel neighbour graph and Euclidean clustering on it.

use bodyseg_core::math::{Vec3, dist2};
use rustc_hash::{FxHashMap, FxHashSet};

/// Points averaged into voxels. Voxels are numbered in order of their first point.
pub(crate) struct Voxels {
    /// Centroid of each voxel's points, metres.
    pub centers: Vec<Vec3>,
    /// Per voxel, the class id most of its points carry (ties: lower id).
    pub labels: Vec<u8>,
    /// Number of points in each voxel.
    pub counts: Vec<u32>,
    /// Index (into the input cloud) of every kept point.
    pub points: Vec<u32>,
    /// For each kept point, its voxel.
    pub point_voxel: Vec<u32>,
}

/// Integer voxel coordinates packed into one key (21 bits per axis: ±40 km at 4 cm).
fn key(p: Vec3, inv: f32) -> u64 {
    let c = |v: f32| ((v * inv).floor() as i64 + (1 << 20)) as u64 & 0x1F_FFFF;
    (c(p[0]) << 42) | (c(p[1]) << 21) | c(p[2])
}

/// Averages the points `(index, position, class id)` into cubes of edge `voxel_m`.
pub(crate) fn voxelize(points: impl Iterator<Item = (usize, Vec3, u8)>, voxel_m: f32) -> Voxels {
    let inv = 1.0 / voxel_m;
    let mut index: FxHashMap<u64, u32> = FxHashMap::default();
    let mut sums: Vec<[f64; 3]> = Vec::new();
    let mut counts: Vec<[u32; 8]> = Vec::new();
    let mut kept = Vec::new();
    let mut point_voxel = Vec::new();
    for (i, p, class) in points {
        let next = sums.len() as u32;
        let v = *index.entry(key(p, inv)).or_insert(next);
        if v == next {
            sums.push([0.0; 3]);
            counts.push([0; 8]);
        }
        let s = &mut sums[v as usize];
        for a in 0..3 {
            s[a] += f64::from(p[a]);
        }
        let c = &mut counts[v as usize];
        c[usize::from(class.min(6))] += 1;
        c[7] += 1;
        kept.push(i as u32);
        point_voxel.push(v);
    }
    let centers = sums
        .iter()
        .zip(&counts)
        .map(|(s, c)| {
            let n = f64::from(c[7]);
            [(s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32]
        })
        .collect();
    let labels = counts
        .iter()
        .map(|c| {
            let mut best = 0;
            for k in 1..7 {
                if c[k] > c[best] {
                    best = k;
                }
            }
            best as u8
        })
        .collect();
    Voxels {
        centers,
        labels,
        counts: counts.iter().map(|c| c[7]).collect(),
        points: kept,
        point_voxel,
    }
}

/// The neighbour graph of points: an edge joins two points closer than `gap_m`. A grid of
/// cell `gap_m` (points sorted by cell, each occupied cell's 27 neighbour cells looked up
/// once) finds every point's neighbours once, when the graph is built; they are stored
/// (compressed rows, with the squared distance), since the finders walk the graph several
/// times (components, splits, growth). With the graph built only among the voxels walked
/// (see [`VoxelGraph::new`]), `cargo bench -p bodyseg-people --bench boxes`, same session:
/// labels 5.69 → 3.72 ms, geometry 21.4 → 17.1 ms, geometry with colours 24.4 → 17.0 ms;
/// keeping the rows where they are found instead of copying them into point order, 3.29,
/// 15.8 and 16.1 ms (a later run).
pub(crate) struct VoxelGraph {
    /// Per point `i`, its neighbours are `edges[rows[i].0..rows[i].1]` (rows laid out in
    /// the grid's cell order; empty for points the graph is not built among).
    rows: Vec<(u32, u32)>,
    /// (neighbour, squared distance).
    edges: Vec<(u32, f32)>,
}

impl VoxelGraph {
    /// Builds the graph among the points where `among` is true: the others have no
    /// edges (the finders only ever walk kept voxels: geometry mode's above the floor,
    /// labels mode's dense ones), so the floor's voxels cost nothing.
    pub fn new(centers: &[Vec3], gap_m: f32, among: &[bool]) -> VoxelGraph {
        let n = centers.len();
        let inv = 1.0 / gap_m;
        let gap2 = gap_m * gap_m;
        let cell_of = |p: Vec3| {
            [
                (p[0] * inv).floor() as i32,
                (p[1] * inv).floor() as i32,
                (p[2] * inv).floor() as i32,
            ]
        };
        let cells: Vec<[i32; 3]> = centers.iter().map(|&p| cell_of(p)).collect();
        let mut order: Vec<u32> = (0..n as u32).filter(|&i| among[i as usize]).collect();
        order.sort_unstable_by_key(|&i| (cells[i as usize], i));
        let m = order.len();
        let sorted: Vec<Vec3> = order.iter().map(|&i| centers[i as usize]).collect();
        let mut ranges: FxHashMap<[i32; 3], (u32, u32)> = FxHashMap::default();
        let mut bounds = Vec::new();
        let mut k = 0;
        while k < m {
            let c = cells[order[k] as usize];
            let mut e = k + 1;
            while e < m && cells[order[e] as usize] == c {
                e += 1;
            }
            ranges.insert(c, (k as u32, e as u32));
            bounds.push((c, k, e));
            k = e;
        }
        let mut rows: Vec<(u32, u32)> = vec![(0, 0); n];
        let mut edges: Vec<(u32, f32)> = Vec::new();
        let mut near = Vec::with_capacity(27);
        for (c, start, end) in bounds {
            near.clear();
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(&r) = ranges.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            near.push(r);
                        }
                    }
                }
            }
            for a in start..end {
                let (i, p) = (order[a], sorted[a]);
                let first = edges.len() as u32;
                for &(s0, s1) in &near {
                    for b in s0..s1 {
                        let d2 = dist2(p, sorted[b as usize]);
                        let j = order[b as usize];
                        if d2 < gap2 && j != i {
                            edges.push((j, d2));
                        }
                    }
                }
                rows[i as usize] = (first, edges.len() as u32);
            }
        }
        VoxelGraph { rows, edges }
    }

    /// Calls `f(j, distance²)` for every neighbour `j` of point `i` (not `i` itself).
    #[inline]
    pub(crate) fn for_neighbors(&self, i: usize, mut f: impl FnMut(u32, f32)) {
        let (a, b) = self.rows[i];
        for &(j, d2) in &self.edges[a as usize..b as usize] {
            f(j, d2);
        }
    }

    /// The neighbours of `i`, ascending (tests).
    #[cfg(test)]
    pub fn neighbors(&self, i: usize) -> Vec<u32> {
        let mut out = Vec::new();
        self.for_neighbors(i, |j, _| out.push(j));
        out.sort_unstable();
        out
    }

    /// Connected components among the points where `keep` is true; each component's
    /// points ascending, components in order of their smallest point.
    pub fn components(&self, keep: &[bool]) -> Vec<Vec<u32>> {
        self.components_along(keep, |_, _| true)
    }

    /// [`VoxelGraph::components`] joining two points only where `joined(i, j)` (e.g. along a
    /// body: parts that touch within one body, not a hand on someone's trunk).
    pub fn components_along(
        &self,
        keep: &[bool],
        joined: impl Fn(u32, u32) -> bool,
    ) -> Vec<Vec<u32>> {
        let n = keep.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                let up = parent[parent[i as usize] as usize];
                parent[i as usize] = up;
                i = up;
            }
            i
        }
        let mut links = Vec::new();
        for i in 0..n {
            if !keep[i] {
                continue;
            }
            links.clear();
            self.for_neighbors(i, |j, _| {
                if (j as usize) > i && keep[j as usize] && joined(i as u32, j) {
                    links.push(j);
                }
            });
            for &j in &links {
                let (a, b) = (root(&mut parent, i as u32), root(&mut parent, j));
                if a != b {
                    // The smaller index becomes the root: roots are smallest members.
                    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                    parent[hi as usize] = lo;
                }
            }
        }
        let mut slot = vec![u32::MAX; n];
        let mut out: Vec<Vec<u32>> = Vec::new();
        for i in 0..n {
            if !keep[i] {
                continue;
            }
            let r = root(&mut parent, i as u32) as usize;
            if slot[r] == u32::MAX {
                slot[r] = out.len() as u32;
                out.push(Vec::new());
            }
            out[slot[r] as usize].push(i as u32);
        }
        out
    }

    /// The points reachable from `start` along the graph through points where `keep` is
    /// true (`start` included whatever `keep` says), in the order they were reached.
    pub fn grow(&self, start: u32, keep: impl Fn(u32) -> bool) -> Vec<u32> {
        let mut seen = FxHashSet::default();
        seen.insert(start);
        let mut out = vec![start];
        let mut k = 0;
        while k < out.len() {
            let i = out[k] as usize;
            k += 1;
            self.for_neighbors(i, |j, _| {
                if keep(j) && seen.insert(j) {
                    out.push(j);
                }
            });
        }
        out
    }

    /// Multi-source Dijkstra inside `members`: each member goes to the seed group it is
    /// closest to along the graph. `seeds[k]` are the nodes of group k. Group g's edge
    /// lengths (Euclidean) into voxel j count `scale(g, j)` times and its edge from i to j
    /// pays `penalty(g, i, j)` metres more (one that crosses between people rather than
    /// along a body): a group that spreads more cheaply claims more of what lies between
    /// it and the others, and one that pays to cross a boundary (a colour edge) claims less
    /// of what lies beyond it. Returns per member (same order) its group; unreachable
    /// members get the group whose seed is nearest in a straight line.
    pub fn split_scaled(
        &self,
        centers: &[Vec3],
        members: &[u32],
        seeds: &[Vec<u32>],
        scale: impl Fn(usize, u32) -> f32,
        penalty: impl Fn(usize, u32, u32) -> f32,
    ) -> Vec<usize> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let mut local = vec![u32::MAX; self.rows.len()];
        for (k, &i) in members.iter().enumerate() {
            local[i as usize] = k as u32;
        }
        let mut best = vec![(f32::INFINITY, usize::MAX); members.len()];
        let mut heap = BinaryHeap::new();
        for (g, group) in seeds.iter().enumerate() {
            for &i in group {
                let k = local[i as usize] as usize;
                if k < members.len() {
                    best[k] = (0.0, g);
                    heap.push(Reverse((OrdF32(0.0), k, g)));
                }
            }
        }
        let mut next = Vec::new();
        while let Some(Reverse((OrdF32(d), k, g))) = heap.pop() {
            if d > best[k].0 || best[k].1 != g {
                continue;
            }
            let i = members[k] as usize;
            next.clear();
            self.for_neighbors(i, |j, d2| next.push((j, d2)));
            for &(j, d2) in &next {
                let kj = local[j as usize] as usize;
                if kj >= members.len() {
                    continue;
                }
                let nd = d + scale(g, j) * d2.sqrt() + penalty(g, members[k], j);
                if nd < best[kj].0 {
                    best[kj] = (nd, g);
                    heap.push(Reverse((OrdF32(nd), kj, g)));
                }
            }
        }
        best.iter()
            .enumerate()
            .map(|(k, &(_, g))| {
                if g != usize::MAX {
                    return g;
                }
                let p = centers[members[k] as usize];
                let mut nearest = (f32::INFINITY, 0);
                for (g, group) in seeds.iter().enumerate() {
                    for &s in group {
                        let d = dist2(p, centers[s as usize]);
                        if d < nearest.0 {
                            nearest = (d, g);
                        }
                    }
                }
                nearest.1
            })
            .collect()
    }
}

/// A finite f32 with a total order, for the Dijkstra heap.
#[derive(Clone, Copy, Debug, PartialEq)]
struct OrdF32(f32);

impl Eq for OrdF32 {}

impl PartialOrd for OrdF32 {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrdF32 {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_match_brute_force_and_split_follows_the_graph() {
        // Two rows of points 5 cm apart, the rows 30 cm apart: two components at a 10 cm gap.
        let mut pts = Vec::new();
        for i in 0..10 {
            pts.push([i as f32 * 0.05, 0.0, 0.0]);
            pts.push([i as f32 * 0.05, 0.3, 0.0]);
        }
        let g = VoxelGraph::new(&pts, 0.1, &vec![true; pts.len()]);
        let comps = g.components(&vec![true; pts.len()]);
        assert_eq!(comps.len(), 2);
        assert!(comps[0].iter().all(|&i| i % 2 == 0));
        // Brute-force edge count equals the graph's.
        let brute: usize = (0..pts.len())
            .map(|i| {
                (0..pts.len())
                    .filter(|&j| j != i && dist2(pts[i], pts[j]) < 0.01)
                    .count()
            })
            .sum();
        let got: usize = (0..pts.len()).map(|i| g.neighbors(i).len()).sum();
        assert_eq!(got, brute);
        // Grown from point 0 through points left of x = 0.18: the first four of its row.
        let mut grown = g.grow(0, |j| pts[j as usize][0] < 0.18);
        grown.sort_unstable();
        assert_eq!(grown, [0, 2, 4, 6]);
        let seeds = [vec![0], vec![18]];
        let groups = g.split_scaled(&pts, &comps[0], &seeds, |_, _| 1.0, |_, _, _| 0.0);
        assert_eq!(groups[..5], [0; 5]);
        assert_eq!(groups[5..], [1; 5]);
    }

    #[test]
    fn the_graph_among_some_points_is_the_full_graph_restricted_to_them() {
        // A 6 × 6 × 3 lattice 4 cm apart, jittered, every third point left out.
        let mut pts = Vec::new();
        for k in 0..108u32 {
            let (x, y, z) = (k % 6, (k / 6) % 6, k / 36);
            let jitter = (k.wrapping_mul(2_654_435_761) % 1000) as f32 * 1e-5;
            pts.push([
                0.04 * x as f32 + jitter,
                0.04 * y as f32,
                0.04 * z as f32 - jitter,
            ]);
        }
        let among: Vec<bool> = (0..pts.len()).map(|i| i % 3 != 0).collect();
        let full = VoxelGraph::new(&pts, 0.07, &vec![true; pts.len()]);
        let part = VoxelGraph::new(&pts, 0.07, &among);
        for i in 0..pts.len() {
            let want: Vec<u32> = if among[i] {
                let mut n = full.neighbors(i);
                n.retain(|&j| among[j as usize]);
                n
            } else {
                Vec::new()
            };
            assert_eq!(part.neighbors(i), want, "point {i}");
        }
        // Neighbours are found at all (the test can fail): 4 cm apart, 7 cm gap.
        assert!(part.neighbors(1).len() >= 3);
    }

    #[test]
    fn voxels_average_their_points_and_vote_labels() {
        let pts = [
            (0, [0.01, 0.01, 0.01], 1),
            (1, [0.03, 0.03, 0.03], 2),
            (2, [0.02, 0.02, 0.02], 2),
            (3, [0.5, 0.5, 0.5], 6),
        ];
        let v = voxelize(pts.into_iter(), 0.04);
        assert_eq!(v.centers.len(), 2);
        assert_eq!(v.labels, [2, 6]);
        // Centroid of the first three points; tolerance: f32 rounding.
        assert!((v.centers[0][0] - 0.02).abs() < 1e-6);
        assert_eq!(v.point_voxel, [0, 0, 0, 1]);
    }
}
