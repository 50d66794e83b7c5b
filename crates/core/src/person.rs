//! Person boxes: oriented boxes in the world frame around each person (ALGORITHM.md §4).

use crate::math::{RigidTransform, Vec3};
use serde::{Deserialize, Serialize};

/// An oriented box around one person, world frame (z up).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PersonBox {
    /// Person id within the frame (from the tracker or the box finder).
    pub id: u32,
    /// Box centre, world frame, metres.
    pub center_m: Vec3,
    /// Half the box's size along its own x, y, z axes, metres (all > 0).
    pub half_extents_m: Vec3,
    /// Rotation of the box about the world z axis, radians (counter-clockwise seen from above).
    #[serde(default)]
    pub yaw_rad: f32,
}

impl PersonBox {
    /// A box with its axes along the world's (yaw 0).
    pub fn axis_aligned(id: u32, center_m: Vec3, half_extents_m: Vec3) -> PersonBox {
        PersonBox {
            id,
            center_m,
            half_extents_m,
            yaw_rad: 0.0,
        }
    }

    /// True when `p_world` lies inside the box or on its faces. For many points, make a
    /// [`BoxTest`] once with [`PersonBox::test`].
    #[inline]
    pub fn contains(&self, p_world: Vec3) -> bool {
        self.test().contains(p_world)
    }

    /// The containment test with the yaw's sine and cosine computed once.
    pub fn test(&self) -> BoxTest {
        let (sin, cos) = self.yaw_rad.sin_cos();
        BoxTest {
            center_m: self.center_m,
            half_extents_m: self.half_extents_m,
            sin,
            cos,
        }
    }

    /// Why this box is unusable, if it is (non-finite numbers, non-positive extents).
    pub fn invalid_reason(&self) -> Option<String> {
        let all = self.center_m.iter().chain(&self.half_extents_m);
        if !all.clone().all(|v| v.is_finite()) || !self.yaw_rad.is_finite() {
            return Some(format!(
                "box {}: coordinates must be finite numbers",
                self.id
            ));
        }
        if self.half_extents_m.iter().any(|&h| h <= 0.0) {
            return Some(format!(
                "box {}: half_extents_m must all be > 0, got {:?}",
                self.id, self.half_extents_m
            ));
        }
        None
    }
}

/// A [`PersonBox`] ready for fast point-in-box tests.
#[derive(Clone, Copy, Debug)]
pub struct BoxTest {
    center_m: Vec3,
    half_extents_m: Vec3,
    sin: f32,
    cos: f32,
}

impl BoxTest {
    /// [`BoxTest::contains`] of four points at once (lane by lane the same operations in
    /// the same order, so the same answers), written so that the compiler can test the
    /// four in vector registers.
    #[inline]
    pub fn contains4(&self, p: &[Vec3; 4]) -> [bool; 4] {
        let mut d = [[0f32; 4]; 3];
        for (l, q) in p.iter().enumerate() {
            for a in 0..3 {
                d[a][l] = q[a] - self.center_m[a];
            }
        }
        let mut inside = [false; 4];
        for l in 0..4 {
            let lx = self.cos * d[0][l] + self.sin * d[1][l];
            let ly = -self.sin * d[0][l] + self.cos * d[1][l];
            inside[l] = (lx.abs() <= self.half_extents_m[0])
                & (ly.abs() <= self.half_extents_m[1])
                & (d[2][l].abs() <= self.half_extents_m[2]);
        }
        inside
    }

    /// True when `p_world` lies inside the box or on its faces.
    #[inline]
    pub fn contains(&self, p_world: Vec3) -> bool {
        let dx = p_world[0] - self.center_m[0];
        let dy = p_world[1] - self.center_m[1];
        let dz = p_world[2] - self.center_m[2];
        // Rotate into the box frame by -yaw.
        let lx = self.cos * dx + self.sin * dy;
        let ly = -self.sin * dx + self.cos * dy;
        // `&`, not `&&`: no branch per test (scans over whole clouds call this).
        (lx.abs() <= self.half_extents_m[0])
            & (ly.abs() <= self.half_extents_m[1])
            & (dz.abs() <= self.half_extents_m[2])
    }
}

/// The boxes of one frame, as in FORMATS.md's boxes JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PersonBoxes {
    /// Frame stem the boxes belong to (may be empty when unknown).
    #[serde(default)]
    pub frame: String,
    /// One box per person.
    pub boxes: Vec<PersonBox>,
    /// Set when the boxes were found in a cloud whose own frame is not z up (a camera's
    /// frame): the transform from the cloud's frame into the world frame the boxes are in
    /// (z up, floor at z = 0), found from the floor. `None` (and absent from the JSON):
    /// the cloud's frame is the world frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world_from_cloud: Option<RigidTransform>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yawed_box_contains_its_rotated_corner_region() {
        let b = PersonBox {
            id: 0,
            center_m: [1.0, 2.0, 1.0],
            half_extents_m: [0.5, 0.1, 1.0],
            yaw_rad: std::f32::consts::FRAC_PI_2,
        };
        // Long axis now along world y.
        assert!(b.contains([1.0, 2.45, 1.0]));
        assert!(!b.contains([1.45, 2.0, 1.0]));
        assert!(!b.contains([1.0, 2.0, 2.1]));
        assert!(b.invalid_reason().is_none());
        let bad = PersonBox {
            half_extents_m: [0.0, 1.0, 1.0],
            ..b
        };
        assert!(bad.invalid_reason().is_some());
    }

    #[test]
    fn four_at_a_time_equals_one_at_a_time_on_and_near_the_faces() {
        let b = PersonBox {
            id: 0,
            center_m: [0.5389, 0.1351, 0.9395],
            half_extents_m: [0.4478, 0.4140, 0.9395],
            yaw_rad: 2.1459,
        };
        let t = b.test();
        // A lattice over and past the box (some points on its faces up to rounding).
        let mut pts = Vec::new();
        for i in 0..41 {
            for j in 0..41 {
                for k in 0..9 {
                    let f = |v: i32, c: f32, h: f32| c + (v as f32 / 20.0 - 1.0) * 1.3 * h;
                    pts.push([
                        f(i, 0.5389, 0.6),
                        f(j, 0.1351, 0.6),
                        f(k * 5, 0.9395, 0.9395),
                    ]);
                }
            }
        }
        let mut inside = 0;
        for four in pts.chunks_exact(4) {
            let four: &[Vec3; 4] = four.try_into().expect("chunks of 4");
            let got = t.contains4(four);
            for (l, p) in four.iter().enumerate() {
                assert_eq!(got[l], t.contains(*p), "{p:?}");
                inside += usize::from(got[l]);
            }
        }
        assert!(
            inside > 1000 && inside < pts.len() - 1000,
            "{inside} of {}",
            pts.len()
        );
    }

    #[test]
    fn an_axis_aligned_box_has_no_yaw() {
        let b = PersonBox::axis_aligned(3, [1.0, 2.0, 1.0], [0.5, 0.1, 1.0]);
        assert_eq!((b.id, b.yaw_rad), (3, 0.0));
        assert!(b.contains([1.45, 2.05, 1.0]));
        assert!(!b.contains([1.0, 2.45, 1.0]));
    }
}
