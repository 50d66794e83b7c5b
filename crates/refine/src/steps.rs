//! The M, R and N steps (ALGORITHM.md §5.4–§5.6), each a plain function.

use crate::graph::{BodyTree, ClusterFeatures, Graph};
use bodyseg_core::math::{Vec3, dist2};
use bodyseg_core::{Label, NUM_CLASSES};
use std::collections::HashMap;

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
    graph: &Graph,
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

/// R — remove_nodes: when the tree is valid, every body-labelled cluster not connected to
/// the tree through a chain of inside / intersect / tree edges *between body-labelled
/// clusters* becomes background. Background clusters stay background; a chain may not pass
/// through them (a floor touches everything). With no valid tree, nothing changes.
pub fn remove_nodes(labels: &[Label], graph: &Graph, tree: &BodyTree) -> Vec<Label> {
    if !tree.is_valid() {
        return labels.to_vec();
    }
    let k = labels.len();
    let mut reached = vec![false; k];
    // Tree nodes are body-labelled (they never change), and tree edges join them; seeding
    // the search with all of them covers the tree edges.
    let mut stack: Vec<u32> = tree.nodes().collect();
    for &n in &stack {
        reached[n as usize] = true;
    }
    while let Some(a) = stack.pop() {
        for &b in &graph.adjacent[a as usize] {
            if !reached[b as usize] && labels[b as usize].is_body() {
                reached[b as usize] = true;
                stack.push(b);
            }
        }
    }
    labels
        .iter()
        .zip(&reached)
        .map(|(&l, &r)| {
            if l.is_body() && !r {
                Label::BACKGROUND
            } else {
                l
            }
        })
        .collect()
}

/// R's bridge (`remove_through_noise`): after [`remove_nodes`] (`removed`, from
/// `before`), a cluster R turned into background gets its label back when a chain of body
/// points joins it to a tree cluster: points of body-labelled clusters (labels `before`)
/// and noise points the parser labelled body (`own`), in cells of `cell_m` touching one
/// another (26 neighbours, so gaps up to about one cell). Tree clusters are never removed.
///
/// Why: the contact graph R walks joins clusters only, and the points left out of the
/// clustering — labels the parser doubted (`noise_doubt_ratio`), sparse DBSCAN noise — are
/// still the body's surface. A forearm or a foot joined to the body by a strip the parser
/// hesitated on (an elbow, a knee, a hidden ankle) was cut off and removed; an object or a
/// clump of flying pixels with no body points between it and the person still is. Measured
/// on the tune sets of docs/notes/2026-11-30-improved-refinement-tuning.md.
pub fn restore_bridged(
    removed: &[Label],
    before: &[Label],
    positions_m: &[Vec3],
    cluster_of: &[Option<u32>],
    own: &[Label],
    tree: &BodyTree,
    cell_m: f32,
) -> Vec<Label> {
    let mut out = removed.to_vec();
    if !tree.is_valid() || removed == before {
        return out;
    }
    let key = |p: Vec3| p.map(|x| (x / cell_m).floor() as i32);
    // Cells holding body points, then their components (flood fill over 26 neighbours).
    const UNSEEN: u32 = u32::MAX;
    let mut component: HashMap<[i32; 3], u32> = HashMap::default();
    for ((p, c), l) in positions_m.iter().zip(cluster_of).zip(own) {
        let body = match c {
            Some(c) => before[*c as usize].is_body(),
            None => l.is_body(),
        };
        if body {
            component.insert(key(*p), UNSEEN);
        }
    }
    let mut cells: Vec<[i32; 3]> = component.keys().copied().collect();
    // Deterministic component ids whatever the map's order.
    cells.sort_unstable();
    let mut next = 0;
    let mut stack = Vec::new();
    for start in cells {
        if component[&start] != UNSEEN {
            continue;
        }
        component.insert(start, next);
        stack.push(start);
        while let Some(k) = stack.pop() {
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let n = [k[0] + dx, k[1] + dy, k[2] + dz];
                        if let Some(id) = component.get_mut(&n)
                            && *id == UNSEEN
                        {
                            *id = next;
                            stack.push(n);
                        }
                    }
                }
            }
        }
        next += 1;
    }
    // The components the tree lies in, and those of each removed cluster.
    let in_tree: Vec<bool> = (0..before.len() as u32).map(|c| tree.contains(c)).collect();
    let mut with_tree = vec![false; next as usize];
    for (p, c) in positions_m.iter().zip(cluster_of) {
        if let Some(c) = c
            && in_tree[*c as usize]
            && let Some(&id) = component.get(&key(*p))
        {
            with_tree[id as usize] = true;
        }
    }
    for (p, c) in positions_m.iter().zip(cluster_of) {
        if let Some(c) = c {
            let c = *c as usize;
            if out[c] != before[c]
                && component
                    .get(&key(*p))
                    .is_some_and(|&id| with_tree[id as usize])
            {
                out[c] = before[c];
            }
        }
    }
    out
}

/// N — reassign_noise: every point with `is_noise[i]` takes the label of the nearest point
/// with `!is_noise` (ties: the smaller index), exact nearest neighbour. With no clustered
/// point, noise keeps its label and unknown becomes background.
///
/// Why not a plain ring search or an unbounded k-d tree walk: flying pixels lie far from
/// the body, and searching outward from each costs more than the clustering. [`NnIndex`]
/// is a two-level grid: blocks of cells, each with the tight bounding box of its points, so
/// a query ranks the few hundred blocks by lower bound and opens only those that can still
/// hold a nearer point — a bounded cost whatever the distance.
pub fn reassign_noise(
    positions_m: &[Vec3],
    labels: &[Label],
    is_noise: &[bool],
    eps_m: f32,
) -> Vec<Label> {
    let mut out = labels.to_vec();
    let clustered: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| !is_noise[i as usize])
        .collect();
    if clustered.is_empty() {
        for l in &mut out {
            if l.is_unknown() {
                *l = Label::BACKGROUND;
            }
        }
        return out;
    }
    let index = NnIndex::new(positions_m, &clustered, eps_m);
    for i in 0..positions_m.len() {
        if is_noise[i]
            && let Some(j) = index.nearest(positions_m[i])
        {
            out[i] = labels[j as usize];
        }
    }
    out
}

/// Who votes in N's votes ([`reassign_noise_weighted`], [`reassign_doubted_wide`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vote {
    /// About this many nearest clustered points vote.
    pub k: usize,
    /// They lie within this distance, metres, which also scales their weight
    /// (`1 / (1 + (d / radius_m)²)`). Must be > 0.
    pub radius_m: f32,
    /// The point's own label weighs this many voters lying on the point.
    pub self_weight: f32,
}

/// N, weighted (`noise = "weighted"`): every point with `is_noise[i]` (and `relabel[i]`,
/// when given: the others keep their label) takes the label with the largest vote among the
/// `vote.k` nearest points with `!is_noise` within `vote.radius_m` (`eps_m` in a run; ties
/// between points: the smaller index), each voting for its label with weight
/// `1 / (1 + (d / radius_m)²)` (1 on the point, ½ at the radius), plus the point's own
/// label — the parser's, unless unknown — with weight `vote.self_weight` (as many voters
/// lying on the point). Ties between labels go to the nearest voter's label. A noise point
/// with no clustered point within the radius has no neighbourhood to be corrected by: it
/// keeps its own label, unless that is unknown or `self_weight` is 0 (then the nearest
/// clustered point's label, as in [`reassign_noise`]).
///
/// With `label_probs` (`noise = "probability"`: the parser's probability of each point's
/// own label, one per point) the own label weighs `self_weight × label_probs[i]` (clamped
/// to [0, 1]; NaN counts 1), so a label the parser was unsure of — a border pixel, a part
/// it hesitated on — yields to its neighbours while a sure one holds against a strand of
/// another label. Without, every own label weighs `self_weight`.
///
/// What it fixes: 1-NN follows whichever single point is nearest — a thin strand of another
/// label, a stray border point — where the surrounding surface says otherwise, and it
/// overwrites whole parts too sparse to cluster (a hand far from the sensors) with the
/// label of whatever cluster is nearest.
pub fn reassign_noise_weighted(
    positions_m: &[Vec3],
    labels: &[Label],
    is_noise: &[bool],
    relabel: Option<&[bool]>,
    label_probs: Option<&[f32]>,
    vote: Vote,
) -> Vec<Label> {
    let Vote {
        k,
        radius_m: eps_m,
        self_weight,
    } = vote;
    let clustered: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| !is_noise[i as usize])
        .collect();
    if clustered.is_empty() {
        return reassign_noise(positions_m, labels, is_noise, eps_m);
    }
    let mut out = labels.to_vec();
    let index = NnIndex::new(positions_m, &clustered, eps_m);
    let r2 = eps_m * eps_m;
    let weight = |d2: f32| 1.0 / (1.0 + d2 / r2);
    let (mut voters, mut cells) = (Vec::new(), Vec::new());
    for i in 0..positions_m.len() {
        if !is_noise[i] || relabel.is_some_and(|r| !r[i]) {
            continue;
        }
        let q = positions_m[i];
        index.knn_within(q, k.max(1), r2, &mut voters, &mut cells);
        let Some(&(_, nearest)) = voters.first() else {
            if (labels[i].is_unknown() || self_weight == 0.0)
                && let Some(j) = index.nearest(q)
            {
                out[i] = labels[j as usize];
            }
            continue;
        };
        let mut votes = [0f32; NUM_CLASSES];
        for &(d2, j) in &voters {
            if let Some(c) = labels[j as usize].class() {
                votes[usize::from(c.id())] += weight(d2);
            }
        }
        if let Some(c) = labels[i].class() {
            let p = label_probs.map_or(1.0, |p| {
                let p = p[i];
                if p.is_nan() { 1.0 } else { p.clamp(0.0, 1.0) }
            });
            votes[usize::from(c.id())] += self_weight * p;
        }
        let mut best = labels[nearest as usize];
        let mut best_vote = best.class().map_or(0.0, |c| votes[usize::from(c.id())]);
        for (id, &v) in votes.iter().enumerate() {
            if v > best_vote {
                best_vote = v;
                best = Label::from_id(id as u8).unwrap_or(best);
            }
        }
        out[i] = best;
    }
    out
}

/// N for the labels the parser doubted (`noise = "probability"` with
/// `noise_doubt_radius_m > 0`): every point with `relabel[i]` (a noise point) takes the
/// label of a vote as in [`reassign_noise_weighted`], but of about `vote.k` clustered
/// points within `vote.radius_m` — a few hundred within 0.15 m, where the other noise
/// points ask the 16 nearest within `eps_m`. Other points keep their label.
///
/// Why wider for doubted points: they are mostly the strips along part boundaries where
/// the parser hesitated, and the few nearest sure points lie on whichever side happens to
/// be denser there; the sure points across a limb's width say better which part the strip
/// belongs to. For DBSCAN's own noise (sparse points, flying pixels, a hand too sparse to
/// cluster) the narrow vote stays better. Measured in docs/notes/2026-12-01-noise-oracle.md.
///
/// How: the clustered points are counted per label in cells of `radius_m / 8`; each cell
/// votes from its centroid with its counts, the nearest cells first until they hold about
/// `k` points (`k` over the mean count of a cell); the doubted points of one cell share
/// the vote asked from the cell's centre and differ only by their own label. Point by
/// point, a few hundred voters each made the refinement 15 times slower (tune sets,
/// docs/notes/2026-12-01-noise-oracle.md); this is within 0.2 BIoU of it.
///
/// A doubted point with no clustered point within the radius keeps its own label, unless
/// that is unknown or `self_weight` is 0 (then the nearest clustered point's). Ties go to
/// the own label, then to the smaller class id.
pub fn reassign_doubted_wide(
    positions_m: &[Vec3],
    labels: &[Label],
    is_noise: &[bool],
    relabel: &[bool],
    label_probs: Option<&[f32]>,
    vote: Vote,
) -> Vec<Label> {
    let clustered: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| !is_noise[i as usize])
        .collect();
    if clustered.is_empty() || !relabel.iter().any(|&r| r) {
        return labels.to_vec();
    }
    let Vote {
        k,
        radius_m,
        self_weight,
    } = vote;
    let cells = LabelCells::new(positions_m, labels, &clustered, radius_m, k);
    let mut out = labels.to_vec();
    let mut scratch = CellScratch::default();
    let mut nearest_point: Option<Vec<Label>> = None;
    // The votes of the cells around each cell holding noise, asked from its centre: the
    // noise points of one cell share them (they differ only by their own label).
    let mut cell_votes: HashMap<[i32; 3], Option<[f32; NUM_CLASSES]>> = HashMap::default();
    for i in 0..positions_m.len() {
        if !(is_noise[i] && relabel[i]) {
            continue;
        }
        let at = cells.key(positions_m[i]);
        let around = *cell_votes
            .entry(at)
            .or_insert_with(|| cells.votes_around(at, &mut scratch));
        let Some(mut votes) = around else {
            if labels[i].is_unknown() || self_weight == 0.0 {
                let nearest = nearest_point
                    .get_or_insert_with(|| reassign_noise(positions_m, labels, is_noise, radius_m));
                out[i] = nearest[i];
            }
            continue;
        };
        let own = labels[i].class().map(|c| usize::from(c.id()));
        if let Some(c) = own {
            let p = label_probs.map_or(1.0, |p| {
                let p = p[i];
                if p.is_nan() { 1.0 } else { p.clamp(0.0, 1.0) }
            });
            votes[c] += self_weight * p;
        }
        if let Some(b) = winner(&votes, own) {
            out[i] = Label::from_id(b as u8).unwrap_or(labels[i]);
        }
    }
    out
}

/// S — smooth_labels (`smooth_radius_m`): every body-labelled point takes the body label
/// most body-labelled points within `radius_m` carry (each weighing
/// `1 / (1 + (d / radius_m)²)`, the point itself included; ties keep its own). All points
/// are judged on the labels as given, so the result does not depend on order. Background
/// and unknown points neither vote nor change: a body point never becomes background here.
///
/// Why: after M, R and N a person's labels still hold islands of another part smaller than
/// a cluster the steps act on (a few centimetres of upper arm on the torso, a patch of
/// lower leg on the thigh), and the parser's part boundaries are ragged; the surface around
/// a point says better which part it lies on. A vote over body labels only, so that the
/// floor or a wall does not outvote a foot or a hand. Measured on the tune sets of
/// docs/notes/2026-11-30-improved-refinement-tuning.md.
///
/// How: as [`reassign_doubted_wide`], the body points are counted per label in cells of
/// `radius_m / 8`, and the points of one cell share the vote asked from its centre.
pub fn smooth_labels(positions_m: &[Vec3], labels: &[Label], radius_m: f32) -> Vec<Label> {
    smooth_labels_with(positions_m, labels, radius_m, true)
}

/// [`smooth_labels`], asking every point's vote when `skip_single_class` is false (the
/// tests check that skipping changes nothing).
fn smooth_labels_with(
    positions_m: &[Vec3],
    labels: &[Label],
    radius_m: f32,
    skip_single_class: bool,
) -> Vec<Label> {
    let body: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| labels[i as usize].is_body())
        .collect();
    if body.is_empty() || radius_m <= 0.0 {
        return labels.to_vec();
    }
    // Every cell within the radius votes.
    let cells = LabelCells::new(positions_m, labels, &body, radius_m, usize::MAX);
    // Most of a body lies farther than the radius from any other part: there the vote can
    // only name the own label, so it is not asked. The classes of the cells per block of
    // side a little over the radius, placed by their centroids (the voters): every voter
    // within the radius of a cell's centre lies in the 3×3×3 blocks around the centre's
    // block (the margin keeps rounding from breaking that).
    let block_m = radius_m * 1.01;
    let block_of = |p: Vec3| p.map(|x| (x / block_m).floor() as i32);
    let mut classes_in: HashMap<[i32; 3], u16> = HashMap::default();
    for (centroid, counts) in cells.centroids.iter().zip(&cells.counts) {
        let present = (0..NUM_CLASSES)
            .filter(|&c| counts[c] > 0.0)
            .fold(0u16, |m, c| m | 1 << c);
        *classes_in.entry(block_of(*centroid)).or_default() |= present;
    }
    let mut classes_around: HashMap<[i32; 3], u16> = HashMap::default();
    let mut out = labels.to_vec();
    let mut scratch = CellScratch::default();
    let mut cell_votes: HashMap<[i32; 3], Option<[f32; NUM_CLASSES]>> = HashMap::default();
    for &i in &body {
        let i = i as usize;
        let at = cells.key(positions_m[i]);
        let b = block_of(cells.centre(at));
        let around = *classes_around.entry(b).or_insert_with(|| {
            let mut m = 0;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let n = [b[0] + dx, b[1] + dy, b[2] + dz];
                        m |= classes_in.get(&n).copied().unwrap_or(0);
                    }
                }
            }
            m
        });
        if skip_single_class && around.count_ones() == 1 {
            continue; // Only the point's own class within reach.
        }
        let around = *cell_votes
            .entry(at)
            .or_insert_with(|| cells.votes_around(at, &mut scratch));
        let own = labels[i].class().map(|c| usize::from(c.id()));
        if let Some(b) = around.and_then(|v| winner(&v, own)) {
            out[i] = Label::from_id(b as u8).unwrap_or(labels[i]);
        }
    }
    out
}

/// The class with the largest vote (> 0); ties go to `own`, then to the smaller class id.
fn winner(votes: &[f32; NUM_CLASSES], own: Option<usize>) -> Option<usize> {
    let mut best = own;
    for (c, &v) in votes.iter().enumerate() {
        if best.is_none_or(|b| v > votes[b]) && v > 0.0 {
            best = Some(c);
        }
    }
    best
}

/// Cells of a wide vote ([`reassign_doubted_wide`], [`smooth_labels`]) per radius.
const WIDE_VOTE_CELLS: f32 = 8.0;

/// Voters counted per label in cells of `radius_m / WIDE_VOTE_CELLS`, for the wide votes:
/// each cell votes from its centroid with its counts, weighing `1 / (1 + (d / radius)²)`.
struct LabelCells {
    side_m: f32,
    r2: f32,
    /// Nearest cells asked per vote (about `k` voters); `usize::MAX`: every cell within
    /// the radius.
    k_cells: usize,
    /// Per cell, its voters per class (counts, as f32 to weigh them).
    counts: Vec<[f32; NUM_CLASSES]>,
    /// Where each cell votes from: the mean of its voters.
    centroids: Vec<Vec3>,
    /// Over the cells' centroids.
    index: NnIndex,
}

/// Buffers reused between [`LabelCells::votes_around`] calls.
#[derive(Default)]
struct CellScratch {
    voters: Vec<(f32, u32)>,
    cells: Vec<(f32, u32)>,
}

impl LabelCells {
    /// Counts the labels of `voters` (point indices, at least one) per cell; a vote asks
    /// the nearest cells holding about `k` of them within `radius_m` (`usize::MAX`: all).
    fn new(
        positions_m: &[Vec3],
        labels: &[Label],
        voters: &[u32],
        radius_m: f32,
        k: usize,
    ) -> Self {
        let side_m = radius_m / WIDE_VOTE_CELLS;
        let key = |p: Vec3| p.map(|x| (x / side_m).floor() as i32);
        let mut cell_of: HashMap<[i32; 3], u32> = HashMap::default();
        let mut sums: Vec<[f64; 3]> = Vec::new();
        let mut counts: Vec<[f32; NUM_CLASSES]> = Vec::new();
        for &i in voters {
            let p = positions_m[i as usize];
            let next = sums.len() as u32;
            let c = *cell_of.entry(key(p)).or_insert(next) as usize;
            if c == sums.len() {
                sums.push([0.0; 3]);
                counts.push([0.0; NUM_CLASSES]);
            }
            for a in 0..3 {
                sums[c][a] += f64::from(p[a]);
            }
            if let Some(class) = labels[i as usize].class() {
                counts[c][usize::from(class.id())] += 1.0;
            }
        }
        let centroids: Vec<Vec3> = sums
            .iter()
            .zip(&counts)
            .map(|(s, n)| {
                let n = f64::from(n.iter().sum::<f32>().max(1.0));
                s.map(|x| (x / n) as f32)
            })
            .collect();
        let ids: Vec<u32> = (0..centroids.len() as u32).collect();
        let per_cell = voters.len() as f32 / centroids.len().max(1) as f32;
        Self {
            side_m,
            r2: radius_m * radius_m,
            k_cells: if k == usize::MAX {
                usize::MAX
            } else {
                ((k as f32 / per_cell).ceil() as usize).max(1)
            },
            counts,
            index: NnIndex::new(&centroids, &ids, radius_m / 3.0),
            centroids,
        }
    }

    /// The cell key of a position.
    fn key(&self, p: Vec3) -> [i32; 3] {
        p.map(|x| (x / self.side_m).floor() as i32)
    }

    /// The centre of cell `at`, where its vote is asked from.
    fn centre(&self, at: [i32; 3]) -> Vec3 {
        at.map(|x| (x as f32 + 0.5) * self.side_m)
    }

    /// The votes per class of the cells around cell `at`, asked from its centre; `None`
    /// when no cell lies within the radius.
    fn votes_around(&self, at: [i32; 3], s: &mut CellScratch) -> Option<[f32; NUM_CLASSES]> {
        let centre = self.centre(at);
        let mut votes = [0f32; NUM_CLASSES];
        let mut any = false;
        let mut vote = |d2: f32, c: u32| {
            let w = 1.0 / (1.0 + d2 / self.r2);
            for (v, &n) in votes.iter_mut().zip(&self.counts[c as usize]) {
                *v += w * n;
            }
            any = true;
        };
        if self.k_cells == usize::MAX {
            // Every cell within the radius votes, in no particular order: no list to keep.
            self.index
                .for_each_within(centre, self.r2, &mut s.cells, &mut vote);
        } else {
            self.index
                .knn_within(centre, self.k_cells, self.r2, &mut s.voters, &mut s.cells);
            for &(d2, c) in &s.voters {
                vote(d2, c);
            }
        }
        any.then_some(votes)
    }
}

/// Value at quantile `q` in [0, 1] of `v`, which must not be empty: the element of rank
/// round((len - 1) q) (the upper median for q = 0.5 and an even length). Reorders `v`.
pub(crate) fn quantile(v: &mut [f32], q: f64) -> f32 {
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    *v.select_nth_unstable_by(k, f32::total_cmp).1
}

/// `noise = "probability"`'s doubt test: `labels` with every label the parser was unsure of
/// made unknown (so the clustering leaves it out and N relabels it). A label is doubtful
/// when its probability (`probs[i]`, one per point) is below `ratio` × the median
/// probability of that same label over these points (a person's); unknown stays unknown,
/// a NaN probability is never doubtful.
///
/// Why relative to the label's own median, not one threshold for all: a parser is less sure
/// of small parts everywhere (a forearm's pixels are mostly border pixels). One absolute
/// threshold (0.6) made whole forearms noise, and the larger sure parts around them outvoted
/// them in N: on the benchmark of docs/results.md lower arms lost 1.2–3.5 IoU against no
/// probabilities. Relative to each label's median only the points the parser doubted more
/// than it usually doubts that part go (tuning in
/// `docs/notes/2026-11-30-improved-refinement-tuning.md`).
pub fn doubtful_as_unknown(labels: &[Label], probs: &[f32], ratio: f32) -> Vec<Label> {
    let mut by_class: [Vec<f32>; NUM_CLASSES] = Default::default();
    for (l, &p) in labels.iter().zip(probs) {
        if let Some(c) = l.class()
            && !p.is_nan()
        {
            by_class[usize::from(c.id())].push(p);
        }
    }
    let threshold = by_class.map(|mut v| {
        if v.is_empty() {
            return 0.0;
        }
        quantile(&mut v, 0.5) * ratio
    });
    labels
        .iter()
        .zip(probs)
        .map(|(&l, &p)| match l.class() {
            Some(c) if p < threshold[usize::from(c.id())] => Label::UNKNOWN,
            _ => l,
        })
        .collect()
}

/// Fine cells per block edge in [`NnIndex`].
const NN_BLOCK_CELLS: i32 = 4;

/// Axis-aligned box, metres.
#[derive(Clone, Copy)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };
    fn grow(&mut self, p: Vec3) {
        // Plain comparisons (coordinates are finite): `f32::min`'s NaN handling costs
        // several instructions per call on this hot path.
        for a in 0..3 {
            if p[a] < self.lo[a] {
                self.lo[a] = p[a];
            }
            if p[a] > self.hi[a] {
                self.hi[a] = p[a];
            }
        }
    }
    fn union(&mut self, o: &Aabb) {
        self.grow(o.lo);
        self.grow(o.hi);
    }
    /// Squared distance from `q` to the box (0 inside); a lower bound for its points,
    /// shaved by a hair so rounding never prunes a point at exactly the best distance.
    #[inline]
    fn dist2(&self, q: Vec3) -> f32 {
        let mut d = 0.0;
        for a in 0..3 {
            let g = (self.lo[a] - q[a]).max(q[a] - self.hi[a]).max(0.0);
            d += g * g;
        }
        d * (1.0 - 1e-5)
    }
}

/// Exact nearest-neighbour index over a fixed point set: cells of side eps grouped into
/// blocks of 4×4×4 cells, each cell and block with the bounding box of its points.
struct NnIndex {
    /// Grid geometry, to find a query's own cell.
    lo: Vec3,
    inv_side: f32,
    dims: [i32; 3],
    /// Per grid cell (dense, row-major): its index among the non-empty cells, or `u32::MAX`.
    cell_of_grid: Vec<u32>,
    /// Point ids grouped by cell (CSR over cells), and their positions in the same order.
    items: Vec<u32>,
    pts: Vec<Vec3>,
    cell_start: Vec<u32>,
    cell_box: Vec<Aabb>,
    /// Cells grouped by block (CSR over blocks).
    block_cells: Vec<u32>,
    block_start: Vec<u32>,
    block_box: Vec<Aabb>,
    /// Block lower bounds of the query in progress (reused to avoid an allocation per query).
    scratch: std::cell::RefCell<Vec<f32>>,
}

impl NnIndex {
    fn new(positions: &[Vec3], idx: &[u32], eps_m: f32) -> Self {
        let mut bounds = Aabb::EMPTY;
        for &i in idx {
            bounds.grow(positions[i as usize]);
        }
        let extent = (0..3)
            .map(|a| bounds.hi[a] - bounds.lo[a])
            .fold(0.0f32, f32::max);
        // Cells of side eps, but never more than ~64 along the longest axis.
        let side = eps_m.max(extent / 64.0).max(1e-6);
        let inv_side = 1.0 / side;
        let dims = [0, 1, 2].map(|a| ((bounds.hi[a] - bounds.lo[a]) * inv_side) as i32 + 1);
        let key = |p: Vec3| -> [i32; 3] {
            [0, 1, 2].map(|a| (((p[a] - bounds.lo[a]) * inv_side) as i32).clamp(0, dims[a] - 1))
        };
        let lin = |k: [i32; 3]| ((k[2] * dims[1] + k[1]) * dims[0] + k[0]) as usize;
        let ncell = dims.iter().map(|&d| d as usize).product::<usize>();
        // Counting sort of the points by cell.
        let cell_of: Vec<usize> = idx
            .iter()
            .map(|&i| lin(key(positions[i as usize])))
            .collect();
        let mut start = vec![0u32; ncell + 1];
        for &c in &cell_of {
            start[c + 1] += 1;
        }
        for c in 0..ncell {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut sorted = vec![0u32; idx.len()];
        // Positions too, in cell order, so that scanning a cell reads memory in sequence.
        let mut pts = vec![[0f32; 3]; idx.len()];
        for (&i, &c) in idx.iter().zip(&cell_of) {
            let f = fill[c] as usize;
            sorted[f] = i;
            pts[f] = positions[i as usize];
            fill[c] += 1;
        }
        // Keep the non-empty cells only, with their boxes, and bucket them by block.
        let bdims = dims.map(|d| (d + NN_BLOCK_CELLS - 1) / NN_BLOCK_CELLS);
        let nblock = bdims.iter().map(|&d| d as usize).product::<usize>();
        let mut cell_start = vec![0u32];
        let mut cell_box = Vec::new();
        let mut cell_block = Vec::new();
        let mut cell_of_grid = vec![u32::MAX; ncell];
        for c in 0..ncell {
            let (s, e) = (start[c] as usize, start[c + 1] as usize);
            if s == e {
                continue;
            }
            cell_of_grid[c] = cell_box.len() as u32;
            let mut bx = Aabb::EMPTY;
            for &p in &pts[s..e] {
                bx.grow(p);
            }
            cell_box.push(bx);
            cell_start.push(e as u32);
            let (x, y, z) = (
                c as i32 % dims[0],
                (c as i32 / dims[0]) % dims[1],
                c as i32 / (dims[0] * dims[1]),
            );
            let b = [x, y, z].map(|v| v / NN_BLOCK_CELLS);
            cell_block.push(((b[2] * bdims[1] + b[1]) * bdims[0] + b[0]) as usize);
        }
        let mut bstart = vec![0u32; nblock + 1];
        for &b in &cell_block {
            bstart[b + 1] += 1;
        }
        for b in 0..nblock {
            bstart[b + 1] += bstart[b];
        }
        let mut bfill = bstart.clone();
        let mut bcells = vec![0u32; cell_block.len()];
        for (c, &b) in cell_block.iter().enumerate() {
            bcells[bfill[b] as usize] = c as u32;
            bfill[b] += 1;
        }
        let mut block_start = vec![0u32];
        let mut block_cells = Vec::with_capacity(bcells.len());
        let mut block_box = Vec::new();
        for b in 0..nblock {
            let cells = &bcells[bstart[b] as usize..bstart[b + 1] as usize];
            if cells.is_empty() {
                continue;
            }
            let mut bx = Aabb::EMPTY;
            for &c in cells {
                bx.union(&cell_box[c as usize]);
            }
            block_cells.extend_from_slice(cells);
            block_start.push(block_cells.len() as u32);
            block_box.push(bx);
        }
        NnIndex {
            lo: bounds.lo,
            inv_side,
            dims,
            cell_of_grid,
            items: sorted,
            pts,
            cell_start,
            cell_box,
            block_cells,
            block_start,
            block_box,
            scratch: Default::default(),
        }
    }

    /// The nearest indexed point to `q` (ties: smaller index).
    ///
    /// The block nearest to `q` is opened first so the bound is tight, then every other
    /// block is checked against it in one linear pass (a few hundred box tests).
    fn nearest(&self, q: Vec3) -> Option<u32> {
        let mut best: Option<(f32, u32)> = None;
        // Near the body (most noise: unknown points on it, points at its edges) the answer
        // lies in the query's own 3×3×3 block of cells: scan the own cell, then the block,
        // and stop as soon as the best point is nearer than the block's walls.
        let k = [0, 1, 2].map(|a| ((q[a] - self.lo[a]) * self.inv_side).floor() as i32);
        if (0..3).all(|a| k[a] >= 0 && k[a] < self.dims[a]) {
            let g = ((k[2] * self.dims[1] + k[1]) * self.dims[0] + k[0]) as usize;
            let own = self.cell_of_grid[g];
            if own != u32::MAX {
                self.scan_cell(q, own as usize, &mut best);
                if best.is_some_and(|(b2, _)| b2 <= self.wall_dist2(q, k, 0)) {
                    return best.map(|(_, j)| j);
                }
            }
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let n = [k[0] + dx, k[1] + dy, k[2] + dz];
                        if (dx, dy, dz) == (0, 0, 0)
                            || (0..3).any(|a| n[a] < 0 || n[a] >= self.dims[a])
                        {
                            continue;
                        }
                        let c = self.cell_of_grid
                            [((n[2] * self.dims[1] + n[1]) * self.dims[0] + n[0]) as usize];
                        if c != u32::MAX
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
        // Far from the body: rank the blocks by their lower bound, scan the nearest cell of
        // the nearest block for a real best distance, then open only the blocks and cells
        // whose boxes are nearer than it.
        let blb = &mut *self.scratch.borrow_mut();
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
    /// particular order (the same for the same query): for votes that sum all of them
    /// ([`smooth_labels`]); `cells` is scratch.
    fn for_each_within(
        &self,
        q: Vec3,
        r2: f32,
        cells: &mut Vec<(f32, u32)>,
        mut f: impl FnMut(f32, u32),
    ) {
        self.cells_within(q, r2, cells);
        for &(_, c) in cells.iter() {
            let r = self.cell_start[c as usize] as usize..self.cell_start[c as usize + 1] as usize;
            for (&j, &p) in self.items[r.clone()].iter().zip(&self.pts[r]) {
                let d2 = dist2(q, p);
                if d2 <= r2 {
                    f(d2, j);
                }
            }
        }
    }

    /// The non-empty cells whose box lies within `r2` of `q`, as (squared distance, cell).
    fn cells_within(&self, q: Vec3, r2: f32, cells: &mut Vec<(f32, u32)>) {
        cells.clear();
        let kc = [0, 1, 2].map(|a| ((q[a] - self.lo[a]) * self.inv_side).floor() as i32);
        let reach = ((r2.sqrt() * self.inv_side).ceil() as i32).max(1);
        for dz in -reach..=reach {
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let n = [kc[0] + dx, kc[1] + dy, kc[2] + dz];
                    if (0..3).any(|a| n[a] < 0 || n[a] >= self.dims[a]) {
                        continue;
                    }
                    let c = self.cell_of_grid
                        [((n[2] * self.dims[1] + n[1]) * self.dims[0] + n[0]) as usize];
                    if c == u32::MAX {
                        continue;
                    }
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
    /// reach of `r2` is searched, nearest first (3×3×3 when `r2` is at most a cell's side
    /// squared: the narrow N; wider for the cell centroids of [`reassign_doubted_wide`]);
    /// `cells` is scratch.
    fn knn_within(
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
            let r = self.cell_start[c as usize] as usize..self.cell_start[c as usize + 1] as usize;
            for (&j, &p) in self.items[r.clone()].iter().zip(&self.pts[r]) {
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
        let r = self.cell_start[c] as usize..self.cell_start[c + 1] as usize;
        for (&j, &p) in self.items[r.clone()].iter().zip(&self.pts[r]) {
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

    #[test]
    fn quantile_takes_the_rounded_rank_and_the_upper_median() {
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert_eq!(quantile(&mut v, 0.5), 3.0);
        assert_eq!(quantile(&mut v, 0.0), 1.0);
        assert_eq!(quantile(&mut v, 1.0), 4.0);
        let mut w: Vec<f32> = (0..201).map(|i| (200 - i) as f32).collect();
        assert_eq!(quantile(&mut w, 0.005), 1.0, "rank round(200 x 0.005) = 1");
    }

    #[test]
    fn nearest_neighbour_index_equals_brute_force() {
        let mut rng = bodyseg_testkit_free_rng(11);
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
        let mut rng = bodyseg_testkit_free_rng(5);
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

    #[test]
    fn wide_vote_relabels_only_the_points_asked_and_counts_every_cell() {
        let torso = Label::from(bodyseg_core::Class::Torso);
        let arm = Label::from(bodyseg_core::Class::UpperArms);
        // A line of 40 arm points 1 cm apart, 3 torso points 5 cm beside its start (another
        // cell), and three noise points (own label unknown) by the torso points: two to
        // relabel, one not.
        let mut pos: Vec<Vec3> = (0..40).map(|i| [i as f32 * 0.01, 0.0, 1.0]).collect();
        let mut labels = vec![arm; 40];
        for j in 0..3 {
            pos.push([0.0, 0.05 + 0.004 * j as f32, 1.0]);
            labels.push(torso);
        }
        for j in 0..3 {
            pos.push([0.001 * j as f32, 0.045, 1.0]);
            labels.push(Label::UNKNOWN);
        }
        let n = pos.len();
        let is_noise: Vec<bool> = (0..n).map(|i| i >= 43).collect();
        let relabel: Vec<bool> = (0..n).map(|i| i >= 44).collect();
        let vote = |k| Vote {
            k,
            radius_m: 0.3,
            self_weight: 1.0,
        };
        // About 40 voters: the whole arm outvotes the 3 torso points.
        let out = reassign_doubted_wide(&pos, &labels, &is_noise, &relabel, None, vote(40));
        assert_eq!(out[43], Label::UNKNOWN, "not asked: unchanged");
        assert_eq!(&out[44..], &[arm, arm]);
        assert_eq!(&out[..43], &labels[..43], "clustered points unchanged");
        // The nearest cell only: the torso points'.
        let out = reassign_doubted_wide(&pos, &labels, &is_noise, &relabel, None, vote(1));
        assert_eq!(&out[44..], &[torso, torso]);
        // The narrow vote asks the same points only: the nearest (torso) within 3 cm.
        let narrow = Vote {
            k: 16,
            radius_m: 0.03,
            self_weight: 1.0,
        };
        let out = reassign_noise_weighted(&pos, &labels, &is_noise, Some(&relabel), None, narrow);
        assert_eq!(out[43], Label::UNKNOWN, "narrow, not asked: unchanged");
        assert_eq!(&out[44..], &[torso, torso]);
        let all = reassign_noise_weighted(&pos, &labels, &is_noise, None, None, narrow);
        assert_eq!(all[43], torso, "narrow, every noise point");
    }

    #[test]
    fn smoothing_gives_islands_to_the_part_around_them_and_never_touches_background() {
        use bodyseg_core::Class;
        let torso = Label::from(Class::Torso);
        let arm = Label::from(Class::UpperArms);
        let leg = Label::from(Class::LowerLegs);
        // A 30 x 30 torso patch, 1 cm apart, holding a 2 x 2 island of upper arm.
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..30 {
            for j in 0..30 {
                pos.push([i as f32 * 0.01, j as f32 * 0.01, 1.0]);
                let island = (14..16).contains(&i) && (14..16).contains(&j);
                labels.push(if island { arm } else { torso });
            }
        }
        // A foot: 6 lower-leg points on a floor of 400 background points, 1 m away from
        // the torso; and an unknown point inside the torso patch.
        for i in 0..20 {
            for j in 0..20 {
                pos.push([3.0 + i as f32 * 0.01, j as f32 * 0.01, 0.0]);
                labels.push(Label::BACKGROUND);
            }
        }
        for k in 0..6 {
            pos.push([3.1 + 0.005 * k as f32, 0.1, 0.005]);
            labels.push(leg);
        }
        pos.push([0.105, 0.105, 1.0]);
        labels.push(Label::UNKNOWN);
        let out = smooth_labels(&pos, &labels, 0.05);
        for (i, (o, l)) in out.iter().zip(&labels).enumerate() {
            if *l == arm {
                assert_eq!(*o, torso, "island point {i} goes to the torso around it");
            } else {
                assert_eq!(o, l, "point {i} ({l:?}) keeps its label");
            }
        }
        // The result does not depend on the order of the points.
        let rev_pos: Vec<Vec3> = pos.iter().rev().copied().collect();
        let rev_labels: Vec<Label> = labels.iter().rev().copied().collect();
        let rev_out: Vec<Label> = smooth_labels(&rev_pos, &rev_labels, 0.05)
            .into_iter()
            .rev()
            .collect();
        assert_eq!(rev_out, out);
        // Off: unchanged.
        assert_eq!(smooth_labels(&pos, &labels, 0.0), labels);
    }

    #[test]
    fn smoothing_skips_only_votes_that_cannot_change_a_label() {
        let mut rng = bodyseg_testkit_free_rng(11);
        let mut moved_cases = 0;
        for case in 0..30 {
            // Parts as slabs along x with islands and strays of other parts, some
            // background and unknown, at several densities and radii.
            let n = 2000 + 397 * case;
            let width = 0.05 + 0.01 * (case % 7) as f32;
            let mut pos = Vec::with_capacity(n);
            let mut labels = Vec::with_capacity(n);
            for _ in 0..n {
                let p = [rng() * 0.6, rng() * 0.3, rng() * 0.2];
                let slab = (p[0] / width) as u8 % 6 + 1;
                let r = rng();
                let id = if r < 0.05 {
                    0
                } else if r < 0.08 {
                    1 + (rng() * 6.0) as u8 % 6
                } else {
                    slab
                };
                pos.push(p);
                labels.push(if r > 0.99 {
                    Label::UNKNOWN
                } else {
                    Label::from_id_or_unknown(id)
                });
            }
            let radius = 0.02 + 0.01 * (case % 5) as f32;
            let fast = smooth_labels_with(&pos, &labels, radius, true);
            let slow = smooth_labels_with(&pos, &labels, radius, false);
            assert_eq!(fast, slow, "case {case}");
            moved_cases += usize::from(slow != labels);
        }
        assert!(
            moved_cases >= 20,
            "the vote moved labels in {moved_cases} of 30 cases"
        );
    }

    #[test]
    fn smoothing_keeps_a_straight_boundary_between_two_parts() {
        let torso = Label::from(bodyseg_core::Class::Torso);
        let arm = Label::from(bodyseg_core::Class::UpperArms);
        // Two halves of a plane: a point's own half always holds the larger vote (the
        // boundary column is nearer its own side's points), so nothing moves.
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..40 {
            for j in 0..20 {
                pos.push([i as f32 * 0.01 + 0.0005, j as f32 * 0.01, 1.0]);
                labels.push(if i < 20 { torso } else { arm });
            }
        }
        let out = smooth_labels(&pos, &labels, 0.05);
        let moved = out.iter().zip(&labels).filter(|(a, b)| a != b).count();
        assert!(moved <= 4, "{moved} points crossed a straight boundary");
    }

    /// A tiny xorshift so this unit test needs no dev-dependency.
    fn bodyseg_testkit_free_rng(seed: u64) -> impl FnMut() -> f32 {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        }
    }
}
