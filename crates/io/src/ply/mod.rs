//! Labelled point clouds as PLY files (FORMATS.md, "Labelled point cloud").

mod header;
mod read;
mod write;

pub use read::{parse_ply, read_ply};
pub use write::{PlyColors, PlyFormat, PlyWriteOptions, ply_bytes, write_ply};
