//! Decoding the landmark model's outputs: heatmap refinement and landmark visibility.

use super::model::{HEATMAP, INPUT, NUM_LANDMARKS};
use super::roi::{P2, Roi};

pub(crate) fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x.clamp(-60.0, 60.0)).exp())
}

/// MediaPipe's RefineLandmarksFromHeatmap: each landmark's (x, y) (tensor px) becomes the
/// sigmoid-weighted mean cell position in a `kernel`×`kernel` window of its heatmap around
/// it, when the window's largest weight is ≥ `min_confidence`. `landmarks` holds
/// (x, y, …) per landmark; `heatmap` is `[64][64][39]` logits (row, column, landmark).
pub fn refine_from_heatmap(
    landmarks: &mut [[f64; 5]],
    heatmap: &[f32],
    kernel: usize,
    min_confidence: f64,
) {
    if heatmap.len() < HEATMAP * HEATMAP * NUM_LANDMARKS {
        return;
    }
    let off = (kernel / 2) as i64;
    let cell = (INPUT / HEATMAP) as f64;
    for (k, lm) in landmarks.iter_mut().enumerate().take(NUM_LANDMARKS) {
        let col = (lm[0] / cell).floor();
        let row = (lm[1] / cell).floor();
        if !(0.0..HEATMAP as f64).contains(&col) || !(0.0..HEATMAP as f64).contains(&row) {
            continue;
        }
        let (col, row) = (col as i64, row as i64);
        let (mut sum, mut sc, mut sr, mut max) = (0.0, 0.0, 0.0, 0.0f64);
        for r in (row - off).max(0)..(row + off + 1).min(HEATMAP as i64) {
            for c in (col - off).max(0)..(col + off + 1).min(HEATMAP as i64) {
                let idx = (r as usize * HEATMAP + c as usize) * NUM_LANDMARKS + k;
                let wgt = sigmoid(f64::from(heatmap[idx]));
                sum += wgt;
                sc += c as f64 * wgt;
                sr += r as f64 * wgt;
                max = max.max(wgt);
            }
        }
        if max >= min_confidence && sum > 0.0 {
            lm[0] = (sc / sum + 0.5) * cell;
            lm[1] = (sr / sum + 0.5) * cell;
        }
    }
}

/// One person's decoded model output, in image coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedPose {
    /// The ROI the model saw.
    pub roi: Roi,
    /// Pose presence in [0, 1] (the model's `Identity_1`).
    pub flag: f64,
    /// Landmark positions, image px, [`NUM_LANDMARKS`] entries.
    pub xy: Vec<P2>,
    /// Depth per landmark relative to the mid-hip point, image px (the model's z, which
    /// has x's scale, mapped by the ROI's scale): smaller is nearer the camera.
    pub depth_px: Vec<f64>,
    /// Visibility (sigmoid), per landmark.
    pub visibility: Vec<f64>,
    /// Presence (sigmoid), per landmark.
    pub presence: Vec<f64>,
    /// Person probability on the ROI's 256×256 grid, row-major (sigmoid of the mask logits).
    pub mask: Vec<f32>,
}

/// Decodes the landmark model's outputs for `roi`: `landmarks` = `Identity` (195 values:
/// x, y, z, visibility logit, presence logit per landmark, x and y in tensor px),
/// `flag` = `Identity_1`, `mask_logits` = `Identity_2` (256×256), `heatmap` = `Identity_3`
/// (refines x, y when given). `None` when a buffer is shorter than the model's.
pub fn decode(
    roi: &Roi,
    landmarks: &[f32],
    flag: f32,
    mask_logits: &[f32],
    heatmap: Option<&[f32]>,
) -> Option<DecodedPose> {
    if landmarks.len() < NUM_LANDMARKS * 5 || mask_logits.len() < INPUT * INPUT {
        return None;
    }
    let mut lm: Vec<[f64; 5]> = landmarks
        .chunks_exact(5)
        .take(NUM_LANDMARKS)
        .map(|c| {
            [
                f64::from(c[0]),
                f64::from(c[1]),
                f64::from(c[2]),
                f64::from(c[3]),
                f64::from(c[4]),
            ]
        })
        .collect();
    if let Some(h) = heatmap {
        refine_from_heatmap(&mut lm, h, 7, 0.5);
    }
    Some(DecodedPose {
        roi: *roi,
        flag: f64::from(flag),
        xy: lm
            .iter()
            .map(|l| roi.tensor_to_image([l[0], l[1]]))
            .collect(),
        depth_px: lm
            .iter()
            .map(|l| l[2] * roi.side_px / INPUT as f64)
            .collect(),
        visibility: lm.iter().map(|l| sigmoid(l[3])).collect(),
        presence: lm.iter().map(|l| sigmoid(l[4])).collect(),
        mask: mask_logits[..INPUT * INPUT]
            .iter()
            .map(|&v| sigmoid(f64::from(v)) as f32)
            .collect(),
    })
}
