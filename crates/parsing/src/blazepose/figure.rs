//! Test figures: an upright person's landmarks and a pose seen everywhere around given
//! landmarks. Shared by the unit tests (`blazepose/tests.rs`, `blazepose_segmenter.rs`)
//! and, through `#[path]`, by `benches/blazepose_rule.rs`.

use super::{DecodedPose, NUM_LANDMARKS, Roi, landmark};

/// An upright figure's landmarks, image px in a 100×160 frame: eyes, mouth and ears at
/// y 23–28, shoulders 40, elbows 60, wrists 78, hips 80, knees 110, ankles 140; hand
/// landmarks 6 px past the wrists, foot landmarks 6 px past the ankles; the rest (nose,
/// eye corners) at (50, 25).
pub(crate) fn upright_figure_xy() -> Vec<[f64; 2]> {
    use landmark::*;
    let mut xy = vec![[50.0, 25.0]; NUM_LANDMARKS];
    for (i, p) in [
        (LEFT_EYE, [53.0, 23.0]),
        (RIGHT_EYE, [47.0, 23.0]),
        (MOUTH_LEFT, [52.0, 28.0]),
        (MOUTH_RIGHT, [48.0, 28.0]),
        (LEFT_EAR, [56.0, 24.0]),
        (RIGHT_EAR, [44.0, 24.0]),
        (LEFT_SHOULDER, [60.0, 40.0]),
        (RIGHT_SHOULDER, [40.0, 40.0]),
        (LEFT_HIP, [58.0, 80.0]),
        (RIGHT_HIP, [42.0, 80.0]),
        (LEFT_ELBOW, [70.0, 60.0]),
        (RIGHT_ELBOW, [30.0, 60.0]),
        (LEFT_WRIST, [72.0, 78.0]),
        (RIGHT_WRIST, [28.0, 78.0]),
        (LEFT_KNEE, [58.0, 110.0]),
        (RIGHT_KNEE, [42.0, 110.0]),
        (LEFT_ANKLE, [58.0, 140.0]),
        (RIGHT_ANKLE, [42.0, 140.0]),
    ] {
        xy[i] = p;
    }
    for (idx, p) in [
        (&LEFT_HAND[..], [72.0, 84.0]),
        (&RIGHT_HAND[..], [28.0, 84.0]),
        (&LEFT_FOOT[..], [58.0, 146.0]),
        (&RIGHT_FOOT[..], [42.0, 146.0]),
    ] {
        for &i in idx {
            xy[i] = p;
        }
    }
    xy
}

/// A pose at landmarks `xy` that the model is sure of (flag, every visibility and presence
/// 1, every depth 0), seen in an upright ROI of side `side_px` centred at `centre_px`.
pub(crate) fn sure_pose(
    xy: Vec<[f64; 2]>,
    centre_px: [f64; 2],
    side_px: f64,
    mask: Vec<f32>,
) -> DecodedPose {
    DecodedPose {
        roi: Roi {
            centre_px,
            side_px,
            angle_rad: 0.0,
        },
        flag: 1.0,
        xy,
        depth_px: vec![0.0; NUM_LANDMARKS],
        visibility: vec![1.0; NUM_LANDMARKS],
        presence: vec![1.0; NUM_LANDMARKS],
        mask,
    }
}
