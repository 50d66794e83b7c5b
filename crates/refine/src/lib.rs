//! bodyseg-refine: the clustering refinement of body-part labels (the paper's Algorithm 1,
//! ALGORITHM.md §5).
//!
//! Place in the pipeline: `LabeledCloud` (projected labels) + `PersonBox`es →
//! [`refine`] → `RefinedCloud` (same points, same order, repaired labels).
//!
//! Per person box, in parallel: label-aware DBSCAN ([`dbscan()`], Ester et al. 1996),
//! cluster features and graph ([`graph`]), the best body tree, then the steps
//! ([`steps`]): M merges clusters lying inside a cluster of another label, R removes
//! clusters cut off from the body tree, N gives noise points the label of the nearest
//! clustered point. [`fuse`] puts the people back into the whole cloud.
//!
//! Beside the paper's reading, each selectable in [`RefineConfig`] (defaults = the paper):
//! `graph = "contact"` measures adjacency and containment on actual point gaps
//! ([`build_graph_contact`]) instead of bounding spheres; `tree = "coverage"` searches the
//! valid body tree covering the most points ([`best_tree_coverage`]) instead of filling
//! slots greedily; `noise = "weighted"` relabels noise by a distance-weighted vote of its
//! nearest clustered points and its own label ([`reassign_noise_weighted`]), and `noise =
//! "probability"` weighs that own label by the parser's probability of it
//! ([`PointEvidence::label_probs`]). After the steps, `floor_contact_m` gives lower-leg
//! points on the floor back to the background ([`floor`]), `smooth_radius_m` gives each
//! body point the body label most points around it carry ([`smooth_labels`]), and
//! `foreign_color_density` arm labels on colors the person does not wear ([`color`]).
//!
//! Every spatial search (DBSCAN's neighbour counts, N's nearest clustered point and votes,
//! smoothing's cell counts, R's bridges, the contact graph) runs on one grid (`grid.rs`:
//! cells keyed without overflow for any finite input, dense or hashed look-up, tested
//! against brute force). Lengths that set a grid's cells are checked against the cloud's
//! extent ([`RefineConfig::validate_for_extent`]).
//!
//! # Conventions
//! - Positions in metres, any right-handed frame (the world frame in the pipeline).
//! - Cluster ids are dense, ordered by each cluster's smallest point index (within the
//!   person's point list, which keeps the cloud's order).
//! - Nothing here depends on point order beyond that numbering: ties are broken by index.

pub mod color;
pub mod config;
pub mod dbscan;
pub mod floor;
pub mod graph;
mod grid;
pub mod steps;

pub use config::{
    GraphMode, MAX_COUNT, MAX_NOISE_K, MAX_RADIUS_M, NoiseMode, RefineConfig, RefineError, Steps,
    TreeMode, VoteMode,
};
pub use dbscan::{Clustering, DbscanParams, dbscan, dbscan_brute_force};
pub use graph::{
    BodyTree, ClusterFeatures, ClusterGraph, best_tree_coverage, best_tree_paper, build_graph,
    build_graph_contact, cluster_features,
};
pub use steps::{
    Vote, doubtful_as_unknown, merge_nodes, reassign_doubted_wide, reassign_noise,
    reassign_noise_weighted, remove_nodes, restore_bridged, smooth_labels,
};

use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabeledCloud, PersonBox, RefinedCloud};
use rayon::prelude::*;
use steps::NoiseNearest;

/// Everything the refinement computed for one person, for tests, figures and reports.
#[derive(Clone, Debug)]
pub struct PersonRefinement {
    /// DBSCAN's result on the person's points.
    pub clustering: Clustering,
    /// Per cluster features.
    pub features: Vec<ClusterFeatures>,
    /// The cluster graph.
    pub graph: ClusterGraph,
    /// The best body tree.
    pub tree: BodyTree,
    /// Cluster labels after M (equal to DBSCAN's when M is off).
    pub labels_after_merge: Vec<Label>,
    /// Cluster labels after R (equal to the above when R is off or the tree is invalid).
    pub labels_after_remove: Vec<Label>,
    /// Final per-point labels of the person's points: never unknown, except where
    /// `foreign_color_density` found an arm label of a color this person does not wear
    /// (it abstains: the fuse gives the point another person's label, or background).
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

/// What the refinement computes for one person whatever the steps: DBSCAN's clusters,
/// their features and graph, and the best body tree. The steps ([`apply_steps`]) only
/// relabel clusters and noise, so the paper's five configurations share one of these.
#[derive(Clone, Debug)]
pub struct PersonStructure {
    /// DBSCAN's result on the person's points.
    pub clustering: Clustering,
    /// Per cluster features.
    pub features: Vec<ClusterFeatures>,
    /// The cluster graph.
    pub graph: ClusterGraph,
    /// The best body tree.
    pub tree: BodyTree,
}

/// Clusters one person's points and finds the body tree (Algorithm 1's first half).
pub fn analyse_person(
    positions_m: &[Vec3],
    labels: &[Label],
    cfg: &RefineConfig,
) -> PersonStructure {
    analyse_person_with(positions_m, labels, cfg, false).0
}

/// [`analyse_person`], and with `want_cells` the index of the clustered points that N's
/// nearest search takes ([`dbscan::dbscan_with_cells`]).
fn analyse_person_with(
    positions_m: &[Vec3],
    labels: &[Label],
    cfg: &RefineConfig,
    want_cells: bool,
) -> (PersonStructure, Option<dbscan::ClusteredCells>) {
    let (clustering, cells) =
        dbscan::dbscan_with_cells(positions_m, labels, &cfg.dbscan_params(), want_cells);
    let features = cluster_features(positions_m, &clustering);
    let graph = match cfg.graph {
        GraphMode::Spheres => build_graph(&features, cfg.inside_tolerance),
        GraphMode::Contact => build_graph_contact(
            positions_m,
            &clustering,
            &features,
            cfg.contact_gap_m,
            cfg.contact_inside_fraction,
        ),
    };
    let tree = match cfg.tree {
        TreeMode::Paper => best_tree_paper(&features, &graph),
        TreeMode::Coverage => best_tree_coverage(&features, &graph),
    };
    (
        PersonStructure {
            clustering,
            features,
            graph,
            tree,
        },
        cells,
    )
}

/// Runs `steps` on a person's [`PersonStructure`] (Algorithm 1's second half). `Reference`
/// is treated as no step (it does no per-person work; see [`refine`]).
///
/// `label_probs`: the parser's probability of each point's label in `labels` (one per
/// point), used by `noise = "probability"` only; `None` counts every label as sure.
pub fn apply_steps(
    structure: PersonStructure,
    positions_m: &[Vec3],
    labels: &[Label],
    label_probs: Option<&[f32]>,
    doubted: Option<&[bool]>,
    steps: Steps,
    cfg: &RefineConfig,
) -> PersonRefinement {
    let evidence = PersonEvidence {
        label_probs,
        doubted,
        nearest: None,
    };
    apply_steps_with(structure, positions_m, labels, evidence, steps, cfg)
}

/// What [`apply_steps`] may be given beside the structure: the parser's evidence, and N's
/// search when it was done already for another configuration of the same clustering.
#[derive(Clone, Copy, Default)]
struct PersonEvidence<'a> {
    label_probs: Option<&'a [f32]>,
    doubted: Option<&'a [bool]>,
    nearest: Option<&'a NoiseNearest>,
}

/// [`apply_steps`] with a [`PersonEvidence`].
fn apply_steps_with(
    structure: PersonStructure,
    positions_m: &[Vec3],
    labels: &[Label],
    evidence: PersonEvidence<'_>,
    steps: Steps,
    cfg: &RefineConfig,
) -> PersonRefinement {
    let PersonEvidence {
        label_probs,
        doubted,
        nearest,
    } = evidence;
    let (merge, remove, noise) = match steps {
        Steps::Reference => (false, false, false),
        Steps::Run {
            merge,
            remove,
            noise,
        } => (merge, remove, noise),
    };
    let PersonStructure {
        clustering,
        features,
        graph,
        tree,
    } = structure;
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
        let removed = remove_nodes(&labels_after_merge, &graph, &tree);
        if cfg.remove_through_noise {
            restore_bridged(
                &removed,
                &labels_after_merge,
                positions_m,
                &clustering.cluster_of,
                labels,
                &tree,
                cfg.eps_m,
            )
        } else {
            removed
        }
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
        // The noise flags, for the searches and votes below; N's shared search (the
        // paper's nearest rule with `nearest` given) does without.
        let is_noise: Vec<bool> = if cfg.noise == NoiseMode::Nearest && nearest.is_some() {
            Vec::new()
        } else {
            clustering.cluster_of.iter().map(Option::is_none).collect()
        };
        // The labels the parser doubted: a wider vote (see `reassign_doubted_wide`), from
        // the clustered labels as they are before N.
        let wide = doubted
            .filter(|_| cfg.noise == NoiseMode::Probability && cfg.noise_doubt_radius_m > 0.0)
            .map(|doubted| {
                let labels = reassign_doubted_wide(
                    positions_m,
                    &point_labels,
                    &is_noise,
                    doubted,
                    label_probs,
                    Vote {
                        k: cfg.noise_doubt_k,
                        radius_m: cfg.noise_doubt_radius_m,
                        self_weight: cfg.noise_self_weight,
                    },
                );
                (doubted, labels)
            });
        // The narrow vote is not asked for the points the wide one relabels.
        let narrow: Option<Vec<bool>> = wide
            .as_ref()
            .map(|(doubted, _)| doubted.iter().map(|&d| !d).collect());
        point_labels = match cfg.noise {
            NoiseMode::Nearest => match nearest {
                Some(n) => n.relabel(&point_labels),
                None => reassign_noise(positions_m, &point_labels, &is_noise, cfg.eps_m),
            },
            NoiseMode::Weighted | NoiseMode::Probability => reassign_noise_weighted(
                positions_m,
                &point_labels,
                &is_noise,
                narrow.as_deref(),
                // Noise points keep their starting label until here, so `label_probs[i]`
                // is the probability of the label that votes.
                label_probs.filter(|_| cfg.noise == NoiseMode::Probability),
                Vote {
                    k: cfg.noise_k,
                    radius_m: cfg.eps_m,
                    self_weight: cfg.noise_self_weight,
                },
            ),
        };
        if let Some((doubted, wide)) = wide {
            for ((l, w), &d) in point_labels.iter_mut().zip(wide).zip(doubted) {
                if d {
                    *l = w;
                }
            }
        }
    }
    if cfg.floor_contact_m > 0.0 {
        point_labels = floor::floor_contact(positions_m, &point_labels, cfg.floor_contact_m);
    }
    if cfg.smooth_radius_m > 0.0 {
        point_labels = smooth_labels(positions_m, &point_labels, cfg.smooth_radius_m);
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

/// Refines one person's points (Algorithm 1's loop body) with `cfg.steps`, which must
/// not be `Reference` (it does no per-person work; it is treated as no step).
pub fn refine_person(
    positions_m: &[Vec3],
    labels: &[Label],
    cfg: &RefineConfig,
) -> PersonRefinement {
    let structure = analyse_person(positions_m, labels, cfg);
    apply_steps(structure, positions_m, labels, None, None, cfg.steps, cfg)
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
    let mut out = refine_variants(cloud, boxes, cfg, &[cfg.steps], true)?;
    // One configuration asked, one returned.
    let labels = out.labels.swap_remove(0);
    Ok(RefinedCloud {
        cloud: cloud.with_labels(labels),
        clusters: if cfg.steps == Steps::Reference {
            vec![None; cloud.len()]
        } else {
            out.clusters
        },
    })
}

/// The refinement of one cloud under several step configurations ([`refine_variants`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinedVariants {
    /// Per configuration, in the order asked: the refined label of every point (the
    /// cloud's order).
    pub labels: Vec<Vec<Label>>,
    /// Per point, `(person index, cluster id)` as in [`RefinedCloud::clusters`]: the same
    /// for every configuration (they share the clustering); all `None` when only
    /// `Reference` was asked; empty when not asked for (`with_clusters` false).
    pub clusters: Vec<Option<(u32, u32)>>,
}

/// [`refine`] once per entry of `steps` (e.g. [`Steps::PAPER`], the paper's ablation), in
/// that order, with `cfg`'s other settings, returning labels only (no copy of the
/// points). Each person is clustered once ([`analyse_person`]) and every configuration
/// derived from that clustering, so the five configurations cost little more than one;
/// each label list equals what [`refine`] gives with `cfg.steps` set to that entry.
/// The clusters of every point (12 bytes each) are listed only `with_clusters` (a
/// figure draws them; a plain run does not need them).
///
/// With `cfg.vote = multi_view` this is an error (no vote labels): see
/// [`refine_variants_with`].
pub fn refine_variants(
    cloud: &LabeledCloud,
    boxes: &[PersonBox],
    cfg: &RefineConfig,
    steps: &[Steps],
    with_clusters: bool,
) -> Result<RefinedVariants, RefineError> {
    refine_variants_with(
        cloud,
        PointEvidence::default(),
        boxes,
        cfg,
        steps,
        with_clusters,
    )
}

/// What the projection knows of each point beyond its label, one entry per point of the
/// cloud; only `bodyseg run` / `convert`, which have the images, can give it.
#[derive(Clone, Copy, Debug, Default)]
pub struct PointEvidence<'a> {
    /// The labels of the projection's multi-view vote
    /// (`bodyseg_project::FrameProjector::vote_labels`); needed by `vote = multi_view`.
    pub voted: Option<&'a [Label]>,
    /// The parser's probability of each point's projected label (the softmax of that
    /// label at the point's color pixel); used by `noise = "probability"`. Where the
    /// vote changed a label, its probability is not the new label's: such points count 1.
    pub label_probs: Option<&'a [f32]>,
}

/// [`refine_variants`] with the [`PointEvidence`] of the projection. With `cfg.vote =
/// multi_view` every configuration but Reference starts from `evidence.voted` instead of
/// `cloud.labels` (clustering, steps, and the fuse's "original label"); Reference is
/// `cloud.labels`, the projection, either way. With `cfg.vote = off`, `voted` is ignored;
/// `label_probs` only matter to `noise = "probability"`.
///
/// # Errors
/// As [`refine_variants`]; `cfg.vote = multi_view` and `voted` is `None` or not one label
/// per point; `label_probs` not one per point.
pub fn refine_variants_with(
    cloud: &LabeledCloud,
    evidence: PointEvidence<'_>,
    boxes: &[PersonBox],
    cfg: &RefineConfig,
    steps: &[Steps],
    with_clusters: bool,
) -> Result<RefinedVariants, RefineError> {
    cfg.validate()?;
    cfg.validate_for_extent(validated_extent_m(cloud)?)?;
    let PointEvidence { voted, label_probs } = evidence;
    let colors = match &cloud.colors {
        _ if cfg.foreign_color_density == 0.0 => None,
        Some(c) => Some(c.as_slice()),
        None => {
            return Err(RefineError::NoColors {
                density: cfg.foreign_color_density,
            });
        }
    };
    if let Some(p) = label_probs
        && p.len() != cloud.len()
    {
        return Err(RefineError::LabelProbs {
            got: p.len(),
            want: cloud.len(),
        });
    }
    // Probabilities only where the steps use them: the starting label's, 1 where the vote
    // replaced the projected label.
    let label_probs = label_probs.filter(|_| cfg.noise == NoiseMode::Probability);
    // The labels the configurations other than Reference start from.
    let start: &[Label] = match (cfg.vote, voted) {
        (VoteMode::Off, _) => &cloud.labels,
        (VoteMode::MultiView, Some(v)) if v.len() == cloud.len() => v,
        (VoteMode::MultiView, v) => {
            return Err(RefineError::VoteLabels {
                got: v.map_or(0, <[Label]>::len),
                want: cloud.len(),
            });
        }
    };
    if let Some(reason) = boxes.iter().find_map(PersonBox::invalid_reason) {
        return Err(RefineError::InvalidBox { reason });
    }
    let runs: Vec<Steps> = steps
        .iter()
        .copied()
        .filter(|s| *s != Steps::Reference)
        .collect();
    // Per person: its point indices and one refinement per entry of `runs`.
    let people: Vec<(Vec<u32>, Vec<PersonRefinement>)> = if runs.is_empty() {
        Vec::new()
    } else {
        boxes
            .par_iter()
            .map(|b| {
                let test = b.test();
                // Branch-free: every index is written, the end advances only for points
                // inside (a `filter().collect()` pushed with a capacity test per point).
                let mut idx: Vec<u32> = vec![0; cloud.len()];
                let mut inside = 0;
                // Four points a test (`contains4`), the rest one by one.
                let mut quads = cloud.positions_m.chunks_exact(4);
                for (q, four) in (&mut quads).enumerate() {
                    let four: &[Vec3; 4] = four.try_into().expect("chunks of 4");
                    for (l, ok) in test.contains4(four).into_iter().enumerate() {
                        idx[inside] = (4 * q + l) as u32;
                        inside += usize::from(ok);
                    }
                }
                let done = cloud.len() - quads.remainder().len();
                for (i, &p) in cloud.positions_m.iter().enumerate().skip(done) {
                    idx[inside] = i as u32;
                    inside += usize::from(test.contains(p));
                }
                idx.truncate(inside);
                // A box holding the whole cloud (a cloud cropped to one person) needs no
                // copy.
                let copied;
                let (pos, lab): (&[Vec3], &[Label]) = if idx.len() == cloud.len() {
                    (&cloud.positions_m, start)
                } else {
                    copied = (
                        idx.iter()
                            .map(|&i| cloud.positions_m[i as usize])
                            .collect::<Vec<Vec3>>(),
                        idx.iter()
                            .map(|&i| start[i as usize])
                            .collect::<Vec<Label>>(),
                    );
                    (&copied.0, &copied.1)
                };
                let probs: Option<Vec<f32>> = label_probs.map(|p| {
                    idx.iter()
                        .map(|&i| {
                            let i = i as usize;
                            if start[i] == cloud.labels[i] {
                                p[i]
                            } else {
                                1.0
                            }
                        })
                        .collect()
                });
                let probs = probs.as_deref();
                // `noise = "probability"`: labels the parser was unsure of take no part in
                // the clustering (they become noise, relabelled by N from the sure ones
                // around them); the steps still see them as the point's own label.
                let doubtful: Option<Vec<Label>> = probs
                    .filter(|_| cfg.noise_doubt_ratio > 0.0)
                    .map(|p| doubtful_as_unknown(lab, p, cfg.noise_doubt_ratio));
                let cluster_lab: &[Label] = doubtful.as_deref().unwrap_or(lab);
                // The points whose label was doubted (for the wider vote of N).
                let doubted: Option<Vec<bool>> = doubtful.as_ref().map(|d| {
                    d.iter()
                        .zip(lab)
                        .map(|(c, l)| c.is_unknown() && !l.is_unknown())
                        .collect()
                });
                let doubted = doubted.as_deref();
                // N's search depends on the clustering only: once for every run with N, on
                // DBSCAN's cells.
                let want_nearest = cfg.noise == NoiseMode::Nearest && runs.iter().any(Steps::noise);
                let (structure, cells) = analyse_person_with(pos, cluster_lab, cfg, want_nearest);
                let nearest = want_nearest.then(|| {
                    NoiseNearest::of_clustering(
                        pos,
                        &structure.clustering.cluster_of,
                        cfg.eps_m,
                        cells,
                    )
                });
                let evidence = PersonEvidence {
                    label_probs: probs,
                    doubted,
                    nearest: nearest.as_ref(),
                };
                // Every run but the last works on a copy; the last (the only one of a
                // plain run) takes the structure itself.
                let mut refinements: Vec<PersonRefinement> = Vec::with_capacity(runs.len());
                if let Some((&last, rest)) = runs.split_last() {
                    for &s in rest {
                        refinements.push(apply_steps_with(
                            structure.clone(),
                            pos,
                            lab,
                            evidence,
                            s,
                            cfg,
                        ));
                    }
                    refinements.push(apply_steps_with(structure, pos, lab, evidence, last, cfg));
                }
                if let Some(colors) = colors {
                    let colors: Vec<[u8; 3]> = idx.iter().map(|&i| colors[i as usize]).collect();
                    for r in &mut refinements {
                        color::drop_foreign_arms(
                            &mut r.point_labels,
                            &colors,
                            cfg.foreign_color_density,
                            // Unknown: this person abstains; another whose box holds the
                            // point (a hand reaching into it) may keep it.
                            Label::UNKNOWN,
                        );
                    }
                }
                if let Some(r) = refinements.last() {
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
                }
                (idx, refinements)
            })
            .collect()
    };
    let mut run_index = 0;
    let mut out = RefinedVariants {
        labels: Vec::with_capacity(steps.len()),
        clusters: Vec::new(),
    };
    for s in steps {
        if *s == Steps::Reference {
            out.labels.push(cloud.labels.clone());
            continue;
        }
        let per_person: Vec<(&[u32], &PersonRefinement)> = people
            .iter()
            .map(|(idx, rs)| (idx.as_slice(), &rs[run_index]))
            .collect();
        // The clusters are the same for every configuration: collect them once.
        let first = run_index == 0 && with_clusters;
        let (labels, clusters) = fuse_labels(
            cloud,
            start,
            boxes,
            &per_person,
            cfg.keep_outside_boxes,
            first,
        );
        out.labels.push(labels);
        if first {
            out.clusters = clusters;
        }
        run_index += 1;
    }
    if with_clusters && out.clusters.is_empty() {
        out.clusters = vec![None; cloud.len()];
    }
    Ok(out)
}

/// [`LabeledCloud::validate`], and the largest extent of the positions along an axis,
/// metres (0 when empty), in one pass over the positions instead of two: the pass that
/// takes the extent also sums `x · 0` over every coordinate, which stays ±0 unless some
/// coordinate is infinite or NaN. Any doubt (a length that differs, a non-finite
/// coordinate) asks `validate` itself, so the errors are its own.
fn validated_extent_m(cloud: &LabeledCloud) -> Result<f32, RefineError> {
    let n = cloud.len();
    let lengths_agree = cloud.labels.len() == n
        && cloud.origins.len() == n
        && cloud.colors.as_ref().is_none_or(|c| c.len() == n);
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut probe = [0f32; 3];
    for p in &cloud.positions_m {
        for a in 0..3 {
            lo[a] = if p[a] < lo[a] { p[a] } else { lo[a] };
            hi[a] = if p[a] > hi[a] { p[a] } else { hi[a] };
            probe[a] += p[a] * 0.0;
        }
    }
    if !lengths_agree || probe.iter().any(|&z| z != 0.0) {
        cloud.validate()?;
    }
    Ok((0..3).map(|a| hi[a] - lo[a]).fold(0.0, f32::max))
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
    let refs: Vec<(&[u32], &PersonRefinement)> =
        people.iter().map(|(idx, r)| (idx.as_slice(), r)).collect();
    let (labels, clusters) =
        fuse_labels(cloud, &cloud.labels, boxes, &refs, keep_outside_boxes, true);
    RefinedCloud {
        cloud: cloud.with_labels(labels),
        clusters,
    }
}

/// [`fuse`] on borrowed people, with `original` as the points' labels before refinement:
/// the labels, and the clusters when `with_clusters` (else an empty list).
fn fuse_labels(
    cloud: &LabeledCloud,
    original: &[Label],
    boxes: &[PersonBox],
    people: &[(&[u32], &PersonRefinement)],
    keep_outside_boxes: bool,
    with_clusters: bool,
) -> (Vec<Label>, Vec<Option<(u32, u32)>>) {
    let n = cloud.len();
    if let [(idx, r)] = people
        && idx.len() == n
    {
        // One person whose box holds every point (a cloud cropped to one person; `idx` is
        // then `0..n`): its labels are the output, as the rules below give, without the
        // pass over the original labels and the scatter.
        let mut labels = r.point_labels.clone();
        for l in &mut labels {
            if l.is_unknown() {
                *l = Label::BACKGROUND;
            }
        }
        let clusters = if with_clusters {
            r.clustering
                .cluster_of
                .iter()
                .map(|c| c.map(|c| (0, c)))
                .collect()
        } else {
            Vec::new()
        };
        return (labels, clusters);
    }
    // Points outside every box first (most of a room's points), then each person's
    // points over them. Two bytes per point of working memory, no per-point `Option`s:
    // this runs once per configuration on every frame.
    let mut labels: Vec<Label> = original
        .iter()
        .map(|&original| match original {
            o if keep_outside_boxes && !o.is_unknown() => o,
            o if o.is_body() || o.is_unknown() => Label::BACKGROUND,
            o => o,
        })
        .collect();
    let mut clusters = if with_clusters {
        vec![None; n]
    } else {
        Vec::new()
    };
    if let [(idx, r)] = people {
        // One person: every point of its box takes its label (what the rules below give
        // when no point is in two boxes), without the bookkeeping.
        for (k, (&i, &l)) in idx.iter().zip(&r.point_labels).enumerate() {
            labels[i as usize] = l;
            if with_clusters {
                clusters[i as usize] = r
                    .clustering
                    .cluster_of
                    .get(k)
                    .copied()
                    .flatten()
                    .map(|c| (0, c));
            }
        }
    } else {
        fuse_people(
            cloud,
            original,
            boxes,
            people,
            &mut labels,
            &mut clusters,
            with_clusters,
        );
    }
    for l in &mut labels {
        if l.is_unknown() {
            *l = Label::BACKGROUND;
        }
    }
    (labels, clusters)
}

/// [`fuse_labels`] of several people over `labels` (the points outside every box done).
fn fuse_people(
    cloud: &LabeledCloud,
    original: &[Label],
    boxes: &[PersonBox],
    people: &[(&[u32], &PersonRefinement)],
    labels: &mut [Label],
    clusters: &mut [Option<(u32, u32)>],
    with_clusters: bool,
) {
    let n = cloud.len();
    // Per point: how many people's boxes hold it, as far as the fuse cares.
    const NONE: u8 = 0;
    const AGREE: u8 = 1;
    const DISAGREE: u8 = 2;
    let mut seen = vec![NONE; n];
    for (p, (idx, r)) in people.iter().enumerate() {
        for (k, &i) in idx.iter().enumerate() {
            let i = i as usize;
            let l = r.point_labels[k];
            let take = |labels: &mut [Label], clusters: &mut [Option<(u32, u32)>]| {
                labels[i] = l;
                if with_clusters {
                    clusters[i] = r
                        .clustering
                        .cluster_of
                        .get(k)
                        .copied()
                        .flatten()
                        .map(|c| (p as u32, c));
                }
            };
            match seen[i] {
                NONE => {
                    take(labels, clusters);
                    seen[i] = AGREE;
                }
                // Unknown is a person abstaining (a color it does not wear): the others
                // decide; when all abstain, background (in `fuse_labels`).
                AGREE if l.is_unknown() => {}
                AGREE if labels[i].is_unknown() => take(labels, clusters),
                AGREE if labels[i] != l => seen[i] = DISAGREE,
                _ => {}
            }
        }
    }
    // People that disagree: the original label, or when unknown the nearest box's.
    for (idx, _) in people {
        for &i in *idx {
            let iu = i as usize;
            if seen[iu] != DISAGREE {
                continue;
            }
            seen[iu] = AGREE; // Decided (a point is in several people's lists).
            let own = original[iu];
            labels[iu] = if own.is_unknown() {
                nearest_box_label(cloud.positions_m[iu], i, boxes, people)
            } else {
                own
            };
        }
    }
}

/// The label that the person whose box centre is nearest (horizontally) gave point `i`
/// (people who abstained, unknown, left out; background when all did).
fn nearest_box_label(
    p: Vec3,
    i: u32,
    boxes: &[PersonBox],
    people: &[(&[u32], &PersonRefinement)],
) -> Label {
    let mut best: Option<(f32, Label)> = None;
    for (b, (idx, r)) in boxes.iter().zip(people) {
        if let Ok(k) = idx.binary_search(&i)
            && !r.point_labels[k].is_unknown()
        {
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
