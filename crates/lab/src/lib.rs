//! bodyseg-lab: studies of bodyseg's stages on synthetic recordings, apart from the
//! product (STYLE.md: study code lives in a `lab` crate, like rerun's dev tools). Nothing
//! depends on it; it may depend on every bodyseg crate.
//!
//! - [`projection_stats`] (`projection_study`): label projection (naive, DSA) against the
//!   exact truth of every depth pixel — issue 4's report, `examples/projection_report.rs`,
//!   and the floor of `tests/dsa_on_synth.rs`.
//! - [`box_stats`] (`boxes_study`): the person box finder against the true boxes —
//!   issue 6's report, `examples/boxes_report.rs` (`boxes_cache.rs`, `boxes_frame.rs` for
//!   single frames), and the floor of `tests/boxes_on_synth.rs`.
//!
//! Tools in `examples/`: `cpu_per_frame` (CPU time per frame of `bodyseg run`'s frame
//! loop, next to the bench), `pcd_scene` (the input of the PCD fixture of
//! `scripts/gen_pcd_fixtures.py`). Run one with
//! `cargo run --release -p bodyseg-lab --example NAME [ARGS]`.
//!
//! # Conventions
//! As the stages': metres, radians, world frame z up; frames of a synthetic recording are
//! numbered from 0 and rendered by `bodyseg_synth::Synth` with a fixed seed, so every
//! figure is reproducible.

mod boxes_study;
mod projection_study;

pub use boxes_study::{
    BoxStats, FrameMatch, MATCH_IOU, box_stats, describe_box, match_boxes, study_frame,
};
pub use projection_study::{ProjectionStats, camera_images, parsing_images, projection_stats};
