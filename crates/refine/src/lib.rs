//! bodyseg-refine: the clustering refinement of body-part labels (the paper's Algorithm 1,
//! ALGORITHM.md §5).
//!
//! Place in the pipeline: `LabeledCloud` (projected labels) + `PersonBox`es →
//! [`refine`] → `RefinedCloud` (same points, same order, repaired labels).
//!
//! Per person box, in parallel: label-aware DBSCAN ([`dbscan`], Ester et al. 1996),
//! cluster features and graph ([`graph`]), the best body tree, then the steps
//! ([`steps`]): M merges clusters lying inside a cluster of another label, R removes
//! clusters cut off from the body tree, N gives noise points the label of the nearest
//! clustered point. [`fuse`] puts the people back into the whole cloud.
//!
//! # Conventions
//! - Positions in metres, any right-handed frame (the world frame in the pipeline).
//! - Cluster ids are dense, ordered by each cluster's smallest point index (within the
//!   person's point list, which keeps the cloud's order).
//! - Nothing here depends on point order beyond that numbering: ties are broken by index.

pub mod config;
pub mod dbscan;
pub mod graph;
pub mod steps;

pub use config::{RefineConfig, RefineError, Steps, TreeMode};
pub use dbscan::{Clustering, DbscanParams, dbscan, dbscan_brute_force};
pub use graph::{BodyTree, ClusterFeatures, Graph, best_tree_paper, build_graph, cluster_features};
pub use steps::{merge_nodes, reassign_noise, remove_nodes};

use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabeledCloud, PersonBox, RefinedCloud};
use rayon::prelude::*;

/// Everything the refinement computed for one person, for tests, figures and reports.
#[derive(Clone, Debug)]
pub struct PersonRefinement {
    /// DBSCAN's result on the person's points.
    pub clustering: Clustering,
    /// Per cluster features.
    pub features: Vec<ClusterFeatures>,
    /// The cluster graph.
    pub graph: Graph,
    /// The best body tree.
    pub tree: BodyTree,
    /// Cluster labels after M (equal to DBSCAN's when M is off).
    pub labels_after_merge: Vec<Label>,
    /// Cluster labels after R (equal to the above when R is off or the tree is invalid).
    pub labels_after_remove: Vec<Label>,
    /// Final per-point labels of the person's points (never unknown).
    pub point_labels: Vec<Label>,
}

impl PersonRefinement {
    /// Clusters whose label M changed.
    pub fn merged(&self) -> usize {
        self.features
            .iter()
            .zip(&self.labels_after_merge)
            .filter(|(f, l)| f.label != **l)
            .count()
    }

    /// Clusters R turned into background.
    pub fn removed(&self) -> usize {
        self.labels_after_merge
            .iter()
            .zip(&self.labels_after_remove)
            .filter(|(a, b)| a != b)
            .count()
    }
}

/// Refines one person's points (Algorithm 1's loop body). `steps` must not be
/// `Reference`, which does no per-person work; it is treated as `none`.
pub fn refine_person(
    positions_m: &[Vec3],
    labels: &[Label],
    cfg: &RefineConfig,
) -> PersonRefinement {
    let (merge, remove, noise) = match cfg.steps {
        Steps::Reference => (false, false, false),
        Steps::Run {
            merge,
            remove,
            noise,
        } => (merge, remove, noise),
    };
    let clustering = dbscan(positions_m, labels, &cfg.dbscan_params());
    let features = cluster_features(positions_m, &clustering);
    let graph = build_graph(&features, cfg.inside_tolerance);
    let tree = match cfg.tree {
        TreeMode::Paper => best_tree_paper(&features, &graph),
    };
    let initial: Vec<Label> = features.iter().map(|f| f.label).collect();
    let labels_after_merge = if merge {
        merge_nodes(
            &features,
            &initial,
            &graph,
            &tree,
            cfg.merge_into_background,
        )
    } else {
        initial
    };
    let labels_after_remove = if remove {
        remove_nodes(&labels_after_merge, &graph, &tree)
    } else {
        labels_after_merge.clone()
    };
    // Apply cluster labels to their points; noise keeps its own label for now.
    let mut point_labels: Vec<Label> = clustering
        .cluster_of
        .iter()
        .zip(labels)
        .map(|(c, &l)| c.map_or(l, |c| labels_after_remove[c as usize]))
        .collect();
    if noise {
        let is_noise: Vec<bool> = clustering.cluster_of.iter().map(Option::is_none).collect();
        point_labels = reassign_noise(positions_m, &point_labels, &is_noise, cfg.eps_m);
    }
    // Nothing leaves refinement unknown: an unknown point nobody relabelled is background.
    for l in &mut point_labels {
        if l.is_unknown() {
            *l = Label::BACKGROUND;
        }
    }
    PersonRefinement {
        clustering,
        features,
        graph,
        tree,
        labels_after_merge,
        labels_after_remove,
        point_labels,
    }
}

/// Runs the refinement on a whole cloud: every person box independently (in parallel),
/// then the fuse (§5.7). `Steps::Reference` returns the cloud untouched.
///
/// The output holds the input's points in the input's order; only labels change.
pub fn refine(
    cloud: &LabeledCloud,
    boxes: &[PersonBox],
    cfg: &RefineConfig,
) -> Result<RefinedCloud, RefineError> {
    cfg.validate()?;
    cloud.validate()?;
    if let Some(reason) = boxes.iter().find_map(PersonBox::invalid_reason) {
        return Err(RefineError::InvalidBox { reason });
    }
    if cfg.steps == Steps::Reference {
        return Ok(RefinedCloud {
            cloud: cloud.clone(),
            clusters: vec![None; cloud.len()],
        });
    }
    let people: Vec<(Vec<u32>, PersonRefinement)> = boxes
        .par_iter()
        .map(|b| {
            let test = b.test();
            let idx: Vec<u32> = (0..cloud.len() as u32)
                .filter(|&i| test.contains(cloud.positions_m[i as usize]))
                .collect();
            // A box holding the whole cloud (a cloud cropped to one person) needs no copy.
            let r = if idx.len() == cloud.len() {
                refine_person(&cloud.positions_m, &cloud.labels, cfg)
            } else {
                let pos: Vec<Vec3> = idx.iter().map(|&i| cloud.positions_m[i as usize]).collect();
                let lab: Vec<Label> = idx.iter().map(|&i| cloud.labels[i as usize]).collect();
                refine_person(&pos, &lab, cfg)
            };
            tracing::debug!(
                person = b.id,
                points = idx.len(),
                clusters = r.features.len(),
                noise = r.clustering.num_noise(),
                tree_valid = r.tree.is_valid(),
                merged = r.merged(),
                removed = r.removed(),
                "refined person"
            );
            (idx, r)
        })
        .collect();
    Ok(fuse(cloud, boxes, &people, cfg.keep_outside_boxes))
}

/// Fuse (§5.7): a point inside exactly one box takes that person's label; inside several,
/// their common label if they agree, else its original label (the paper) — or, when the
/// original is unknown, the label given by the box whose centre is nearest horizontally.
/// A body-labelled (or unknown) point outside every box becomes background unless
/// `keep_outside_boxes` (then unknown still becomes background).
pub fn fuse(
    cloud: &LabeledCloud,
    boxes: &[PersonBox],
    people: &[(Vec<u32>, PersonRefinement)],
    keep_outside_boxes: bool,
) -> RefinedCloud {
    let n = cloud.len();
    // Per point: the labels given by the people whose box holds it, as (person, label).
    let mut first: Vec<Option<(u32, Label)>> = vec![None; n];
    let mut disagree = vec![false; n];
    let mut clusters = vec![None; n];
    for (p, (idx, r)) in people.iter().enumerate() {
        for (k, &i) in idx.iter().enumerate() {
            let i = i as usize;
            let l = r.point_labels[k];
            match first[i] {
                None => {
                    first[i] = Some((p as u32, l));
                    clusters[i] = r
                        .clustering
                        .cluster_of
                        .get(k)
                        .copied()
                        .flatten()
                        .map(|c| (p as u32, c));
                }
                Some((_, l0)) if l0 != l => disagree[i] = true,
                Some(_) => {}
            }
        }
    }
    let labels = (0..n)
        .map(|i| {
            let original = cloud.labels[i];
            match first[i] {
                None if keep_outside_boxes && !original.is_unknown() => original,
                None if original.is_body() || original.is_unknown() => Label::BACKGROUND,
                None => original,
                Some((_, l)) if !disagree[i] => l,
                Some(_) if !original.is_unknown() => original,
                Some(_) => nearest_box_label(cloud.positions_m[i], i as u32, boxes, people),
            }
        })
        .collect();
    RefinedCloud {
        cloud: cloud.with_labels(labels),
        clusters,
    }
}

/// The label that the person whose box centre is nearest (horizontally) gave point `i`.
fn nearest_box_label(
    p: Vec3,
    i: u32,
    boxes: &[PersonBox],
    people: &[(Vec<u32>, PersonRefinement)],
) -> Label {
    let mut best: Option<(f32, Label)> = None;
    for (b, (idx, r)) in boxes.iter().zip(people) {
        if let Ok(k) = idx.binary_search(&i) {
            let dx = p[0] - b.center_m[0];
            let dy = p[1] - b.center_m[1];
            let d2 = dx * dx + dy * dy;
            if best.is_none_or(|(b2, _)| d2 < b2) {
                best = Some((d2, r.point_labels[k]));
            }
        }
    }
    best.map_or(Label::BACKGROUND, |(_, l)| l)
}
