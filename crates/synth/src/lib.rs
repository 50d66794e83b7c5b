//! Seeded synthetic multi-camera RGB-D recordings of people with exact ground truth
//! (the synth issue): articulated people, a static scene, a Kinect v2-like rig, ray-cast
//! depth and colour with sensor faults, exact 2D and per-depth-pixel truth, true person
//! boxes, simulated parser predictions and DSA error sources.
//!
//! This crate computes images in memory; writing a recording is `bodyseg-pipeline`'s job
//! (only `io` touches the file system).

pub mod chessboard;
pub mod config;
pub mod frame;
pub mod geometry;
pub mod hash;
pub mod parser_mistakes;
pub mod people;
pub mod preview;
pub mod render;
pub mod rig;
pub mod scene;
pub mod shade;

pub use chessboard::{
    ChessboardConfig, ChessboardSet, ChessboardView, SensorImages, chessboard_set,
};
pub use config::{
    CameraPlacement, DepthFaultsConfig, DsaConfig, PRESETS, ParserMistakesConfig, PeopleConfig,
    RigConfig, SceneConfig, StaticSceneConfig, SynthError, preset,
};
pub use frame::{CameraFrame, NO_SURFACE, Synth, SynthFrame, frame_stem};
pub use preview::preview;
