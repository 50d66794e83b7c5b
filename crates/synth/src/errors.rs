//! The simulated 2D parser: predicted label images made from the exact ones by the
//! errors real parsing networks make (ALGORITHM.md §2–§3; the paper's SCHP observations).
//!
//! (Stub: filled in by the parsing-errors work; the public API below is the contract.)

use crate::config::ParsingErrorsConfig;

/// The exact 2D truth of one colour view, row-major, `width * height` entries each.
#[derive(Clone, Copy, Debug)]
pub struct TruthView<'a> {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Class id per pixel (ALGORITHM.md §0; 0 = background).
    pub labels: &'a [u8],
    /// Person id per pixel (1-based; 0 = no person).
    pub person: &'a [u8],
    /// Body segment id per pixel ([`crate::geometry::Segment::id`]; 0 = none).
    pub segment: &'a [u8],
}

/// The predicted label image of one view: the truth with the errors of `config`
/// (pixel sizes given for a 1920-wide image, scaled by `width / 1920`). Deterministic in
/// `seed`. With every knob at zero it equals `truth.labels`.
pub fn predict_labels(truth: &TruthView<'_>, config: &ParsingErrorsConfig, seed: u64) -> Vec<u8> {
    let _ = (config, seed);
    truth.labels.to_vec()
}
