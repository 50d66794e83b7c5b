//! bodyseg-io: bodyseg's files on disk, and the only crate that touches the file system.
//!
//! Place in the pipeline: at both ends of every stage. It reads and writes the values
//! that cross stage boundaries so any intermediate can be stored and inspected:
//! [`LabeledCloud`](bodyseg_core::LabeledCloud) ⇄ PLY ([`read_ply`], [`write_ply`]) and
//! [`PersonBoxes`](bodyseg_core::PersonBoxes) ⇄ JSON ([`read_boxes`], [`write_boxes`]).
//! PCL's `.pcd` files (ascii, binary, binary_compressed) read into a cloud ([`read_pcd`]).
//! Either read as a [`CloudFile`] ([`read_cloud_file`]) leaves the `label` field's meaning
//! to the caller (absent, bodyseg's class ids, or foreign ids such as PCL's segments) and
//! keeps an organised cloud's grid.
//! A recording's images: depth PNGs ⇄ [`DepthImage`] ([`read_depth_png`],
//! [`write_depth_png`]) and label PNGs ⇄ [`LabelImage`](bodyseg_core::LabelImage)
//! ([`read_label_png`], [`write_label_png`]); colour PNG/JPEG → [`RgbImage`](bodyseg_core::RgbImage)
//! ([`read_rgb_image`]), or kept as the file's bytes ([`read_color_file`]). A large file
//! streamed once (the `.rrd` of `--rerun`) can be written past the page cache
//! ([`DirectFile`]). ONNX models are read as bytes ([`read_bytes`]). 2-D numeric
//! matrices of MATLAB MAT v5 files (plain or compressed; datasets' depth maps) read as
//! [`MatMatrix`] ([`read_mat_matrix`], [`read_mat_variable_names`]). Each reader has a
//! `parse_*` twin that takes the file's bytes (as fuzzing does).
//! Other crates' text files (configurations, reports) go through [`read_text`] and
//! [`write_bytes_atomic`].
//! Layouts are those of FORMATS.md. Readers are tolerant (unknown PLY properties and
//! elements, unknown JSON keys are ignored); writers are exact.
//!
//! # Conventions
//! - Units and frames are the stored types': positions in metres, world frame (z up);
//!   angles in radians. Files carry no unit conversion.
//! - Labels on disk are class ids 0..=6, and 255 for unknown
//!   ([`Label::UNKNOWN_ID`](bodyseg_core::Label::UNKNOWN_ID)).
//! - A point's origin is `(camera, pixel)`: camera index in rig order and row-major
//!   index in that camera's depth image. A PLY without `camera`/`pixel` reads as camera 0
//!   and the vertex index, as [`LabeledCloud::origins`](bodyseg_core::LabeledCloud::origins)
//!   documents.
//! - Depth PNGs are 16-bit grayscale raw depth (millimetres), 0 = no measurement; label
//!   PNGs are 8-bit grayscale class ids, 255 = not labelled; pixels row-major.
//! - PLY is written binary little-endian by default; readers accept ASCII and both byte
//!   orders.
//! - Every write goes through [`write_atomic`]: a temporary file in the destination's
//!   directory, fsynced, renamed over the destination. A failed write leaves the
//!   destination untouched and no temporary behind. Batch outputs may skip the fsync
//!   ([`Durability::Renamed`], then [`sync_file_system`] at the end).
//! - Errors are [`IoError`]; each message starts with the file's path and includes the
//!   underlying cause (an OS or JSON error), which is not repeated by `source()`: an
//!   error chain prints each cause once. Bad input is an error, never a panic.
//! - Sizes declared in headers are checked before they size an allocation: overflow-checked
//!   arithmetic, compared with the file's length, and held to a memory budget
//!   ([`MAX_DECLARED_POINTS`], [`MAX_DECLARED_BYTES`], [`MAX_IMAGE_SIDE_PX`],
//!   [`MAX_IMAGE_DECODE_BYTES`]).

mod atomic;
mod boxes;
mod cloud_file;
mod direct;
mod error;
mod folder;
mod image;
mod limits;
mod listing;
mod lock;
mod mat;
mod pcd;
mod ply;
mod read_cloud;
mod text;

pub use atomic::{
    Durability, remove_temporaries, sync_file_system, write_atomic, write_atomic_with,
    write_bytes_atomic,
};
pub use boxes::{parse_boxes, read_boxes, write_boxes, write_boxes_with};
pub use cloud_file::{CloudFile, CloudGrid, FileLabels};
pub use direct::DirectFile;
pub use error::IoError;
pub use folder::{
    create_folder, discard_folder, image_files, publish_folder, require_folder, staging_folder,
};
pub use image::{
    ColorFile, ColorFileFormat, DepthImage, parse_color_file, parse_depth_png, parse_label_png,
    parse_rgb_image, read_color_file, read_depth_png, read_label_png, read_rgb_image,
    write_depth_png, write_gray8_png, write_label_png, write_label_png_with, write_rgb_png,
};
pub use limits::{
    MAX_DECLARED_BYTES, MAX_DECLARED_POINTS, MAX_IMAGE_DECODE_BYTES, MAX_IMAGE_SIDE_PX,
};
pub use listing::{FolderEntry, list_folder};
pub use lock::{FolderLock, LockError, lock_folder};
pub use mat::{
    MatMatrix, parse_mat_matrix, parse_mat_variable_names, read_mat_matrix, read_mat_variable_names,
};
pub use pcd::{parse_pcd, parse_pcd_file, read_pcd};
pub use ply::{
    PlyColors, PlyFormat, PlyWriteOptions, parse_ply, parse_ply_file, ply_bytes, read_ply,
    read_ply_file, write_ply,
};
pub use read_cloud::read_cloud_file;
pub use text::{first_existing_file, read_bytes, read_text};
