//! Landmark indices (MediaPipe pose topology) used by the rule.

/// Nose.
pub const NOSE: usize = 0;
/// Left eye (centre).
pub const LEFT_EYE: usize = 2;
/// Right eye (centre).
pub const RIGHT_EYE: usize = 5;
/// Left ear.
pub const LEFT_EAR: usize = 7;
/// Right ear.
pub const RIGHT_EAR: usize = 8;
/// Mouth, left corner.
pub const MOUTH_LEFT: usize = 9;
/// Mouth, right corner.
pub const MOUTH_RIGHT: usize = 10;
/// Left shoulder.
pub const LEFT_SHOULDER: usize = 11;
/// Right shoulder.
pub const RIGHT_SHOULDER: usize = 12;
/// Left elbow.
pub const LEFT_ELBOW: usize = 13;
/// Right elbow.
pub const RIGHT_ELBOW: usize = 14;
/// Left wrist.
pub const LEFT_WRIST: usize = 15;
/// Right wrist.
pub const RIGHT_WRIST: usize = 16;
/// Left pinky, index, thumb.
pub const LEFT_HAND: [usize; 3] = [17, 19, 21];
/// Right pinky, index, thumb.
pub const RIGHT_HAND: [usize; 3] = [18, 20, 22];
/// Left hip.
pub const LEFT_HIP: usize = 23;
/// Right hip.
pub const RIGHT_HIP: usize = 24;
/// Left knee.
pub const LEFT_KNEE: usize = 25;
/// Right knee.
pub const RIGHT_KNEE: usize = 26;
/// Left ankle.
pub const LEFT_ANKLE: usize = 27;
/// Right ankle.
pub const RIGHT_ANKLE: usize = 28;
/// Left heel, foot index.
pub const LEFT_FOOT: [usize; 2] = [29, 31];
/// Right heel, foot index.
pub const RIGHT_FOOT: [usize; 2] = [30, 32];
/// Alignment point: body centre (mid-hip).
pub const ALIGN_CENTRE: usize = 33;
/// Alignment point: size and rotation.
pub const ALIGN_SCALE: usize = 34;
/// Face points: nose, eyes, ears, mouth (0..=10).
pub const FACE: std::ops::RangeInclusive<usize> = 0..=10;
