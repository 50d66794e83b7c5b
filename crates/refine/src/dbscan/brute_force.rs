//! The O(n²) reference DBSCAN: the oracle of the property tests (moved out of `dbscan.rs`
//! to keep that file under the 1000-line limit).

use super::group::{Clustering, DbscanParams};
use super::group::{GroupResult, Thresholds, assemble};
use bodyseg_core::Label;
use bodyseg_core::math::{Vec3, dist2};
use rustc_hash::FxHashMap;

/// Reference DBSCAN with the same definitions, O(n²): the oracle of the property tests.
pub fn dbscan_brute_force(
    positions_m: &[Vec3],
    labels: &[Label],
    params: &DbscanParams,
) -> Clustering {
    let n = positions_m.len();
    let th = Thresholds::new(params);
    let ok = |i: usize| !labels[i].is_unknown();
    let nb =
        |i: usize, j: usize| dist2(positions_m[i], positions_m[j]) <= th.get(labels[i], labels[j]);
    let is_core: Vec<bool> = (0..n)
        .map(|i| ok(i) && (0..n).filter(|&j| ok(j) && nb(i, j)).count() >= params.min_points)
        .collect();
    // Components of core points by flood fill.
    let mut root = vec![u32::MAX; n];
    for s in 0..n {
        if !is_core[s] || root[s] != u32::MAX {
            continue;
        }
        root[s] = s as u32;
        let mut stack = vec![s];
        while let Some(i) = stack.pop() {
            for j in 0..n {
                if is_core[j] && root[j] == u32::MAX && nb(i, j) {
                    root[j] = s as u32;
                    stack.push(j);
                }
            }
        }
    }
    let mut comp = root.clone();
    for i in 0..n {
        if is_core[i] || !ok(i) {
            continue;
        }
        let mut best: Option<(f32, usize)> = None;
        for j in 0..n {
            if is_core[j] && nb(i, j) {
                let d2 = dist2(positions_m[i], positions_m[j]);
                if best.is_none_or(|(b2, bj)| d2 < b2 || (d2 == b2 && j < bj)) {
                    best = Some((d2, j));
                }
            }
        }
        if let Some((_, j)) = best {
            comp[i] = root[j];
        }
    }
    let idx: Vec<u32> = (0..n as u32).collect();
    let mut dense: FxHashMap<u32, u32> = FxHashMap::default();
    let component: Vec<Option<u32>> = comp
        .iter()
        .map(|&r| {
            (r != u32::MAX).then(|| {
                let next = dense.len() as u32;
                *dense.entry(r).or_insert(next)
            })
        })
        .collect();
    // Each component's smallest point index: its first point (points in index order).
    let mut first = vec![u32::MAX; dense.len()];
    for (i, c) in component.iter().enumerate() {
        if let Some(c) = c {
            first[*c as usize] = first[*c as usize].min(i as u32);
        }
    }
    let res = GroupResult {
        ids: idx,
        component,
        first,
        is_core,
        grid: None,
    };
    assemble(n, labels, &[res], false)
}
