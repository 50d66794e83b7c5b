//! Cluster features, the cluster graph and the best body tree (ALGORITHM.md §5.2–§5.3).

use crate::dbscan::Clustering;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label};

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
            radius2[c as usize] = radius2[c as usize].max(d2);
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
pub struct Graph {
    /// `containers[a]`: the clusters that cluster `a` lies inside (sorted ids).
    pub containers: Vec<Vec<u32>>,
    /// `adjacent[a]`: clusters joined to `a` by an inside (either way) or intersect edge
    /// (sorted ids).
    pub adjacent: Vec<Vec<u32>>,
}

impl Graph {
    /// True when `a` and `b` are joined by an inside or intersect edge.
    pub fn touches(&self, a: u32, b: u32) -> bool {
        self.adjacent[a as usize].binary_search(&b).is_ok()
    }
}

/// Builds the inside / intersect edges. With `d = ‖c_A − c_B‖`: A is inside B when
/// `d + r_A ≤ r_B · (1 + inside_tolerance)`; A and B intersect when `d ≤ r_A + r_B`.
pub fn build_graph(features: &[ClusterFeatures], inside_tolerance: f32) -> Graph {
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
    Graph {
        containers,
        adjacent,
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
pub fn best_tree_paper(features: &[ClusterFeatures], graph: &Graph) -> BodyTree {
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
