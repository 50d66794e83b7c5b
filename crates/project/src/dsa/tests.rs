//! Unit tests of `dsa`.

use super::*;

/// The pixels of the square of radius `r` around `pixel` (row-major index in a
/// `w × h` image), clipped to the image, without `pixel` itself: the brute-force
/// reference of the window tests.
fn window(pixel: usize, w: usize, h: usize, r: usize) -> impl Iterator<Item = usize> {
    let (u, v) = (pixel % w, pixel / w);
    let (u0, u1) = (u.saturating_sub(r), (u + r).min(w - 1));
    let (v0, v1) = (v.saturating_sub(r), (v + r).min(h - 1));
    (v0..=v1)
        .flat_map(move |vn| (u0..=u1).map(move |un| vn * w + un))
        .filter(move |&p| p != pixel)
}

/// xorshift64*, seeded: the brute-force comparisons below are deterministic.
type Rng = bodyseg_core::rng::XorShift64Star;

#[test]
fn zbuffer_is_the_nearest_point_within_the_radius() {
    let mut rng = Rng::new(0x5EED_0001);
    // One buffer for both radii: it must come back all +∞.
    let mut buffer = Vec::new();
    for r in [1, 2] {
        let n = 400;
        let hits = Hits {
            u: (0..n)
                .map(|i| {
                    if i % 17 == 0 {
                        NO_HIT
                    } else {
                        10 + rng.below(30) as u32
                    }
                })
                .collect(),
            v: (0..n).map(|_| 5 + rng.below(20) as u32).collect(),
            z_color_m: (0..n)
                .map(|_| 0.5 + rng.below(1000) as f32 / 250.0)
                .collect(),
        };
        let color = bodyseg_calib::Intrinsics::pinhole(50, 30, 1.0, 1.0, 0.0, 0.0);
        let zb = ZBuffer::splat(hits.view(), r, &color, &mut buffer);
        for i in 0..n {
            let (u, v) = (hits.u[i], hits.v[i]);
            if u == NO_HIT {
                continue;
            }
            let want = (0..n)
                .filter(|&j| {
                    hits.u[j] != NO_HIT
                        && hits.u[j].abs_diff(u) as usize <= r
                        && hits.v[j].abs_diff(v) as usize <= r
                })
                .map(|j| hits.z_color_m[j])
                .fold(f32::INFINITY, f32::min);
            assert_eq!(zb.at(u, v), want, "({u}, {v}) r {r}");
        }
        drop(zb);
        assert!(
            buffer.iter().all(|&z| z == f32::INFINITY),
            "r {r}: buffer not reset"
        );
    }
}

#[test]
fn label_change_tests_match_brute_force() {
    let mut rng = Rng::new(0x5EED_0002);
    let (w, h) = (61, 43);
    // Blobs of a few labels: uniform blocks, borders, and blocks cut by the edges.
    let mut image = vec![Label::BACKGROUND; w * h];
    for _ in 0..12 {
        let (cu, cv, rad) = (
            rng.below(w as u64) as usize,
            rng.below(h as u64) as usize,
            2 + rng.below(9) as usize,
        );
        let l = Label::from_id(rng.below(3) as u8).expect("a class");
        for v in cv.saturating_sub(rad)..(cv + rad).min(h) {
            for u in cu.saturating_sub(rad)..(cu + rad).min(w) {
                image[v * w + u] = l;
            }
        }
    }
    let blocks = UniformBlocks::new(&image, w, h);
    for r in [1, 2, 3, 5] {
        for v in 0..h {
            for u in 0..w {
                let own = image[v * w + u];
                let want = window(v * w + u, w, h, r).any(|n| image[n] != own);
                let exact = square_holds_other(&image, w, h, (u, v), r, own);
                assert_eq!(exact, want, "({u}, {v}) r {r}");
                // The block test never misses a change.
                assert!(
                    blocks.may_hold_other(u, v, r, own) || !want,
                    "({u}, {v}) r {r}"
                );
            }
        }
    }
}

#[test]
fn edge_map_matches_the_per_pixel_test() {
    let mut rng = Rng::new(0x5EED_0003);
    let (w, h) = (37, 29);
    let mut camera = RgbdCamera::new(
        "e",
        bodyseg_calib::Intrinsics::pinhole(w as u32, h as u32, 30.0, 30.0, 18.0, 14.0),
        bodyseg_calib::Intrinsics::pinhole(74, 58, 60.0, 60.0, 37.0, 29.0),
    );
    camera.depth_shift_mm = -300.0;
    let lut = depth_lut(&camera);
    // Depths from 0 (none) over values ≤ the shift (none) to far, with jumps.
    let raw: Vec<u16> = (0..w * h)
        .map(|_| match rng.below(10) {
            0 => 0,
            1 => 200,
            2..=5 => 1000 + rng.below(40) as u16,
            _ => 1500 + rng.below(400) as u16,
        })
        .collect();
    for r in [1, 2] {
        let got = edge_map(&raw, &lut, w, h, r, 0.05);
        for p in 0..w * h {
            let z = lut[usize::from(raw[p])];
            let want = !z.is_nan()
                && window(p, w, h, r).any(|n| {
                    let zn = lut[usize::from(raw[n])];
                    !zn.is_nan() && (zn - z).abs() > 0.05 * z
                });
            assert_eq!(got[p], want, "pixel {p} r {r}");
        }
    }
}

#[test]
fn window_is_clipped_and_excludes_the_centre() {
    // 4×3 image; pixel (0, 0) has 3 neighbours, (1, 1) has 8.
    let mut corner: Vec<usize> = grid_neighbours(0, 4, 3, 1).collect();
    corner.sort_unstable();
    assert_eq!(corner, [1, 4, 5]);
    let mut inner: Vec<usize> = grid_neighbours(5, 4, 3, 1).collect();
    inner.sort_unstable();
    assert_eq!(inner, [0, 1, 2, 4, 6, 8, 9, 10]);
    // Step 2 on a 5×5 image from the centre (2, 2): the corners and edge midpoints.
    let mut coarse: Vec<usize> = grid_neighbours(12, 5, 5, 2).collect();
    coarse.sort_unstable();
    assert_eq!(coarse, [0, 2, 4, 10, 14, 20, 22, 24]);
    // From (1, 1) with step 2 only the points inside the image remain.
    let mut clipped: Vec<usize> = grid_neighbours(6, 5, 5, 2).collect();
    clipped.sort_unstable();
    assert_eq!(clipped, [8, 16, 18]);
    // The same squares as row segments, centre included.
    let rows = |pixel, r| {
        let mut out = Vec::new();
        any_row_in_square(pixel, 4, 3, r, |row| {
            out.push(row);
            false
        });
        out
    };
    assert_eq!(rows(0, 1), [0..2, 4..6]);
    assert_eq!(rows(5, 1), [0..3, 4..7, 8..11]);
    assert_eq!(rows(11, 2), [1..4, 5..8, 9..12]);
}
