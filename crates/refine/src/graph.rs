//! Cluster features, the cluster graph and the best body tree (ALGORITHM.md §5.2–§5.3).

use crate::dbscan::Clustering;
use crate::grid::{Aabb, CellGrid};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label};
use rustc_hash::{FxHashMap, FxHashSet};

/// Features of one cluster (paper §3.2). Centroid and radius never change; the label may
/// change in M and R, so it is kept outside, in a per-cluster label array.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterFeatures {
    /// The cluster's label after DBSCAN.
    pub label: Label,
    /// Number of points.
    pub size: usize,
    /// Mean of its points, metres, the cloud's frame.
    pub centroid_m: Vec3,
    /// Largest distance from the centroid to one of its points, metres.
    pub radius_m: f32,
}

/// Computes the features of every cluster (index = cluster id).
pub fn cluster_features(positions_m: &[Vec3], clustering: &Clustering) -> Vec<ClusterFeatures> {
    let k = clustering.num_clusters();
    let mut sum = vec![[0f64; 3]; k];
    let mut size = vec![0usize; k];
    for (p, c) in positions_m.iter().zip(&clustering.cluster_of) {
        if let Some(c) = *c {
            let s = &mut sum[c as usize];
            for a in 0..3 {
                s[a] += f64::from(p[a]);
            }
            size[c as usize] += 1;
        }
    }
    let centroid: Vec<Vec3> = sum
        .iter()
        .zip(&size)
        .map(|(s, &n)| {
            let n = n.max(1) as f64;
            [(s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32]
        })
        .collect();
    let mut radius2 = vec![0f32; k];
    for (p, c) in positions_m.iter().zip(&clustering.cluster_of) {
        if let Some(c) = *c {
            let d2 = bodyseg_core::math::dist2(*p, centroid[c as usize]);
            // A select (`maxss`), not `f32::max` (its NaN handling costs five more
            // instructions per point); distances are finite.
            let r2 = &mut radius2[c as usize];
            *r2 = if d2 > *r2 { d2 } else { *r2 };
        }
    }
    (0..k)
        .map(|c| ClusterFeatures {
            label: clustering.cluster_labels[c],
            size: size[c],
            centroid_m: centroid[c],
            radius_m: radius2[c].sqrt(),
        })
        .collect()
}

/// The graph of clusters: *inside* and *intersect* edges from the bounding spheres. Tree
/// edges live in [`BodyTree`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusterGraph {
    /// `containers[a]`: the clusters that cluster `a` lies inside (sorted ids).
    pub containers: Vec<Vec<u32>>,
    /// `adjacent[a]`: clusters joined to `a` by an inside (either way) or intersect edge
    /// (sorted ids).
    pub adjacent: Vec<Vec<u32>>,
}

impl ClusterGraph {
    /// True when `a` and `b` are joined by an inside or intersect edge.
    pub fn touches(&self, a: u32, b: u32) -> bool {
        self.adjacent[a as usize].binary_search(&b).is_ok()
    }
}

/// Builds the inside / intersect edges. With `d = ‖c_A − c_B‖`: A is inside B when
/// `d + r_A ≤ r_B · (1 + inside_tolerance)`; A and B intersect when `d ≤ r_A + r_B`.
pub fn build_graph(features: &[ClusterFeatures], inside_tolerance: f32) -> ClusterGraph {
    let k = features.len();
    let mut containers = vec![Vec::new(); k];
    let mut adjacent = vec![Vec::new(); k];
    for a in 0..k {
        for b in a + 1..k {
            let (fa, fb) = (&features[a], &features[b]);
            let d = bodyseg_core::math::dist(fa.centroid_m, fb.centroid_m);
            let a_in_b = d + fa.radius_m <= fb.radius_m * (1.0 + inside_tolerance);
            let b_in_a = d + fb.radius_m <= fa.radius_m * (1.0 + inside_tolerance);
            if a_in_b {
                containers[a].push(b as u32);
            }
            if b_in_a {
                containers[b].push(a as u32);
            }
            if a_in_b || b_in_a || d <= fa.radius_m + fb.radius_m {
                adjacent[a].push(b as u32);
                adjacent[b].push(a as u32);
            }
        }
    }
    // Pushed in increasing order of the other id already; keep it explicit.
    for v in containers.iter_mut().chain(adjacent.iter_mut()) {
        v.sort_unstable();
    }
    ClusterGraph {
        containers,
        adjacent,
    }
}

/// Builds the inside / intersect edges from actual point gaps (`graph = "contact"`), not
/// from bounding spheres: A and B *touch* (an intersect edge) when some point of A lies
/// within `contact_gap_m` of some point of B; A lies *inside* B when they touch, A has no
/// more points than B, and at least `inside_fraction` of A's points lie within
/// `contact_gap_m` of a point of B. So a cluster whose sphere overlaps the body but whose
/// points stay apart (a blob of the neighbour or of the robot, a hand held in front of the
/// torso) gets no edge, and a cluster immersed in another one — the same surface seen with
/// another label by another camera, which a sphere test misses when the spheres are alike —
/// lies inside it. (`inside_tolerance` is a sphere slack and plays no part here.)
///
/// Clustered points are bucketed in cells of side `contact_gap_m`, per (cell, cluster) with
/// the bounding box of the bucket's points; only buckets of different clusters in
/// neighbouring cells whose boxes come within the gap are compared point by point, and a
/// point stops at its first neighbour within the gap.
pub fn build_graph_contact(
    positions_m: &[Vec3],
    clustering: &Clustering,
    features: &[ClusterFeatures],
    contact_gap_m: f32,
    inside_fraction: f32,
) -> ClusterGraph {
    let index = ContactIndex::new(positions_m, clustering, contact_gap_m);
    let touching = index.touching_pairs();
    let near = index.near_counts(&touching, features, inside_fraction);
    let k = features.len();
    let mut containers = vec![Vec::new(); k];
    let mut adjacent = vec![Vec::new(); k];
    let mut pairs: Vec<(u32, u32)> = touching.into_iter().collect();
    pairs.sort_unstable();
    for (a, b) in pairs {
        adjacent[a as usize].push(b);
        adjacent[b as usize].push(a);
    }
    let mut near: Vec<((u32, u32), usize)> = near.into_iter().collect();
    near.sort_unstable();
    for ((a, b), n) in near {
        if n as f32 >= inside_fraction * features[a as usize].size as f32 {
            containers[a as usize].push(b);
        }
    }
    for v in containers.iter_mut().chain(adjacent.iter_mut()) {
        v.sort_unstable();
    }
    ClusterGraph {
        containers,
        adjacent,
    }
}

/// Clustered points bucketed by (cell of side `gap_m`, cluster), for the contact graph: the
/// crate's grid ([`CellGrid`]) over the clustered points, each cell's points grouped by
/// cluster.
struct ContactIndex {
    gap2: f32,
    /// The clustered points by cell, and within a cell by cluster: buckets are runs of it.
    grid: CellGrid,
    buckets: Vec<Bucket>,
    /// Per cell of the grid, the range of its buckets.
    cell_buckets: Vec<std::ops::Range<usize>>,
}

/// The points of one cluster in one cell, with their bounding box.
struct Bucket {
    cluster: u32,
    range: std::ops::Range<usize>,
    bbox: Aabb,
}

impl ContactIndex {
    fn new(positions_m: &[Vec3], clustering: &Clustering, gap_m: f32) -> Self {
        let inv = 1.0 / gap_m;
        let cell = |p: Vec3| [0, 1, 2].map(|a| (p[a] * inv).floor() as i32);
        // Clustered points ordered by cluster (a counting sort): the grid keeps that
        // order within each cell, so each cell's points come grouped by cluster.
        let k = clustering.num_clusters();
        let mut start = vec![0u32; k + 1];
        for c in clustering.cluster_of.iter().flatten() {
            start[*c as usize + 1] += 1;
        }
        for c in 0..k {
            start[c + 1] += start[c];
        }
        let mut ids = vec![0u32; start[k] as usize];
        for (i, c) in clustering.cluster_of.iter().enumerate() {
            if let Some(c) = c {
                let s = &mut start[*c as usize];
                ids[*s as usize] = i as u32;
                *s += 1;
            }
        }
        let keys: Vec<[i32; 3]> = ids.iter().map(|&i| cell(positions_m[i as usize])).collect();
        let grid = CellGrid::new(positions_m, &ids, &keys, 1);
        let mut buckets: Vec<Bucket> = Vec::new();
        let mut cell_buckets = Vec::with_capacity(grid.num_cells());
        for c in 0..grid.num_cells() as u32 {
            let first = buckets.len();
            let r = grid.range(c);
            let mut i = r.start;
            while i < r.end {
                let cluster = clustering.cluster_of[grid.ids()[i] as usize].unwrap_or(u32::MAX);
                let mut j = i;
                while j < r.end && clustering.cluster_of[grid.ids()[j] as usize] == Some(cluster) {
                    j += 1;
                }
                buckets.push(Bucket {
                    cluster,
                    range: i..j,
                    bbox: Aabb::of(&grid.pts()[i..j]),
                });
                i = j;
            }
            cell_buckets.push(first..buckets.len());
        }
        ContactIndex {
            gap2: gap_m * gap_m,
            grid,
            buckets,
            cell_buckets,
        }
    }

    /// Calls `f(a, b)` for every pair of buckets of different clusters in neighbouring
    /// cells (the same cell included) whose boxes come within the gap, each ordered pair
    /// once.
    fn for_each_near_bucket_pair(&self, mut f: impl FnMut(usize, usize)) {
        let around: Vec<[i32; 3]> = (-1..=1)
            .flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| [x, y, z])))
            .collect();
        let offs = self.grid.offsets(&around);
        for c in 0..self.grid.num_cells() as u32 {
            let at = self.grid.anchor(c);
            let own = self.cell_buckets[c as usize].clone();
            for o in 0..around.len() {
                let Some(d) = self.grid.near_cell(at, &offs, o) else {
                    continue;
                };
                for ai in own.clone() {
                    for bi in self.cell_buckets[d as usize].clone() {
                        let (a, b) = (&self.buckets[ai], &self.buckets[bi]);
                        if a.cluster != b.cluster && a.bbox.gap2(&b.bbox) <= self.gap2 {
                            f(ai, bi);
                        }
                    }
                }
            }
        }
    }

    /// True when a point of bucket `b` lies within the gap of `p`.
    fn near(&self, p: Vec3, b: &Bucket) -> bool {
        b.bbox.dist2(p) <= self.gap2
            && self.grid.pts()[b.range.clone()]
                .iter()
                .any(|&q| bodyseg_core::math::dist2(p, q) <= self.gap2)
    }

    /// The pairs `(a, b)`, `a < b`, of clusters with two points within the gap.
    fn touching_pairs(&self) -> FxHashSet<(u32, u32)> {
        let mut touching = FxHashSet::default();
        self.for_each_near_bucket_pair(|ai, bi| {
            let (a, b) = (&self.buckets[ai], &self.buckets[bi]);
            if a.cluster < b.cluster && !touching.contains(&(a.cluster, b.cluster)) {
                let hit = self.grid.pts()[a.range.clone()]
                    .iter()
                    .any(|&p| self.near(p, b));
                if hit {
                    touching.insert((a.cluster, b.cluster));
                }
            }
        });
        touching
    }

    /// For touching clusters `a`, `b` with `a` no larger than `b` and possibly immersed in
    /// it: how many points of `a` have a point of `b` within the gap, keyed `(a, b)`. A
    /// pair whose buckets near each other hold fewer than `fraction` of `a`'s points cannot
    /// reach it and is skipped before any point is compared (most touching pairs: parts
    /// that meet along a seam).
    fn near_counts(
        &self,
        touching: &FxHashSet<(u32, u32)>,
        features: &[ClusterFeatures],
        fraction: f32,
    ) -> FxHashMap<(u32, u32), usize> {
        let candidate = |ai: usize, bi: usize| -> Option<(u32, u32)> {
            let (a, b) = (self.buckets[ai].cluster, self.buckets[bi].cluster);
            let key = (a.min(b), a.max(b));
            (features[a as usize].size <= features[b as usize].size && touching.contains(&key))
                .then_some((a, b))
        };
        // Bound: the points of a's buckets near some bucket of b.
        let mut near_buckets: FxHashSet<(usize, u32)> = FxHashSet::default();
        self.for_each_near_bucket_pair(|ai, bi| {
            if let Some((_, b)) = candidate(ai, bi) {
                near_buckets.insert((ai, b));
            }
        });
        let mut bound: FxHashMap<(u32, u32), usize> = FxHashMap::default();
        for &(ai, b) in &near_buckets {
            *bound.entry((self.buckets[ai].cluster, b)).or_default() +=
                self.buckets[ai].range.len();
        }
        bound.retain(|&(a, _), n| *n as f32 >= fraction * features[a as usize].size as f32);
        // Per bucket of `a`: which of its points are near cluster `b`, over all of `b`'s
        // buckets (a point near two of them counts once).
        let mut flags: FxHashMap<(usize, u32), Vec<bool>> = FxHashMap::default();
        self.for_each_near_bucket_pair(|ai, bi| {
            let Some(pair) = candidate(ai, bi) else {
                return;
            };
            if !bound.contains_key(&pair) {
                return;
            }
            let a = &self.buckets[ai];
            let f = flags
                .entry((ai, pair.1))
                .or_insert_with(|| vec![false; a.range.len()]);
            for (flag, &p) in f.iter_mut().zip(&self.grid.pts()[a.range.clone()]) {
                if !*flag && self.near(p, &self.buckets[bi]) {
                    *flag = true;
                }
            }
        });
        let mut counts: FxHashMap<(u32, u32), usize> = FxHashMap::default();
        for ((ai, b), f) in flags {
            let a = self.buckets[ai].cluster;
            *counts.entry((a, b)).or_default() += f.iter().filter(|&&x| x).count();
        }
        counts
    }
}

/// A slot of the body template: its class, and the slot it hangs from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    /// The class a cluster must have to fill it.
    pub class: Class,
    /// Index of the parent slot in [`TEMPLATE`] (`None` for children of the root).
    pub parent: Option<usize>,
}

/// The Pascal-Person-Part body template below the torso root, in breadth-first order:
/// head, two upper arms, two upper legs on the torso; a lower arm on each upper arm and a
/// lower leg on each upper leg (Grapy-ML's `pascal_graph`).
pub const TEMPLATE: [Slot; 9] = [
    Slot {
        class: Class::Head,
        parent: None,
    },
    Slot {
        class: Class::UpperArms,
        parent: None,
    },
    Slot {
        class: Class::UpperArms,
        parent: None,
    },
    Slot {
        class: Class::UpperLegs,
        parent: None,
    },
    Slot {
        class: Class::UpperLegs,
        parent: None,
    },
    Slot {
        class: Class::LowerArms,
        parent: Some(1),
    },
    Slot {
        class: Class::LowerArms,
        parent: Some(2),
    },
    Slot {
        class: Class::LowerLegs,
        parent: Some(3),
    },
    Slot {
        class: Class::LowerLegs,
        parent: Some(4),
    },
];

/// The best body tree: the root torso cluster and the cluster filling each template slot.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BodyTree {
    /// The root (a torso cluster), if any.
    pub root: Option<u32>,
    /// Per slot of [`TEMPLATE`], the cluster filling it.
    pub slots: [Option<u32>; 9],
}

impl BodyTree {
    /// A tree is valid when its root exists and at least one slot is filled.
    pub fn is_valid(&self) -> bool {
        self.root.is_some() && self.slots.iter().any(Option::is_some)
    }

    /// The tree's nodes: root and filled slots.
    pub fn nodes(&self) -> impl Iterator<Item = u32> + '_ {
        self.root
            .into_iter()
            .chain(self.slots.iter().flatten().copied())
    }

    /// True when `c` is a node of the tree.
    pub fn contains(&self, c: u32) -> bool {
        self.nodes().any(|n| n == c)
    }

    /// The tree edges as (parent, child) cluster pairs.
    pub fn edges(&self) -> Vec<(u32, u32)> {
        let Some(root) = self.root else {
            return Vec::new();
        };
        TEMPLATE
            .iter()
            .zip(&self.slots)
            .filter_map(|(slot, filled)| {
                let child = (*filled)?;
                let parent = match slot.parent {
                    None => root,
                    Some(p) => self.slots[p]?,
                };
                Some((parent, child))
            })
            .collect()
    }
}

/// The paper's best tree: root = the largest torso cluster; slots filled breadth-first, each
/// with the largest unused cluster of its label adjacent (intersecting, inside or
/// containing) to its parent; ties go to the smaller cluster id. A slot whose parent slot
/// is empty stays empty.
pub fn best_tree_paper(features: &[ClusterFeatures], graph: &ClusterGraph) -> BodyTree {
    let largest = |cands: &mut dyn Iterator<Item = u32>| -> Option<u32> {
        cands.fold(None, |best: Option<u32>, c| match best {
            Some(b) if features[b as usize].size >= features[c as usize].size => Some(b),
            _ => Some(c),
        })
    };
    let torso = Label::from(Class::Torso);
    let root =
        largest(&mut (0..features.len() as u32).filter(|&c| features[c as usize].label == torso));
    let mut tree = BodyTree {
        root,
        slots: [None; 9],
    };
    let Some(root) = root else {
        return tree;
    };
    let mut used = vec![false; features.len()];
    used[root as usize] = true;
    for (s, slot) in TEMPLATE.iter().enumerate() {
        let parent = match slot.parent {
            None => Some(root),
            Some(p) => tree.slots[p],
        };
        let Some(parent) = parent else { continue };
        let want = Label::from(slot.class);
        let pick = largest(
            &mut graph.adjacent[parent as usize]
                .iter()
                .copied()
                .filter(|&c| !used[c as usize] && features[c as usize].label == want),
        );
        if let Some(c) = pick {
            used[c as usize] = true;
            tree.slots[s] = Some(c);
        }
    }
    tree
}

/// The best tree covering the most points (`tree = "coverage"`): every torso cluster is
/// tried as the root; for each, the head slot takes the largest adjacent head cluster and
/// the two arm chains (upper arm adjacent to the root, lower arm adjacent to that upper
/// arm) are chosen together — likewise the legs — so that the tree's nodes hold the most
/// points. Slot order and template are [`TEMPLATE`]'s; a lower slot is filled only under a
/// filled upper slot, as in the paper. Ties go to the first found in increasing ids.
///
/// Greedy slot filling ([`best_tree_paper`]) gives an upper-arm slot to the largest
/// upper-arm cluster even when it carries no lower arm (a mislabelled patch on the torso),
/// leaving a real arm and its forearm out of the tree; this search does not.
pub fn best_tree_coverage(features: &[ClusterFeatures], graph: &ClusterGraph) -> BodyTree {
    let size = |c: u32| features[c as usize].size;
    let with_label = |cands: &[u32], class: Class| -> Vec<u32> {
        let want = Label::from(class);
        cands
            .iter()
            .copied()
            .filter(|&c| features[c as usize].label == want)
            .collect()
    };
    let torso = Label::from(Class::Torso);
    let mut best: Option<(usize, BodyTree)> = None;
    for root in (0..features.len() as u32).filter(|&c| features[c as usize].label == torso) {
        let adjacent = &graph.adjacent[root as usize];
        let mut tree = BodyTree {
            root: Some(root),
            slots: [None; 9],
        };
        let mut total = size(root);
        // Head: the largest adjacent head cluster (ties: smaller id).
        let head = with_label(adjacent, Class::Head)
            .into_iter()
            .fold(None, |b: Option<u32>, c| match b {
                Some(b) if size(b) >= size(c) => Some(b),
                _ => Some(c),
            });
        if let Some(h) = head {
            tree.slots[0] = Some(h);
            total += size(h);
        }
        for (upper, lower, slots) in [
            (Class::UpperArms, Class::LowerArms, [1, 2, 5, 6]),
            (Class::UpperLegs, Class::LowerLegs, [3, 4, 7, 8]),
        ] {
            let uppers = with_label(adjacent, upper);
            let lowers: Vec<Vec<u32>> = uppers
                .iter()
                .map(|&u| with_label(&graph.adjacent[u as usize], lower))
                .collect();
            let (points, pick) = best_limb_pair(&uppers, &lowers, &size);
            total += points;
            for (slot, c) in slots.into_iter().zip(pick) {
                tree.slots[slot] = c;
            }
        }
        if best.as_ref().is_none_or(|(t, _)| total > *t) {
            best = Some((total, tree));
        }
    }
    best.map(|(_, t)| t).unwrap_or_default()
}

/// Two limb chains (upper, optional lower under it) with distinct clusters covering the
/// most points: `[upper 1, upper 2, lower 1, lower 2]` and their points. `lowers[i]` are
/// the lower clusters adjacent to `uppers[i]`.
fn best_limb_pair(
    uppers: &[u32],
    lowers: &[Vec<u32>],
    size: &dyn Fn(u32) -> usize,
) -> (usize, [Option<u32>; 4]) {
    // Chains: (upper index or none, lower or none).
    let mut chains: Vec<(Option<usize>, Option<u32>)> = vec![(None, None)];
    for (i, ls) in lowers.iter().enumerate() {
        chains.push((Some(i), None));
        chains.extend(ls.iter().map(|&l| (Some(i), Some(l))));
    }
    let points =
        |(u, l): (Option<usize>, Option<u32>)| u.map_or(0, |u| size(uppers[u])) + l.map_or(0, size);
    let mut best = (0, [None; 4]);
    for (x, &a) in chains.iter().enumerate() {
        for &b in &chains[x..] {
            let same_upper = a.0.is_some() && a.0 == b.0;
            let same_lower = a.1.is_some() && a.1 == b.1;
            if same_upper || same_lower {
                continue;
            }
            let total = points(a) + points(b);
            if total > best.0 {
                // A filled chain goes in the first slot.
                let (a, b) = if a.0.is_none() { (b, a) } else { (a, b) };
                best = (
                    total,
                    [a.0.map(|u| uppers[u]), b.0.map(|u| uppers[u]), a.1, b.1],
                );
            }
        }
    }
    best
}
