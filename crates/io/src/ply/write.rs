//! PLY writer: FORMATS.md's exact vertex layout, binary little-endian or ASCII.

use crate::{Durability, IoError, write_atomic_with};
use bodyseg_core::LabeledCloud;
use std::io::{self, Write};
use std::path::Path;

/// Byte encoding of a written PLY file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PlyFormat {
    /// `binary_little_endian`: compact and exact (FORMATS.md's default).
    #[default]
    BinaryLittleEndian,
    /// `ascii`: one line per point, for reading by eye. Coordinates are written with the
    /// shortest decimal that reads back to the same `f32`, so it is exact too.
    Ascii,
}

/// What goes into the `red`, `green`, `blue` properties.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PlyColors {
    /// The class palette ([`bodyseg_core::Label::color`]; unknown is white), so any viewer
    /// shows the labels.
    #[default]
    Palette,
    /// The cloud's camera colours ([`LabeledCloud::colors`]); writing fails when the cloud
    /// has none.
    Camera,
}

/// How [`write_ply`] encodes a cloud. The default is FORMATS.md's: binary little-endian,
/// palette colours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PlyWriteOptions {
    /// Byte encoding.
    pub format: PlyFormat,
    /// Colour source.
    pub colors: PlyColors,
    /// fsync or not (see [`Durability`]); synced by default.
    pub durability: Durability,
}

/// Bytes per vertex in the binary encoding: 3 × f32, 3 × u8 colour, u8 label, u8
/// camera, u32 pixel.
const RECORD_BYTES: usize = 12 + 3 + 1 + 1 + 4;

/// Writes `cloud` to `path` atomically (see [`crate::write_atomic`]) in FORMATS.md's layout:
/// one `vertex` element with `float x, y, z`, `uchar red, green, blue`, `uchar label`
/// (255 = unknown), `uchar camera`, `uint pixel`, in the cloud's point order.
///
/// # Errors
/// [`IoError::InvalidCloud`] when [`LabeledCloud::validate`] fails (array lengths differ
/// or a coordinate is not finite), [`IoError::NoCameraColors`] when
/// [`PlyColors::Camera`] is asked of a cloud without colours (in both cases nothing is
/// written), [`IoError::Write`] on I/O failure (the destination is left untouched).
pub fn write_ply(path: &Path, cloud: &LabeledCloud, opts: &PlyWriteOptions) -> Result<(), IoError> {
    check(cloud, opts, path)?;
    write_atomic_with(path, opts.durability, |w| encode(cloud, opts, w))
}

/// The bytes [`write_ply`] would write; `path_for_errors` only names the destination in
/// error messages.
///
/// # Errors
/// [`IoError::InvalidCloud`] and [`IoError::NoCameraColors`], as [`write_ply`].
pub fn ply_bytes(
    cloud: &LabeledCloud,
    opts: &PlyWriteOptions,
    path_for_errors: &Path,
) -> Result<Vec<u8>, IoError> {
    check(cloud, opts, path_for_errors)?;
    let mut out = Vec::with_capacity(512 + cloud.len() * RECORD_BYTES);
    encode(cloud, opts, &mut out).map_err(|cause| IoError::Write {
        cause,
        path: path_for_errors.to_path_buf(),
    })?;
    Ok(out)
}

/// Everything that can be wrong with the input, checked before any byte is written.
fn check(cloud: &LabeledCloud, opts: &PlyWriteOptions, path: &Path) -> Result<(), IoError> {
    cloud.validate().map_err(|cause| IoError::InvalidCloud {
        cause,
        path: path.to_path_buf(),
    })?;
    if opts.colors == PlyColors::Camera && cloud.colors.is_none() {
        return Err(IoError::NoCameraColors {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

/// Writes header and data; the cloud has passed [`check`].
fn encode(cloud: &LabeledCloud, opts: &PlyWriteOptions, w: &mut dyn Write) -> io::Result<()> {
    let format = match opts.format {
        PlyFormat::BinaryLittleEndian => "binary_little_endian",
        PlyFormat::Ascii => "ascii",
    };
    let color_source = match opts.colors {
        PlyColors::Palette => "class palette", // read back as no colours (PALETTE_COMMENT)
        PlyColors::Camera => "camera colour",
    };
    write!(
        w,
        "ply\nformat {format} 1.0\n\
         comment bodyseg labelled point cloud (bodyseg-io {}); red green blue = {color_source}; label 255 = unknown\n\
         element vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property uchar label\nproperty uchar camera\nproperty uint pixel\n\
         end_header\n",
        env!("CARGO_PKG_VERSION"),
        cloud.len(),
    )?;
    let camera_colors = match opts.colors {
        PlyColors::Camera => cloud.colors.as_deref(),
        PlyColors::Palette => None,
    };
    // Encode in chunks: one write call per chunk rather than per value.
    const CHUNK_POINTS: usize = 4096;
    let mut buf = Vec::with_capacity(CHUNK_POINTS * 64);
    for start in (0..cloud.len()).step_by(CHUNK_POINTS) {
        buf.clear();
        for i in start..(start + CHUNK_POINTS).min(cloud.len()) {
            let p = cloud.positions_m[i];
            let label = cloud.labels[i];
            let rgb = camera_colors.map_or_else(|| label.color(), |c| c[i]);
            let o = cloud.origins[i];
            match opts.format {
                PlyFormat::BinaryLittleEndian => {
                    // One fixed-size record, one copy: no capacity check per field.
                    let mut record = [0u8; RECORD_BYTES];
                    record[0..4].copy_from_slice(&p[0].to_le_bytes());
                    record[4..8].copy_from_slice(&p[1].to_le_bytes());
                    record[8..12].copy_from_slice(&p[2].to_le_bytes());
                    record[12..15].copy_from_slice(&rgb);
                    record[15] = label.id();
                    record[16] = o.camera;
                    record[17..21].copy_from_slice(&o.pixel.to_le_bytes());
                    buf.extend_from_slice(&record);
                }
                PlyFormat::Ascii => {
                    // `{}` on f32 prints the shortest decimal that parses back exactly.
                    writeln!(
                        buf,
                        "{} {} {} {} {} {} {} {} {}",
                        p[0],
                        p[1],
                        p[2],
                        rgb[0],
                        rgb[1],
                        rgb[2],
                        label.id(),
                        o.camera,
                        o.pixel
                    )?;
                }
            }
        }
        w.write_all(&buf)?;
    }
    Ok(())
}
