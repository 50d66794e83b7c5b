//! The memory budget for sizes that files declare in their headers.
//!
//! A header's numbers (a PCD's `POINTS` and `COUNT`, a MAT array's dimensions, a PNG's
//! width and height) are checked with overflow-checked arithmetic, compared with the
//! file's length where the data is stored as is, and held to these limits where it is
//! compressed, before anything is allocated: a corrupt or hostile header is an error, not
//! an out-of-memory abort of a whole batch.

/// Most points a cloud file may declare: 2³⁰ (about 1.07 billion). bodyseg's inputs are
/// RGB-D frames: four Kinect v2 depth images hold under a million points, and a cloud of
/// 2³⁰ points already takes about 24 GiB as a `LabeledCloud`.
pub const MAX_DECLARED_POINTS: u64 = 1 << 30;

/// Most bytes of point or matrix data a file may declare: 4 GiB, decoded (a PCD's point
/// records, a MAT matrix's values as `f64`). A 512 × 424 Kinect v2 depth map is 1.7 MB
/// as `f64`, a 1920 × 1080 one 16.6 MB: 4 GiB is hundreds of times what a real input needs,
/// and below what the machines bodyseg runs on can hold twice.
pub const MAX_DECLARED_BYTES: u64 = 4 << 30;

/// Largest image side accepted when decoding a PNG or JPEG, pixels: 16384, four times a
/// 4K frame's width; no RGB-D sensor comes near. Checked from the image header before
/// the pixels are decoded.
pub const MAX_IMAGE_SIDE_PX: u32 = 16_384;

/// Most memory the image decoder may allocate for one image: 512 MiB (the `image`
/// crate's default, stated here): a 16384 × 16384 16-bit depth map, or an 8-bit RGB
/// image of 178 megapixels.
pub const MAX_IMAGE_DECODE_BYTES: u64 = 512 << 20;
