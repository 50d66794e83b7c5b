//! N — reassign_noise (ALGORITHM.md §5.6) and its votes: nearest (the paper), weighted,
//! the parser's probabilities, and the wide vote for doubted labels.

use super::cells::{CellScratch, LabelCells, winner};
use crate::grid::nn::{NnIndex, NnScratch};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, NUM_CLASSES};
use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;

/// N — reassign_noise: every point with `is_noise[i]` takes the label of the nearest point
/// with `!is_noise` (ties: the smaller index), exact nearest neighbour. With no clustered
/// point, noise keeps its label and unknown becomes background.
///
/// Why not a plain ring search or an unbounded k-d tree walk: flying pixels lie far from
/// the body, and searching outward from each costs more than the clustering. `NnIndex` (`grid.rs`)
/// is a two-level grid: blocks of cells, each with the tight bounding box of its points, so
/// a query ranks the few hundred blocks by lower bound and opens only those that can still
/// hold a nearer point — a bounded cost whatever the distance.
pub fn reassign_noise(
    positions_m: &[Vec3],
    labels: &[Label],
    is_noise: &[bool],
    eps_m: f32,
) -> Vec<Label> {
    let nearest = NoiseNearest::new(positions_m, is_noise, eps_m);
    nearest.relabel(labels)
}

/// N's search, done once per clustering: for every noise point, the nearest clustered
/// point ([`reassign_noise`]). The step configurations of one clustering share it (they
/// differ only by the labels they give the clusters); the queries run in parallel.
#[derive(Clone, Debug)]
pub(crate) struct NoiseNearest {
    /// (noise point, its nearest clustered point), in point order; empty when no point is
    /// clustered.
    pairs: Vec<(u32, u32)>,
    /// Noise points with no clustered point to take a label from.
    orphans: Vec<u32>,
}

impl NoiseNearest {
    pub(crate) fn new(positions_m: &[Vec3], is_noise: &[bool], eps_m: f32) -> Self {
        Self::with_index(positions_m, is_noise, eps_m, None)
    }

    /// [`NoiseNearest::with_index`] with the noise read from a clustering's `cluster_of`
    /// (noise: `None`), without a list of flags.
    pub(crate) fn of_clustering(
        positions_m: &[Vec3],
        cluster_of: &[Option<u32>],
        eps_m: f32,
        index: Option<NnIndex>,
    ) -> Self {
        let noise: Vec<u32> = (0..positions_m.len() as u32)
            .filter(|&i| cluster_of[i as usize].is_none())
            .collect();
        Self::with_noise(positions_m, noise, eps_m, index, |i| {
            cluster_of[i as usize].is_some()
        })
    }

    /// [`NoiseNearest::new`] with the index of the clustered points when it was built
    /// already (DBSCAN's cells, [`crate::dbscan::dbscan_with_cells`]): it must hold
    /// exactly the points with `!is_noise`.
    pub(crate) fn with_index(
        positions_m: &[Vec3],
        is_noise: &[bool],
        eps_m: f32,
        index: Option<NnIndex>,
    ) -> Self {
        let noise: Vec<u32> = (0..positions_m.len() as u32)
            .filter(|&i| is_noise[i as usize])
            .collect();
        Self::with_noise(positions_m, noise, eps_m, index, |i| !is_noise[i as usize])
    }

    /// [`NoiseNearest::with_index`] with the noise points listed (`noise`, in point order)
    /// and `clustered(i)` telling the others.
    fn with_noise(
        positions_m: &[Vec3],
        noise: Vec<u32>,
        eps_m: f32,
        index: Option<NnIndex>,
        clustered: impl Fn(u32) -> bool,
    ) -> Self {
        if noise.len() == positions_m.len() {
            return NoiseNearest {
                pairs: Vec::new(),
                orphans: noise,
            };
        }
        let index = index.unwrap_or_else(|| {
            let clustered: Vec<u32> = (0..positions_m.len() as u32)
                .filter(|&i| clustered(i))
                .collect();
            NnIndex::new(positions_m, &clustered, eps_m)
        });
        let pairs: Vec<(u32, u32)> = noise
            .par_iter()
            .with_min_len(256)
            // Each query starts from the answer of the one before it in its run (noise
            // points in point order, i.e. image order, lie near one another): a far
            // query then opens few blocks. The answers do not depend on it.
            .map_init(
                || (NnScratch::default(), None::<u32>),
                |(scratch, last), &i| {
                    let hint = last.map(|j| (j, positions_m[j as usize]));
                    let nearest = index.nearest_from(positions_m[i as usize], hint, scratch);
                    *last = nearest;
                    (i, nearest)
                },
            )
            .filter_map(|(i, j)| j.map(|j| (i, j)))
            .collect();
        NoiseNearest {
            pairs,
            orphans: Vec::new(),
        }
    }

    /// `labels` with every noise point given its nearest clustered point's label (with no
    /// clustered point, unknown becomes background).
    pub(crate) fn relabel(&self, labels: &[Label]) -> Vec<Label> {
        let mut out = labels.to_vec();
        for &(i, j) in &self.pairs {
            out[i as usize] = labels[j as usize];
        }
        for &i in &self.orphans {
            if out[i as usize].is_unknown() {
                out[i as usize] = Label::BACKGROUND;
            }
        }
        out
    }
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
/// than it usually doubts that part go (tuning in `docs/notes/2026-11-30-improved-refinement-tuning.md`).
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
}
