//! Voters counted per label in cells, for the wide votes of N ([`super::reassign_doubted_wide`])
//! and smoothing ([`super::smooth_labels`]).

use crate::grid::CellGrid;
use crate::grid::nn::NnIndex;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, NUM_CLASSES};

/// The class with the largest vote (> 0); ties go to `own`, then to the smaller class id.
pub(super) fn winner(votes: &[f32; NUM_CLASSES], own: Option<usize>) -> Option<usize> {
    let mut best = own;
    for (c, &v) in votes.iter().enumerate() {
        if best.is_none_or(|b| v > votes[b]) && v > 0.0 {
            best = Some(c);
        }
    }
    best
}

/// Cells of a wide vote ([`reassign_doubted_wide`], [`smooth_labels`]) per radius.
pub(super) const WIDE_VOTE_CELLS: f32 = 8.0;

/// Voters counted per label in cells of `radius_m / WIDE_VOTE_CELLS`, for the wide votes:
/// each cell votes from its centroid with its counts, weighing `1 / (1 + (d / radius)²)`.
pub(super) struct LabelCells {
    side_m: f32,
    r2: f32,
    /// Nearest cells asked per vote (about `k` voters); `usize::MAX`: every cell within
    /// the radius.
    k_cells: usize,
    /// Per cell, its voters per class (counts, as f32 to weigh them).
    pub(super) counts: Vec<[f32; NUM_CLASSES]>,
    /// Where each cell votes from: the mean of its voters.
    pub(super) centroids: Vec<Vec3>,
    /// Over the cells' centroids.
    index: NnIndex,
}

/// Buffers reused between [`LabelCells::votes_around`] calls.
#[derive(Default)]
pub(super) struct CellScratch {
    voters: Vec<(f32, u32)>,
    cells: Vec<(f32, u32)>,
}

impl LabelCells {
    /// Counts the labels of `voters` (point indices, at least one) per cell; a vote asks
    /// the nearest cells holding about `k` of them within `radius_m` (`usize::MAX`: all).
    pub(super) fn new(
        positions_m: &[Vec3],
        labels: &[Label],
        voters: &[u32],
        radius_m: f32,
        k: usize,
    ) -> Self {
        let side_m = radius_m / WIDE_VOTE_CELLS;
        let key = |p: Vec3| p.map(|x| (x / side_m).floor() as i32);
        let keys: Vec<[i32; 3]> = voters
            .iter()
            .map(|&i| key(positions_m[i as usize]))
            .collect();
        let grid = CellGrid::new(positions_m, voters, &keys, 0);
        // Cells numbered in the order of their first voter (ties of the votes go to the
        // smaller number, as they always have); each cell's voters in their order.
        let mut order: Vec<u32> = (0..grid.num_cells() as u32).collect();
        order.sort_unstable_by_key(|&c| grid.ids()[grid.range(c).start]);
        let mut sums: Vec<[f64; 3]> = Vec::with_capacity(order.len());
        let mut counts: Vec<[f32; NUM_CLASSES]> = Vec::with_capacity(order.len());
        for &c in &order {
            let r = grid.range(c);
            let mut sum = [0f64; 3];
            let mut count = [0f32; NUM_CLASSES];
            for (&i, p) in grid.ids()[r.clone()].iter().zip(&grid.pts()[r]) {
                for a in 0..3 {
                    sum[a] += f64::from(p[a]);
                }
                if let Some(class) = labels[i as usize].class() {
                    count[usize::from(class.id())] += 1.0;
                }
            }
            sums.push(sum);
            counts.push(count);
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
    pub(super) fn key(&self, p: Vec3) -> [i32; 3] {
        p.map(|x| (x / self.side_m).floor() as i32)
    }

    /// The centre of cell `at`, where its vote is asked from.
    pub(super) fn centre(&self, at: [i32; 3]) -> Vec3 {
        at.map(|x| (x as f32 + 0.5) * self.side_m)
    }

    /// The votes per class of the cells around cell `at`, asked from its centre; `None`
    /// when no cell lies within the radius.
    pub(super) fn votes_around(
        &self,
        at: [i32; 3],
        s: &mut CellScratch,
    ) -> Option<[f32; NUM_CLASSES]> {
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
