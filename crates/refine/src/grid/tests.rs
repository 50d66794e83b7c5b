//! Property tests of the grid against brute force.

use super::nn::NnIndex;
use super::*;
use bodyseg_core::math::dist2;

/// Uniform draws in [0, 1) from core's xorshift64*; the seed is printed by every
/// assertion message (`case`), and fixed so that a failure reproduces.
pub(crate) fn rng_from(seed: u64) -> impl FnMut() -> f32 {
    let mut g = bodyseg_core::rng::XorShift64Star::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    move || (g.next_u64() >> 40) as f32 / (1u64 << 24) as f32
}

/// Random points: a cluttered box, sometimes with a few far strays (kilometres away:
/// the hashed look-up) or many duplicates.
fn cloud(rng: &mut impl FnMut() -> f32, case: usize) -> Vec<Vec3> {
    let n = 1 + (case * 53) % 700;
    let mut pos: Vec<Vec3> = (0..n)
        .map(|_| [rng() * 0.6, rng() * 0.4, rng() * 0.3])
        .collect();
    if case % 5 == 1 {
        pos.push([3_000.0, -2_000.0, 1.0]);
        pos.push([-120_000.0, 120_000.0, -120_000.0]);
    }
    if case % 7 == 3 {
        let p = pos[0];
        pos.extend(std::iter::repeat_n(p, 50));
    }
    pos
}

#[test]
fn the_grid_holds_every_point_once_in_its_cell_and_finds_every_cell() {
    let mut rng = rng_from(3);
    for case in 0..60 {
        let pos = cloud(&mut rng, case);
        let ids: Vec<u32> = (0..pos.len() as u32).filter(|i| i % 3 != 1).collect();
        // Relative cells (tiny to coarse), and absolute ones as the votes use them.
        let side = [1e-9, 0.003, 0.02, 0.3][case % 4];
        let frame = GridFrame::covering(&pos, &ids, side);
        let keys: Vec<[i32; 3]> = if case % 2 == 0 {
            ids.iter().map(|&i| frame.key(pos[i as usize])).collect()
        } else {
            let s = side as f32;
            ids.iter()
                .map(|&i| pos[i as usize].map(|x| (x / s).floor() as i32))
                .collect()
        };
        let grid = CellGrid::new(&pos, &ids, &keys, 2);
        let mut seen = vec![0usize; pos.len()];
        let mut prev: Option<[i32; 3]> = None;
        for c in 0..grid.num_cells() as u32 {
            let k = grid.key(c);
            assert!(
                prev.is_none_or(|p| (p[2], p[1], p[0]) < (k[2], k[1], k[0])),
                "case {case}: cells in key order"
            );
            prev = Some(k);
            assert_eq!(grid.cell(k), Some(c), "case {case}: look-up");
            let r = grid.range(c);
            assert!(!r.is_empty());
            for n in r.clone() {
                let id = grid.ids()[n];
                seen[id as usize] += 1;
                assert_eq!(grid.pts()[n], pos[id as usize]);
                let want = keys[ids.iter().position(|&i| i == id).unwrap_or(0)];
                assert_eq!(want, k, "case {case}: point {id} in its cell");
            }
            // Within a cell, the order of `ids`.
            assert!(grid.ids()[r].windows(2).all(|w| w[0] < w[1]));
        }
        for (i, &s) in seen.iter().enumerate() {
            assert_eq!(
                s,
                usize::from(ids.contains(&(i as u32))),
                "case {case}: {i}"
            );
        }
        // Keys of no point: none, near and far (the padded border, the hashed map).
        for k in [[-5, 0, 0], [i32::MAX, i32::MIN, 0], [1 << 29, 0, 3]] {
            if !keys.contains(&k) {
                assert_eq!(grid.cell(k), None, "case {case}: {k:?}");
            }
        }
        // Neighbours through offsets equal neighbours through keys.
        let offsets: Vec<[i32; 3]> = (-2..=2)
            .flat_map(|z| (-2..=2).flat_map(move |y| (-2..=2).map(move |x| [x, y, z])))
            .collect();
        let offs = grid.offsets(&offsets);
        for c in 0..grid.num_cells() as u32 {
            let at = grid.anchor(c);
            let k = grid.key(c);
            for (o, d) in offsets.iter().enumerate() {
                let want = grid.cell([k[0] + d[0], k[1] + d[1], k[2] + d[2]]);
                assert_eq!(grid.near_cell(at, &offs, o), want, "case {case}");
            }
        }
    }
}

#[test]
fn a_frame_never_overflows_and_keeps_its_side_when_it_can() {
    let pos = vec![
        [-3.0e38f32, 0.0, 1.0],
        [3.0e38, 1e-30, -1.0],
        [0.0, 0.0, 0.0],
    ];
    let ids = [0u32, 1, 2];
    let f = GridFrame::covering(&pos, &ids, 1e-12);
    assert!(f.side_m() >= 6.0e38 / MAX_CELLS_PER_AXIS);
    let keys: Vec<[i32; 3]> = pos.iter().map(|&p| f.key(p)).collect();
    assert_eq!(keys[0][0], 0);
    assert!(keys[1][0] > 0 && f64::from(keys[1][0]) <= MAX_CELLS_PER_AXIS);
    let grid = CellGrid::new(&pos, &ids, &keys, 2);
    assert_eq!(grid.num_cells(), 3);
    // A small extent keeps the asked side.
    let near = vec![[0.0f32, 0.0, 0.0], [1.0, 2.0, 3.0]];
    let f = GridFrame::covering(&near, &[0, 1], 0.01);
    assert_eq!(f.side_m(), 0.01);
    assert_eq!(f.key([1.0, 2.0, 3.0]), [100, 200, 300]);
    // A point outside the frame gets the nearest border cell.
    assert_eq!(f.key([-7.0, 99.0, 1.5]), [0, 200, 150]);
}

#[test]
fn radius_queries_equal_brute_force() {
    let mut rng = rng_from(7);
    for case in 0..40 {
        let pos = cloud(&mut rng, case);
        let idx: Vec<u32> = (0..pos.len() as u32).filter(|i| i % 4 != 0).collect();
        if idx.is_empty() {
            continue;
        }
        let index = NnIndex::new(&pos, &idx, 0.05);
        let mut cells = Vec::new();
        for _ in 0..20 {
            let q = [rng() * 0.8 - 0.1, rng() * 0.6 - 0.1, rng() * 0.5 - 0.1];
            for r in [0.0, 0.01, 0.05, 0.13, 1e3, f32::INFINITY] {
                let r2 = r * r;
                let mut want: Vec<(f32, u32)> = idx
                    .iter()
                    .map(|&j| (dist2(q, pos[j as usize]), j))
                    .filter(|&(d2, _)| d2 <= r2)
                    .collect();
                want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let mut got = Vec::new();
                index.for_each_within(q, r2, &mut cells, |d2, j| got.push((d2, j)));
                got.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                assert_eq!(got, want, "case {case}, r {r}");
            }
        }
    }
}

#[test]
fn nearest_neighbour_index_equals_brute_force() {
    let mut rng = rng_from(11);
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
    let mut rng = rng_from(5);
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
fn nearest_on_dbscan_cells_equals_brute_force() {
    use crate::dbscan::{DbscanParams, dbscan_with_cells};
    use bodyseg_core::Label;
    let mut rng = rng_from(13);
    for case in 0..60 {
        // Blobs of a few labels (clustered), scattered strays (noise), duplicates (ties),
        // some unknown points (never clustered).
        let n = 50 + (case * 41) % 900;
        let mut pos: Vec<Vec3> = Vec::with_capacity(n);
        let mut labels: Vec<Label> = Vec::with_capacity(n);
        for i in 0..n {
            let blob = i % 4;
            let c = [
                0.2 * blob as f32,
                0.1 * (blob % 2) as f32,
                0.05 * blob as f32,
            ];
            let spread = if rng() < 0.1 { 0.8 } else { 0.06 };
            pos.push([
                c[0] + rng() * spread,
                c[1] + rng() * spread,
                c[2] + rng() * spread,
            ]);
            labels.push(if rng() < 0.05 {
                Label::UNKNOWN
            } else {
                Label::from_id(1 + (i % 3) as u8).expect("a class id")
            });
        }
        if case % 4 == 1 {
            let p = pos[3];
            pos.extend(std::iter::repeat_n(p, 20));
            labels.extend(std::iter::repeat_n(labels[3], 20));
        }
        let params = DbscanParams {
            eps_m: [0.02, 0.05, 0.08][case % 3],
            min_points: 2 + case % 6,
            label_penalty_m: if case % 5 == 2 { 0.01 } else { f32::INFINITY },
        };
        let (clustering, index) = dbscan_with_cells(&pos, &labels, &params, true);
        let Some(index) = index else {
            panic!("case {case}: a small cloud's frame makes the index");
        };
        let clustered: Vec<u32> = (0..pos.len() as u32)
            .filter(|&i| clustering.cluster_of[i as usize].is_some())
            .collect();
        let mut queries: Vec<Vec3> = (0..pos.len())
            .filter(|&i| clustering.cluster_of[i].is_none())
            .map(|i| pos[i])
            .collect();
        queries.extend((0..20).map(|_| [rng() * 2.0 - 0.5, rng() * 2.0 - 0.5, rng() * 2.0 - 0.5]));
        queries.extend(pos.iter().step_by(7).copied());
        for q in queries {
            let want = clustered.iter().copied().min_by(|&a, &b| {
                dist2(q, pos[a as usize])
                    .total_cmp(&dist2(q, pos[b as usize]))
                    .then(a.cmp(&b))
            });
            assert_eq!(index.nearest(q), want, "case {case}, query {q:?}");
            // Any indexed point as the starting hint (near, far, the answer itself) gives
            // the same answer.
            if !clustered.is_empty() {
                let mut scratch = crate::grid::nn::NnScratch::default();
                let pick = clustered[(rng() * clustered.len() as f32) as usize % clustered.len()];
                for hint in [Some(pick), want] {
                    let hint = hint.map(|j| (j, pos[j as usize]));
                    assert_eq!(
                        index.nearest_from(q, hint, &mut scratch),
                        want,
                        "case {case}, query {q:?}, hint {hint:?}"
                    );
                }
            }
        }
    }
}
