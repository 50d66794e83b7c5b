//! Pairing by stamp: a camera's depth and colour images, then the cameras' pairs into
//! frames, each within a largest skew.
//!
//! Both steps are one-to-one and greedy on the time difference: every pair within the
//! skew is sorted by |Δt|, and a pair is taken when neither of its items is taken yet.
//! Ties break on the earlier index, so the result does not depend on the order messages
//! were recorded in.

/// Pairs of indices `(i, j)` of `a` and `b` (both sorted ascending, nanoseconds) whose
/// stamps differ by at most `max_skew_ns`, one-to-one, sorted by `i`.
pub fn pair_nearest(a: &[i64], b: &[i64], max_skew_ns: i64) -> Vec<(usize, usize)> {
    // Every pair within the skew (a few per item at camera rates).
    let mut candidates: Vec<(i64, usize, usize)> = Vec::new();
    for (i, &t) in a.iter().enumerate() {
        let lo = b.partition_point(|&s| s < t.saturating_sub(max_skew_ns));
        for (j, &s) in b.iter().enumerate().skip(lo) {
            if s > t.saturating_add(max_skew_ns) {
                break;
            }
            candidates.push(((s - t).abs(), i, j));
        }
    }
    one_to_one(candidates, a.len(), b.len())
}

/// The greedy one-to-one choice among `candidates` `(|Δt|, i, j)` (`i < len_a`,
/// `j < len_b`): smallest |Δt| first, ties on the earlier indices; sorted by `i`.
fn one_to_one(
    mut candidates: Vec<(i64, usize, usize)>,
    len_a: usize,
    len_b: usize,
) -> Vec<(usize, usize)> {
    candidates.sort_unstable();
    let mut used_a = vec![false; len_a];
    let mut used_b = vec![false; len_b];
    let mut pairs = Vec::new();
    for (_, i, j) in candidates {
        if !used_a[i] && !used_b[j] {
            used_a[i] = true;
            used_b[j] = true;
            pairs.push((i, j));
        }
    }
    pairs.sort_unstable();
    pairs
}

/// Groups of one item per camera (`stamps[c]` sorted ascending, nanoseconds) whose stamps
/// all lie within `max_skew_ns` of the first camera's: `groups[k][c]` is camera `c`'s
/// index in group `k`, groups in stamp order. Each camera's item joins at most one group.
pub fn group_cameras(stamps: &[Vec<i64>], max_skew_ns: i64) -> Vec<Vec<usize>> {
    let Some((first, others)) = stamps.split_first() else {
        return Vec::new();
    };
    // For each other camera, its one-to-one partner of each of the first camera's items.
    let partners: Vec<Vec<Option<usize>>> = others
        .iter()
        .map(|s| {
            let mut of_first = vec![None; first.len()];
            for (i, j) in pair_nearest(first, s, max_skew_ns) {
                of_first[i] = Some(j);
            }
            of_first
        })
        .collect();
    (0..first.len())
        .filter_map(|i| {
            let mut group = vec![i];
            for p in &partners {
                group.push(p[i]?);
            }
            Some(group)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force, written apart from the code under test: over all pairs of the two
    /// streams, repeatedly take the free pair of smallest (|Δt|, i, j) by a full scan
    /// (no window, no sort), until no free pair lies within the skew.
    fn brute(a: &[i64], b: &[i64], skew: i64) -> Vec<(usize, usize)> {
        let (mut used_a, mut used_b) = (vec![false; a.len()], vec![false; b.len()]);
        let mut pairs = Vec::new();
        loop {
            let mut best: Option<(i64, usize, usize)> = None;
            for (i, x) in a.iter().enumerate().filter(|&(i, _)| !used_a[i]) {
                for (j, y) in b.iter().enumerate().filter(|&(j, _)| !used_b[j]) {
                    let d = (x - y).abs();
                    if d <= skew && best.is_none_or(|b| (d, i, j) < b) {
                        best = Some((d, i, j));
                    }
                }
            }
            let Some((_, i, j)) = best else { break };
            used_a[i] = true;
            used_b[j] = true;
            pairs.push((i, j));
        }
        pairs.sort_unstable();
        pairs
    }

    #[test]
    fn pairs_are_nearest_within_the_skew_and_one_to_one() {
        // 30 fps depth, colour 5 ms later, one colour frame dropped, one extra.
        let a: Vec<i64> = (0..6).map(|i| i * 33_000_000).collect();
        let mut b: Vec<i64> = a.iter().map(|t| t + 5_000_000).collect();
        b.remove(3);
        b.push(400_000_000);
        let pairs = pair_nearest(&a, &b, 20_000_000);
        assert_eq!(pairs, [(0, 0), (1, 1), (2, 2), (4, 3), (5, 4)]);
        assert_eq!(pairs, brute(&a, &b, 20_000_000));
        assert!(pair_nearest(&a, &b, 1_000_000).is_empty());
    }

    #[test]
    fn pairing_matches_the_brute_force_on_jittered_streams() {
        // A seeded LCG: jittered 30 fps streams with drops.
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = |m: u64| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 33) % m
        };
        for round in 0..200 {
            let stream = |next: &mut dyn FnMut(u64) -> u64| -> Vec<i64> {
                let mut v = Vec::new();
                for i in 0..40 {
                    if next(10) > 0 {
                        v.push(i * 33_333_333 + next(30_000_000) as i64);
                    }
                }
                v.sort_unstable();
                v
            };
            let a = stream(&mut next);
            let b = stream(&mut next);
            let got = pair_nearest(&a, &b, 20_000_000);
            assert_eq!(got, brute(&a, &b, 20_000_000), "round {round}");
        }
    }

    #[test]
    fn cameras_group_around_the_first_cameras_stamps() {
        let cam0 = vec![0, 100, 200];
        let cam1 = vec![3, 104, 260];
        let cam2 = vec![-2, 98, 201];
        let groups = group_cameras(&[cam0, cam1, cam2], 10);
        assert_eq!(groups, [vec![0, 0, 0], vec![1, 1, 1]]);
        assert!(group_cameras(&[], 10).is_empty());
        assert_eq!(group_cameras(&[vec![5, 6]], 0), [vec![0], vec![1]]);
    }
}
