//! Hand-made scenes shared by the box-finder tests: labelled cylinder and sphere surfaces
//! sampled about as densely as a Kinect v2 frame, and a floor.

// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use bodyseg_synth::geometry::{frame_from_axis, norm, sub};

/// Surface sample spacing, metres: ≈ 25 points per 5 cm voxel of surface, like a Kinect
/// v2 frame at 2–3 m.
pub const STEP_M: f32 = 0.01;

/// Labelled surface points.
#[derive(Clone, Default)]
pub struct Scene {
    pub points: Vec<Vec3>,
    pub labels: Vec<Label>,
}

impl Scene {
    pub fn push(&mut self, p: Vec3, label: Label) {
        self.points.push(p);
        self.labels.push(label);
    }

    /// Points on the side of the cylinder from `a` to `b`, labelled `label`.
    pub fn cylinder(&mut self, a: Vec3, b: Vec3, radius: f32, label: impl Into<Label>) {
        let label = label.into();
        let len = norm(sub(b, a));
        let [u, v, w] = frame_from_axis(sub(b, a));
        let rings = (len / STEP_M).ceil() as usize;
        let around = (std::f32::consts::TAU * radius / STEP_M).ceil() as usize;
        for i in 0..=rings {
            let t = len * i as f32 / rings as f32;
            for k in 0..around {
                let (s, c) = (std::f32::consts::TAU * k as f32 / around as f32).sin_cos();
                let p = std::array::from_fn(|d| a[d] + w[d] * t + radius * (c * u[d] + s * v[d]));
                self.push(p, label);
            }
        }
    }

    /// The cylinders `(a, b, radius)` of the body's right side (y < 0: `y` is negated),
    /// then of its left (as given), labelled `label`: arms and legs.
    pub fn both_sides(&mut self, parts: &[(Vec3, Vec3, f32)], label: impl Into<Label>) {
        let label = label.into();
        for side in [-1.0, 1.0] {
            let mirror = |p: Vec3| [p[0], side * p[1], p[2]];
            for &(a, b, radius) in parts {
                self.cylinder(mirror(a), mirror(b), radius, label);
            }
        }
    }

    /// Points on a sphere (Fibonacci lattice), labelled `label`.
    pub fn sphere(&mut self, center: Vec3, radius: f32, label: impl Into<Label>) {
        let label = label.into();
        let n = (4.0 * std::f32::consts::PI * radius * radius / (STEP_M * STEP_M)) as usize;
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let (s, c) = (golden * i as f32).sin_cos();
            let p = [
                center[0] + radius * r * c,
                center[1] + radius * r * s,
                center[2] + radius * z,
            ];
            self.push(p, label);
        }
    }

    /// A 4 m × 4 m floor at z = 0 around the origin, background, 2 cm apart.
    pub fn floor(&mut self) {
        let n = (4.0 / 0.02) as i32;
        for i in 0..n {
            for j in 0..n {
                let p = [-2.0 + 0.02 * i as f32, -2.0 + 0.02 * j as f32, 0.0];
                self.push(p, Label::BACKGROUND);
            }
        }
    }

    /// The scene's cloud; without `labels` every point is unknown (geometry mode's input).
    pub fn cloud(self, labels: bool) -> LabeledCloud {
        let n = self.points.len();
        LabeledCloud {
            positions_m: self.points,
            labels: if labels {
                self.labels
            } else {
                vec![Label::UNKNOWN; n]
            },
            colors: None,
            origins: (0..n as u32)
                .map(|pixel| PointOrigin { camera: 0, pixel })
                .collect(),
        }
    }
}
