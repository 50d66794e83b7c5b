//! Box fitting (extent along the principal horizontal axis) and oriented-box IoU.

use bodyseg_core::PersonBox;

/// The yaw of the principal horizontal axis of `xy` (2×2 covariance), radians in
/// (-π/2, π/2].
pub(crate) fn principal_yaw(xy: &[[f32; 2]]) -> f32 {
    let n = xy.len().max(1) as f64;
    let (mut mx, mut my) = (0.0f64, 0.0f64);
    for p in xy {
        mx += f64::from(p[0]);
        my += f64::from(p[1]);
    }
    mx /= n;
    my /= n;
    let (mut sxx, mut syy, mut sxy) = (0.0f64, 0.0f64, 0.0f64);
    for p in xy {
        let dx = f64::from(p[0]) - mx;
        let dy = f64::from(p[1]) - my;
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    (0.5 * (2.0 * sxy).atan2(sxx - syy)) as f32
}

/// The box around `xy` aligned with `yaw`: horizontal extent plus `margin_m` on each
/// side; vertically from `floor_z_m` to `top_z_m + margin_m`.
pub(crate) fn fit_box(
    id: u32,
    xy: &[[f32; 2]],
    yaw: f32,
    floor_z_m: f32,
    top_z_m: f32,
    margin_m: f32,
) -> PersonBox {
    let (s, c) = yaw.sin_cos();
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for p in xy {
        let u = c * p[0] + s * p[1];
        let v = -s * p[0] + c * p[1];
        lo[0] = lo[0].min(u);
        hi[0] = hi[0].max(u);
        lo[1] = lo[1].min(v);
        hi[1] = hi[1].max(v);
    }
    let cu = (lo[0] + hi[0]) / 2.0;
    let cv = (lo[1] + hi[1]) / 2.0;
    let bottom = floor_z_m.min(top_z_m);
    let top = top_z_m + margin_m;
    PersonBox {
        id,
        center_m: [c * cu - s * cv, s * cu + c * cv, (bottom + top) / 2.0],
        half_extents_m: [
            (hi[0] - lo[0]) / 2.0 + margin_m,
            (hi[1] - lo[1]) / 2.0 + margin_m,
            ((top - bottom) / 2.0).max(1e-3),
        ],
        yaw_rad: yaw,
    }
}

/// The four corners of a box's footprint, counter-clockwise seen from above.
fn footprint(b: &PersonBox) -> [[f64; 2]; 4] {
    let (s, c) = f64::from(b.yaw_rad).sin_cos();
    let [hx, hy, _] = b.half_extents_m.map(f64::from);
    let [cx, cy, _] = b.center_m.map(f64::from);
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(a, b)| {
        let (u, v) = (a * hx, b * hy);
        [cx + c * u - s * v, cy + s * u + c * v]
    })
}

/// Area of a simple polygon (shoelace), m².
fn area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let mut twice = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        twice += p[0] * q[1] - q[0] * p[1];
    }
    (twice / 2.0).abs()
}

/// Intersection of two convex counter-clockwise polygons (Sutherland–Hodgman).
fn clip(subject: &[[f64; 2]], clipper: &[[f64; 2]; 4]) -> Vec<[f64; 2]> {
    let mut out = subject.to_vec();
    for i in 0..4 {
        let (a, b) = (clipper[i], clipper[(i + 1) % 4]);
        let side = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let input = std::mem::take(&mut out);
        let n = input.len();
        for k in 0..n {
            let (p, q) = (input[k], input[(k + 1) % n]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

/// Intersection over union of two boxes (yawed about z), computed exactly: footprint
/// polygon intersection times the overlap in z. 0 when either box is degenerate.
pub fn box_iou(a: &PersonBox, b: &PersonBox) -> f32 {
    let vol = |x: &PersonBox| {
        8.0 * x
            .half_extents_m
            .iter()
            .map(|&h| f64::from(h.max(0.0)))
            .product::<f64>()
    };
    let (va, vb) = (vol(a), vol(b));
    if va <= 0.0 || vb <= 0.0 {
        return 0.0;
    }
    let z_lo = f64::from(a.center_m[2] - a.half_extents_m[2])
        .max(f64::from(b.center_m[2] - b.half_extents_m[2]));
    let z_hi = f64::from(a.center_m[2] + a.half_extents_m[2])
        .min(f64::from(b.center_m[2] + b.half_extents_m[2]));
    if z_hi <= z_lo {
        return 0.0;
    }
    let inter = area(&clip(&footprint(a), &footprint(b))) * (z_hi - z_lo);
    (inter / (va + vb - inter)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(center: [f32; 3], half: [f32; 3], yaw: f32) -> PersonBox {
        PersonBox {
            id: 0,
            center_m: center,
            half_extents_m: half,
            yaw_rad: yaw,
        }
    }

    #[test]
    fn iou_of_known_cases() {
        let a = b([0.0, 0.0, 1.0], [0.5, 0.5, 1.0], 0.0);
        assert!((box_iou(&a, &a) - 1.0).abs() < 1e-6);
        // Half overlap along x: inter 1/2 of each, IoU = 0.5 / 1.5.
        let s = b([0.5, 0.0, 1.0], [0.5, 0.5, 1.0], 0.0);
        assert!((box_iou(&a, &s) - 1.0 / 3.0).abs() < 1e-5);
        // A square turned by 90° is the same box.
        let r = b(
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 1.0],
            std::f32::consts::FRAC_PI_2,
        );
        assert!((box_iou(&a, &r) - 1.0).abs() < 1e-5);
        assert_eq!(box_iou(&a, &b([5.0, 0.0, 1.0], [0.5, 0.5, 1.0], 0.3)), 0.0);
    }

    #[test]
    fn iou_matches_dense_sampling() {
        // Reference: a 200×200×50 grid over the union's bounding region; with ~2M cells
        // the sampled IoU is within 0.01 of the exact value.
        let a = b([0.1, 0.2, 0.9], [0.4, 0.25, 0.9], 0.4);
        let c = b([0.3, 0.1, 1.0], [0.3, 0.35, 0.8], -0.7);
        let (mut ia, mut ic, mut both) = (0usize, 0usize, 0usize);
        let (ta, tc) = (a.test(), c.test());
        let n = 200;
        for i in 0..n {
            for j in 0..n {
                for k in 0..50 {
                    let p = [
                        -0.6 + 1.4 * (i as f32 + 0.5) / n as f32,
                        -0.6 + 1.4 * (j as f32 + 0.5) / n as f32,
                        2.0 * (k as f32 + 0.5) / 50.0,
                    ];
                    let (x, y) = (ta.contains(p), tc.contains(p));
                    ia += usize::from(x);
                    ic += usize::from(y);
                    both += usize::from(x && y);
                }
            }
        }
        let sampled = both as f32 / (ia + ic - both) as f32;
        let exact = box_iou(&a, &c);
        assert!((sampled - exact).abs() < 0.01, "{sampled} vs {exact}");
        assert!(exact > 0.1);
    }

    #[test]
    fn fit_box_covers_its_points() {
        let xy = [[0.0, 0.0], [1.0, 1.0], [0.9, 1.1], [0.1, -0.1]];
        let yaw = principal_yaw(&xy);
        // The points lie along the diagonal, slightly turned towards y: atan2 gives 0.886.
        assert!((yaw - 0.886).abs() < 1e-3, "{yaw}");
        let bx = fit_box(3, &xy, yaw, 0.0, 1.7, 0.05);
        for p in xy {
            assert!(bx.contains([p[0], p[1], 1.0]));
        }
        // Floor to top + margin; tolerance: f32 rounding.
        assert!((bx.center_m[2] - bx.half_extents_m[2]).abs() < 1e-6);
        assert!((bx.center_m[2] + bx.half_extents_m[2] - 1.75).abs() < 1e-5);
    }
}
