//! Labelled point clouds as PLY files (FORMATS.md, "Labelled point cloud").

mod ascii;
mod binary;
mod header;
mod plan;
mod read;
mod write;

pub use read::{parse_ply, parse_ply_file, read_ply, read_ply_file};
pub use write::{PlyColors, PlyFormat, PlyWriteOptions, ply_bytes, write_ply};
