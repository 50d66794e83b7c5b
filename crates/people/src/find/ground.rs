//! The ground plane: heights above it, horizontal distances along it, and its RANSAC fit
//! (Fischler & Bolles 1981) among voxel centres (geometry mode).
//!
//! Self-contained (nothing here reads the box finder's configuration), so that the fit can
//! grow without touching the finders: today the floor is near-horizontal in a z-up frame.

use bodyseg_core::math::{Vec3, cross, dot, norm, sub};
use bodyseg_core::rng::SplitMix64;

/// Ground plane `n·p + d = 0`, `n` unit with `n.z > 0`: height of `p` is `n·p + d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plane {
    /// Unit normal, pointing up (`n.z > 0`).
    n: Vec3,
    /// Offset, metres: the height of the origin is `d`.
    d: f32,
}

impl Plane {
    /// The floor of bodyseg's world frame, z = 0.
    pub(crate) const FLOOR: Plane = Plane {
        n: [0.0, 0.0, 1.0],
        d: 0.0,
    };

    /// The horizontal plane z = `z_m`.
    pub(crate) fn level_at(z_m: f32) -> Plane {
        Plane {
            n: [0.0, 0.0, 1.0],
            d: -z_m,
        }
    }

    /// Height of `p` above the plane, metres (negative below it).
    pub(crate) fn height(&self, p: Vec3) -> f32 {
        self.n[0] * p[0] + self.n[1] * p[1] + self.n[2] * p[2] + self.d
    }

    /// z of the plane at (x, y), metres.
    pub(crate) fn z_at(&self, x: f32, y: f32) -> f32 {
        -(self.n[0] * x + self.n[1] * y + self.d) / self.n[2]
    }
}

/// Horizontal distance of two points (along the floor of the z-up world frame), metres.
pub(crate) fn xy_dist(a: Vec3, b: Vec3) -> f32 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// RANSAC ground plane among `points` (world frame, metres): of `iterations` planes
/// through three points drawn with a fixed seed (deterministic), the near-horizontal one
/// (normal within `max_tilt_deg` of +z) with the most points within `tol_m` of it; `None`
/// when no sample gives such a plane (fewer than three points, all of them on a line, or
/// no near-horizontal triple).
pub(crate) fn fit_ground(
    points: &[Vec3],
    tol_m: f32,
    max_tilt_deg: f32,
    iterations: usize,
) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    let min_nz = max_tilt_deg.to_radians().cos();
    let mut rng = SplitMix64::new(0x6A09_E667_F3BC_C908);
    let mut best: Option<(usize, Plane)> = None;
    // Score on a strided subset: the count only ranks planes.
    let stride = (points.len() / 4000).max(1);
    for _ in 0..iterations {
        let [a, b, c] = [0; 3].map(|_| points[rng.below(points.len() as u64) as usize]);
        let mut n = cross(sub(b, a), sub(c, a));
        let len = norm(n);
        if len.is_nan() || len <= 1e-9 {
            continue;
        }
        if n[2] < 0.0 {
            n = n.map(|x| -x);
        }
        n = n.map(|x| x / len);
        if n[2] < min_nz {
            continue;
        }
        let plane = Plane { n, d: -dot(n, a) };
        let count = points
            .iter()
            .step_by(stride)
            .filter(|&&p| plane.height(p).abs() <= tol_m)
            .count();
        // The floor has the most points; a table top or a box lid far fewer.
        let better = best.is_none_or(|(bc, _)| count > bc);
        if better {
            best = Some((count, plane));
        }
    }
    best.map(|(_, p)| p)
}

/// The floor when [`fit_ground`] finds none: horizontal, at the 1st percentile of the
/// points' z (z = 0 for no points), so that a few points below the floor (depth noise,
/// flying pixels) do not lower it.
pub(crate) fn lowest_floor(points: &[Vec3]) -> Plane {
    let mut z: Vec<f32> = points.iter().map(|p| p[2]).collect();
    z.sort_by(f32::total_cmp);
    let floor = z.get(z.len() / 100).copied().unwrap_or(0.0);
    tracing::debug!(
        floor,
        "no ground plane found; floor at the 1st percentile of z"
    );
    Plane::level_at(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 m × 2 m floor sampled every 5 cm, tilted by `tilt_deg` about the x axis and
    /// raised to `z0_m`, with a deterministic jitter of ±`noise_m` in z.
    fn floor(tilt_deg: f32, z0_m: f32, noise_m: f32) -> Vec<Vec3> {
        let (s, c) = tilt_deg.to_radians().sin_cos();
        let mut out = Vec::new();
        for i in 0..40u32 {
            for j in 0..40u32 {
                let (x, y) = (-1.0 + 0.05 * i as f32, -1.0 + 0.05 * j as f32);
                let jitter = ((i * 31 + j * 17) % 11) as f32 / 5.0 - 1.0;
                out.push([x, c * y, z0_m + s * y + noise_m * jitter]);
            }
        }
        out
    }

    /// Whether every point lies within `tol_m` of `plane`.
    fn all_on(plane: &Plane, points: &[Vec3], tol_m: f32) -> bool {
        points.iter().all(|&p| plane.height(p).abs() <= tol_m)
    }

    #[test]
    fn a_raised_floor_with_a_person_and_a_table_on_it_is_found() {
        // The floor at z = 0.3 m (depth noise ±1 cm), a person's column of 1.7 m and a
        // table top 0.75 m above the floor, a quarter of the floor's size.
        let ground = floor(0.0, 0.3, 0.01);
        let mut points = ground.clone();
        for k in 0..170 {
            points.push([0.2, 0.1, 0.3 + 0.01 * k as f32]);
        }
        for i in 0..20 {
            for j in 0..20 {
                points.push([0.5 + 0.025 * i as f32, 0.025 * j as f32, 1.05]);
            }
        }
        let plane = fit_ground(&points, 0.05, 15.0, 200).expect("a floor");
        // Every floor point within the tolerance, the top of the table 0.75 m above it.
        assert!(all_on(&plane, &ground, 0.05), "{plane:?}");
        assert!(
            (plane.height([0.6, 0.1, 1.05]) - 0.75).abs() < 0.05,
            "{plane:?}"
        );
        // Its normal points up.
        assert!(plane.height([0.0, 0.0, 10.0]) > plane.height([0.0, 0.0, 0.0]));
        // Deterministic: the same points give the same plane.
        assert_eq!(fit_ground(&points, 0.05, 15.0, 200), Some(plane));
    }

    #[test]
    fn a_floor_tilted_within_the_limit_is_found_one_beyond_it_is_not() {
        let tilted = floor(10.0, 0.0, 0.0);
        let plane = fit_ground(&tilted, 0.02, 15.0, 200).expect("a floor tilted by 10°");
        assert!(all_on(&plane, &tilted, 0.02), "{plane:?}");
        // Not the level plane through the origin: 1 m along y the floor is 0.17 m up.
        assert!(plane.height([0.0, 1.0, 0.0]).abs() > 0.1, "{plane:?}");
        // Tilted by 20°: no sample gives a plane within 15° of level.
        assert_eq!(fit_ground(&floor(20.0, 0.0, 0.0), 0.02, 15.0, 200), None);
    }

    #[test]
    fn too_few_or_collinear_points_give_no_plane() {
        assert_eq!(fit_ground(&[], 0.05, 15.0, 200), None);
        assert_eq!(
            fit_ground(&[[0.0; 3], [1.0, 0.0, 0.0]], 0.05, 15.0, 200),
            None
        );
        let line: Vec<Vec3> = (0..50).map(|k| [0.1 * k as f32, 0.0, 0.0]).collect();
        assert_eq!(fit_ground(&line, 0.05, 15.0, 200), None);
    }

    #[test]
    fn without_a_plane_the_floor_is_the_lowest_percentile() {
        // 200 points from z = 1 m up, and one stray point far below (a flying pixel):
        // the floor is the third lowest point (index 201 / 100), not the stray one.
        let mut points: Vec<Vec3> = (0..200)
            .map(|k| [0.0, 0.0, 1.0 + 0.01 * k as f32])
            .collect();
        points.push([0.0, 0.0, -3.0]);
        let plane = lowest_floor(&points);
        assert_eq!(plane.height([5.0, -2.0, points[1][2]]), 0.0);
        assert_eq!(lowest_floor(&[]), Plane::FLOOR);
    }
}
