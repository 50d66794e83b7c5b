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
    let mut pose = decode_landmarks(roi, landmarks, flag, heatmap)?;
    pose.mask = mask_from_logits(mask_logits);
    Some(pose)
}

/// [`decode`] without the mask (`mask` left empty; [`mask_from_logits`] makes it): the
/// segmenter decodes the mask only for the pose a region keeps. `None` when `landmarks`
/// is shorter than the model's.
pub(crate) fn decode_landmarks(
    roi: &Roi,
    landmarks: &[f32],
    flag: f32,
    heatmap: Option<&[f32]>,
) -> Option<DecodedPose> {
    if landmarks.len() < NUM_LANDMARKS * 5 {
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
        mask: Vec::new(),
    })
}

/// The person probabilities of the mask output's first 256×256 logits (fewer: empty).
pub(crate) fn mask_from_logits(mask_logits: &[f32]) -> Vec<f32> {
    mask_logits
        .get(..INPUT * INPUT)
        .unwrap_or(&[])
        .iter()
        .map(|&v| sigmoid(f64::from(v)) as f32)
        .collect()
}

/// The landmark that each landmark becomes in the mirror image (left ↔ right of
/// MediaPipe's pose topology: eyes, ears, mouth corners, arms, hands, legs, feet; the nose
/// and the alignment and auxiliary points 33–38 stay).
pub(crate) fn mirrored_landmark(i: usize) -> usize {
    match i {
        1..=3 => i + 3,
        4..=6 => i - 3,
        7..=32 if i % 2 == 1 => i + 1,
        8..=32 => i - 1,
        _ => i,
    }
}

/// Mirrors a crop (NHWC, `size`×`size`×3) left ↔ right in place.
pub fn mirror_crop(input: &mut [f32], size: usize) {
    for row in input.chunks_exact_mut(size * 3) {
        for i in 0..size / 2 {
            for c in 0..3 {
                row.swap(i * 3 + c, (size - 1 - i) * 3 + c);
            }
        }
    }
}

/// The outputs of a run on a mirrored crop ([`mirror_crop`]) brought back to the
/// unmirrored crop: x → 256 − x (tensor pixel edges), left and right landmarks swapped
/// (the model names a person's own left, which the mirror shows on the right), mask rows
/// and heatmap rows reversed (heatmap channels swapped as the landmarks). Buffers shorter
/// than the model's come back as they are.
pub fn unmirror_outputs(landmarks: &[f32], mask: &[f32], heatmap: &[f32]) -> [Vec<f32>; 3] {
    let mut lm = landmarks.to_vec();
    if landmarks.len() >= NUM_LANDMARKS * 5 {
        for i in 0..NUM_LANDMARKS {
            let j = mirrored_landmark(i);
            lm[i * 5..i * 5 + 5].copy_from_slice(&landmarks[j * 5..j * 5 + 5]);
            lm[i * 5] = INPUT as f32 - lm[i * 5];
        }
    }
    let mut m = mask.to_vec();
    if mask.len() >= INPUT * INPUT {
        for row in m[..INPUT * INPUT].chunks_exact_mut(INPUT) {
            row.reverse();
        }
    }
    let mut h = heatmap.to_vec();
    let cells = HEATMAP * HEATMAP * NUM_LANDMARKS;
    if heatmap.len() >= cells {
        for r in 0..HEATMAP {
            for c in 0..HEATMAP {
                for i in 0..NUM_LANDMARKS {
                    let src =
                        (r * HEATMAP + (HEATMAP - 1 - c)) * NUM_LANDMARKS + mirrored_landmark(i);
                    h[(r * HEATMAP + c) * NUM_LANDMARKS + i] = heatmap[src];
                }
            }
        }
    }
    [lm, m, h]
}

/// `pose` with its mask averaged with `mirrored`'s (the decoding of a run on the mirrored
/// crop of the same ROI, [`unmirror_outputs`]): two estimates of each pixel's person
/// probability whose errors are not mirror-symmetric (a ragged border, a thin forearm half
/// missed), so the mean is steadier than either. Landmarks, flag and the rest stay
/// `pose`'s: averaging the landmarks too was tried (docs/notes/2026-12-03-blazepose.md,
/// 2026-12-04 session 41) and lost on the tune split, since the two runs may name crossed
/// legs the other way round, and a mean of two hypotheses lies on neither limb. `pose`
/// unchanged when the ROIs or mask sizes differ.
pub fn average_masks(pose: &DecodedPose, mirrored: &DecodedPose) -> DecodedPose {
    let mut out = pose.clone();
    if pose.roi == mirrored.roi && pose.mask.len() == mirrored.mask.len() {
        for (m, q) in out.mask.iter_mut().zip(&mirrored.mask) {
            *m = 0.5 * (*m + q);
        }
    }
    out
}
