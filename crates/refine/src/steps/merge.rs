//! M — merge_nodes (ALGORITHM.md §5.4).

use crate::graph::{BodyTree, ClusterFeatures, ClusterGraph};
use bodyseg_core::Label;

/// M — merge_nodes: every cluster that is not a tree node and lies inside at least one
/// cluster of a different label takes the label of the largest such container (ties: the
/// smaller id). Containers are judged with `labels` as given (all updates at once), so the
/// result does not depend on order. Background containers count only when
/// `merge_into_background` is set, and never for a lower-leg cluster: a foot stands on the
/// floor, so the floor's cluster holds it whatever its label (merging them cost the
/// synthetic parser errors 0.5–2.4 IoU of lower legs on the tune sets of the improved
/// configuration; the other parts gained).
pub fn merge_nodes(
    features: &[ClusterFeatures],
    labels: &[Label],
    graph: &ClusterGraph,
    tree: &BodyTree,
    merge_into_background: bool,
) -> Vec<Label> {
    (0..features.len())
        .map(|a| {
            let own = labels[a];
            if tree.contains(a as u32) {
                return own;
            }
            let best = graph.containers[a]
                .iter()
                .map(|&b| b as usize)
                .filter(|&b| labels[b] != own)
                // Lower legs never go to the background: they stand on the floor, which
                // always holds them (`floor_contact_m` gives the floor under them back).
                .filter(|&b| {
                    labels[b].is_body()
                        || (merge_into_background
                            && own != Label::from(bodyseg_core::Class::LowerLegs))
                })
                .fold(None, |best: Option<usize>, b| match best {
                    Some(x) if features[x].size >= features[b].size => Some(x),
                    _ => Some(b),
                });
            best.map_or(own, |b| labels[b])
        })
        .collect()
}
