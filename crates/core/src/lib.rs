//! bodyseg-core: the data types that flow between bodyseg's stages.
//!
//! Place in the pipeline: every stage crate depends on this one and on nothing else of
//! bodyseg's stages. It holds types only, no I/O and no algorithms beyond small helpers
//! on those types (box containment, palette look-up).
//!
//! # Conventions
//! - Units: metres for all geometry (`_m` suffix); radians for angles (`_rad`).
//! - World frame: right-handed, z up, floor at z = 0 where the rig knows it.
//! - Pixels: (u, v) = (column, row); a pixel index is `v * width + u` (row-major) in the
//!   image of the sensor named by the field (the depth image for [`PointOrigin::pixel`]).
//! - Classes follow Pascal-Person-Part's order (see [`Class`]); ALGORITHM.md §0.

pub mod class;
pub mod cloud;
pub mod image;
pub mod math;
pub mod person;
pub mod rng;

pub use class::{Class, Label, NUM_CLASSES};
pub use cloud::{CloudError, LabeledCloud, PointOrigin, RefinedCloud};
pub use image::{ImageError, LabelImage, RgbImage};
pub use person::{BoxTest, PersonBox, PersonBoxes};
