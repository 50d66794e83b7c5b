//! The landmark model's tensor sizes.

/// Side of the landmark model's square input, pixels.
pub const INPUT: usize = 256;
/// Side of the landmark heatmaps, cells (a cell is 4 input pixels).
pub const HEATMAP: usize = 64;
/// Landmarks the model outputs (33 body points + alignment points + auxiliaries).
pub const NUM_LANDMARKS: usize = 39;
