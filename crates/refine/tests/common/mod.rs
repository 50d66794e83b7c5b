//! Hand-built scenes shared by the refinement tests: lattice balls and boxes of points.

// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label, LabeledCloud, PointOrigin};
use bodyseg_refine::RefineConfig;

/// The test scenes' DBSCAN (lattices of pitch 0.02–0.025 m) with the steps `steps`
/// (e.g. "M-R-N") and the paper's modes.
pub fn paper(steps: &str) -> RefineConfig {
    RefineConfig {
        eps_m: 0.03,
        min_points: 5,
        steps: steps.parse().expect("valid steps"),
        ..Default::default()
    }
}

pub fn l(c: Class) -> Label {
    Label::from(c)
}

/// A dense ball of points on a lattice of pitch `pitch_m` (deterministic, DBSCAN-friendly).
pub fn ball(center: Vec3, radius_m: f32, pitch_m: f32, label: Label) -> (Vec<Vec3>, Vec<Label>) {
    let n = (radius_m / pitch_m).ceil() as i32;
    let mut pos = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            for k in -n..=n {
                let d = [i as f32 * pitch_m, j as f32 * pitch_m, k as f32 * pitch_m];
                if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= radius_m * radius_m {
                    pos.push([center[0] + d[0], center[1] + d[1], center[2] + d[2]]);
                }
            }
        }
    }
    let lab = vec![label; pos.len()];
    (pos, lab)
}

/// A scene built from parts; remembers where each part's points start.
#[derive(Default)]
pub struct Scene {
    pub pos: Vec<Vec3>,
    pub lab: Vec<Label>,
    pub parts: Vec<std::ops::Range<usize>>,
}

impl Scene {
    pub fn add(&mut self, (pos, lab): (Vec<Vec3>, Vec<Label>)) -> usize {
        let s = self.pos.len();
        self.pos.extend(pos);
        self.lab.extend(lab);
        self.parts.push(s..self.pos.len());
        self.parts.len() - 1
    }
    pub fn point(&mut self, p: Vec3, label: Label) -> usize {
        self.add((vec![p], vec![label]));
        self.pos.len() - 1
    }
    pub fn cloud(&self) -> LabeledCloud {
        LabeledCloud {
            positions_m: self.pos.clone(),
            labels: self.lab.clone(),
            colors: None,
            origins: (0..self.pos.len() as u32)
                .map(|pixel| PointOrigin { camera: 0, pixel })
                .collect(),
        }
    }
    pub fn labels_of(&self, out: &[Label], part: usize) -> Vec<Label> {
        out[self.parts[part].clone()].to_vec()
    }
    /// Whether every point of `part` has `label` in `out`.
    pub fn all_labelled(&self, out: &[Label], part: usize, label: Label) -> bool {
        out[self.parts[part].clone()].iter().all(|&x| x == label)
    }
}

/// A solid axis-aligned box of points on a lattice of pitch `pitch_m`, corners `lo`..`hi`.
pub fn cuboid(lo: Vec3, hi: Vec3, pitch_m: f32, label: Label) -> (Vec<Vec3>, Vec<Label>) {
    let steps = |a: usize| ((hi[a] - lo[a]) / pitch_m).round() as i32;
    let mut pos = Vec::new();
    for i in 0..=steps(0) {
        for j in 0..=steps(1) {
            for k in 0..=steps(2) {
                pos.push([
                    lo[0] + i as f32 * pitch_m,
                    lo[1] + j as f32 * pitch_m,
                    lo[2] + k as f32 * pitch_m,
                ]);
            }
        }
    }
    let lab = vec![label; pos.len()];
    (pos, lab)
}
