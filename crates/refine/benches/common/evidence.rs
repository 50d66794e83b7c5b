//! The made-up parser evidence and the `noise = "probability"` configuration shared by the
//! refine bench and the `refine_check` example.

use bodyseg_core::math::Vec3;
use bodyseg_refine::{GraphMode, NoiseMode, RefineConfig, TreeMode};

/// Made-up parser probabilities, as the parser's doubts come: in strips (2.5 cm bands
/// every 10 cm of height at 0.5, the rest at 0.9), so a quarter of the labels are doubted
/// at a doubt ratio of 0.85.
pub fn strip_probs(positions: &[Vec3]) -> Vec<f32> {
    positions
        .iter()
        .map(|q| {
            if (q[2] * 10.0).rem_euclid(1.0) < 0.25 {
                0.5
            } else {
                0.9
            }
        })
        .collect()
}

/// `noise = "probability"` over `paper`: the contact graph, the coverage tree, doubt ratio
/// 0.85.
pub fn probability_config(paper: &RefineConfig) -> RefineConfig {
    RefineConfig {
        graph: GraphMode::Contact,
        tree: TreeMode::Coverage,
        noise: NoiseMode::Probability,
        noise_doubt_ratio: 0.85,
        ..paper.clone()
    }
}
