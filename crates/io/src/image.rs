//! Depth and label PNGs of a recording (FORMATS.md, "Recording"):
//! `<camera>/depth/<stem>.png` (16-bit grayscale, raw depth units, millimetres for Kinect
//! data, 0 = no measurement) and `<camera>/parsing/<stem>.png` (8-bit grayscale class ids,
//! 255 = not labelled). Colour images `<camera>/color/<stem>.png|.jpg` (8-bit RGB) are read
//! with [`read_rgb_image`].

use crate::limits::{MAX_IMAGE_DECODE_BYTES, MAX_IMAGE_SIDE_PX};
use crate::{Durability, IoError, write_atomic_with};
use bodyseg_core::{Label, LabelImage, RgbImage};
use image::codecs::png::PngEncoder;
use image::{DynamicImage, ExtendedColorType, ImageEncoder, ImageFormat, ImageReader, Limits};
use std::io::Cursor;
use std::path::Path;

/// One raw depth image, as stored in a recording.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DepthImage {
    /// Width, pixels (the depth sensor's).
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Raw depth per pixel, row-major (`v * width + u`), `width * height` entries; the
    /// camera's `depth_scale` says the unit (millimetres for Kinect data); 0 = no
    /// measurement.
    pub depth_mm: Vec<u16>,
}

impl DepthImage {
    /// Number of pixels, `width * height`.
    pub fn num_pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// What a depth PNG must hold.
const DEPTH_EXPECTED: &str = "16-bit millimetres";
/// What a label PNG must hold.
const LABEL_EXPECTED: &str = "8-bit grayscale class ids";

/// Reads a whole file.
fn read_file(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })
}

/// Decodes an image of `format` within the size limits ([`MAX_IMAGE_SIDE_PX`],
/// [`MAX_IMAGE_DECODE_BYTES`]), which the decoder checks against the header before it
/// allocates the pixels.
fn decode(bytes: &[u8], format: ImageFormat) -> image::ImageResult<DynamicImage> {
    let mut limits = Limits::no_limits();
    limits.max_image_width = Some(MAX_IMAGE_SIDE_PX);
    limits.max_image_height = Some(MAX_IMAGE_SIDE_PX);
    limits.max_alloc = Some(MAX_IMAGE_DECODE_BYTES);
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    reader.limits(limits);
    reader.decode()
}

/// Decodes the bytes of a PNG file.
fn decode_png(bytes: &[u8], path: &Path) -> Result<DynamicImage, IoError> {
    decode(bytes, ImageFormat::Png).map_err(|e| IoError::Png {
        cause: e.to_string(),
        path: path.to_path_buf(),
    })
}

/// `8-bit`, `16-bit RGB`, ...: a decoded image's pixel format as users know it.
fn describe_format(image: &DynamicImage) -> String {
    let color = image.color();
    let bits = color.bits_per_pixel() / u16::from(color.channel_count());
    let channels = match color.channel_count() {
        1 => "",
        2 => " grayscale with alpha",
        3 => " RGB",
        _ => " RGBA",
    };
    format!("{bits}-bit{channels}")
}

/// Reads a depth PNG: 16-bit grayscale, raw depth units (millimetres), 0 = no
/// measurement.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read; [`IoError::Png`] when it is not a
/// valid PNG; [`IoError::PixelFormat`] when it is not 16-bit grayscale (an 8-bit PNG reads
/// `x.png: depth PNG is 8-bit, expected 16-bit millimetres`). An image wider or higher
/// than [`MAX_IMAGE_SIDE_PX`](crate::MAX_IMAGE_SIDE_PX) is an [`IoError::Png`].
pub fn read_depth_png(path: &Path) -> Result<DepthImage, IoError> {
    parse_depth_png(&read_file(path)?, path)
}

/// [`read_depth_png`] on the bytes of a PNG file; `path_for_errors` only names the file in
/// error messages.
///
/// # Errors
/// As [`read_depth_png`], without the read.
pub fn parse_depth_png(bytes: &[u8], path_for_errors: &Path) -> Result<DepthImage, IoError> {
    let path = path_for_errors;
    let image = decode_png(bytes, path)?;
    let (width, height) = (image.width(), image.height());
    match image {
        DynamicImage::ImageLuma16(buf) => Ok(DepthImage {
            width,
            height,
            depth_mm: buf.into_raw(),
        }),
        other => Err(IoError::PixelFormat {
            what: "depth PNG",
            got: describe_format(&other),
            expected: DEPTH_EXPECTED,
            path: path.to_path_buf(),
        }),
    }
}

/// Reads a label PNG: 8-bit grayscale class ids (ALGORITHM.md §0), 255 = not labelled
/// ([`Label::UNKNOWN`]). The image has no probabilities.
///
/// # Errors
/// [`IoError::Read`], [`IoError::Png`] as [`read_depth_png`]; [`IoError::PixelFormat`]
/// when it is not 8-bit grayscale; [`IoError::BadLabelPixel`] naming the first pixel (row
/// by row) whose id is 7..=254.
pub fn read_label_png(path: &Path) -> Result<LabelImage, IoError> {
    parse_label_png(&read_file(path)?, path)
}

/// [`read_label_png`] on the bytes of a PNG file; `path_for_errors` only names the file in
/// error messages.
///
/// # Errors
/// As [`read_label_png`], without the read.
pub fn parse_label_png(bytes: &[u8], path_for_errors: &Path) -> Result<LabelImage, IoError> {
    let path = path_for_errors;
    let image = decode_png(bytes, path)?;
    let (width, height) = (image.width(), image.height());
    let DynamicImage::ImageLuma8(buf) = image else {
        return Err(IoError::PixelFormat {
            what: "label PNG",
            got: describe_format(&image),
            expected: LABEL_EXPECTED,
            path: path.to_path_buf(),
        });
    };
    let ids = buf.into_raw();
    let mut labels = Vec::with_capacity(ids.len());
    for (i, &id) in ids.iter().enumerate() {
        let Some(label) = Label::from_id(id) else {
            // width > 0 here: the image has at least pixel i.
            let w = width as usize;
            return Err(IoError::BadLabelPixel {
                u: (i % w) as u32,
                v: (i / w) as u32,
                id,
                path: path.to_path_buf(),
            });
        };
        labels.push(label);
    }
    LabelImage::new(width, height, labels).map_err(|e| IoError::Png {
        cause: e.to_string(),
        path: path.to_path_buf(),
    })
}

/// Reads a colour image, PNG or JPEG (the format is taken from the file's content, not its
/// extension), as 8-bit RGB: grayscale is replicated to the three channels, alpha is
/// dropped, 16-bit samples are scaled to 8 bits.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read; [`IoError::Decode`] when it is not a
/// decodable PNG or JPEG (`x.jpg: cannot decode colour image: ...`), or is larger than
/// [`MAX_IMAGE_SIDE_PX`](crate::MAX_IMAGE_SIDE_PX) on a side.
pub fn read_rgb_image(path: &Path) -> Result<RgbImage, IoError> {
    parse_rgb_image(&read_file(path)?, path)
}

/// [`read_rgb_image`] on the bytes of a PNG or JPEG file; `path_for_errors` only names the
/// file in error messages.
///
/// # Errors
/// As [`read_rgb_image`], without the read.
pub fn parse_rgb_image(bytes: &[u8], path_for_errors: &Path) -> Result<RgbImage, IoError> {
    let decode_err = |cause: String| decode_error(path_for_errors, cause);
    let format = color_file_format(bytes, path_for_errors)?.image_format();
    let decoded = decode(bytes, format).map_err(|e| decode_err(e.to_string()))?;
    let rgb = decoded.into_rgb8();
    let (width, height) = (rgb.width(), rgb.height());
    RgbImage::new(width, height, rgb.into_raw()).map_err(|e| decode_err(e.to_string()))
}

/// The format of a colour image file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorFileFormat {
    /// PNG.
    Png,
    /// JPEG.
    Jpeg,
}

/// A colour image file as stored (PNG or JPEG), not decoded: its bytes, and its format and
/// size as its header says. What a viewer that decodes images itself (the Rerun file of
/// `--rerun`) takes, without the cost of decoding here.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColorFile {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// PNG or JPEG, from the content (not the extension).
    pub format: ColorFileFormat,
    /// Width, pixels (from the header).
    pub width: u32,
    /// Height, pixels (from the header).
    pub height: u32,
}

impl ColorFileFormat {
    fn image_format(self) -> ImageFormat {
        match self {
            ColorFileFormat::Png => ImageFormat::Png,
            ColorFileFormat::Jpeg => ImageFormat::Jpeg,
        }
    }
}

/// The format of a colour image file from its content (not its extension): PNG or JPEG,
/// anything else an [`IoError::Decode`] naming the file.
fn color_file_format(bytes: &[u8], path_for_errors: &Path) -> Result<ColorFileFormat, IoError> {
    match image::guess_format(bytes).map_err(|e| decode_error(path_for_errors, e.to_string()))? {
        ImageFormat::Png => Ok(ColorFileFormat::Png),
        ImageFormat::Jpeg => Ok(ColorFileFormat::Jpeg),
        other => Err(decode_error(
            path_for_errors,
            format!("{other:?} images are not supported (PNG or JPEG)"),
        )),
    }
}

fn decode_error(path: &Path, cause: String) -> IoError {
    IoError::Decode {
        cause,
        path: path.to_path_buf(),
    }
}

impl ColorFile {
    /// Decodes the image as [`parse_rgb_image`] does; `path_for_errors` only names the file
    /// in error messages.
    ///
    /// # Errors
    /// As [`parse_rgb_image`].
    pub fn decode(&self, path_for_errors: &Path) -> Result<RgbImage, IoError> {
        parse_rgb_image(&self.bytes, path_for_errors)
    }
}

/// Reads a colour image file (PNG or JPEG) without decoding its pixels: the bytes, and the
/// format and size from the header.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read; [`IoError::Decode`] when it is neither
/// a PNG nor a JPEG, its header does not parse, or it is larger than
/// [`MAX_IMAGE_SIDE_PX`](crate::MAX_IMAGE_SIDE_PX) on a side. A file whose pixel data is
/// corrupt is not detected (nothing is decoded).
pub fn read_color_file(path: &Path) -> Result<ColorFile, IoError> {
    parse_color_file(read_file(path)?, path)
}

/// [`read_color_file`] on the bytes of a file; `path_for_errors` only names the file in
/// error messages.
///
/// # Errors
/// As [`read_color_file`], without the read.
pub fn parse_color_file(bytes: Vec<u8>, path_for_errors: &Path) -> Result<ColorFile, IoError> {
    let decode_err = |cause: String| decode_error(path_for_errors, cause);
    let format = color_file_format(&bytes, path_for_errors)?;
    let (width, height) = ImageReader::with_format(Cursor::new(&bytes), format.image_format())
        .into_dimensions()
        .map_err(|e| decode_err(e.to_string()))?;
    if width > MAX_IMAGE_SIDE_PX || height > MAX_IMAGE_SIDE_PX {
        return Err(decode_err(format!(
            "{width}x{height} pixels, more than {MAX_IMAGE_SIDE_PX} on a side"
        )));
    }
    Ok(ColorFile {
        bytes,
        format,
        width,
        height,
    })
}

/// Encodes `bytes` (native-endian samples) as a grayscale PNG and writes it atomically.
fn write_png(
    path: &Path,
    bytes: &[u8],
    width: u32,
    height: u32,
    color: ExtendedColorType,
    durability: Durability,
) -> Result<(), IoError> {
    let mut encoded = Vec::new();
    PngEncoder::new(&mut encoded)
        .write_image(bytes, width, height, color)
        .map_err(|e| IoError::Png {
            cause: e.to_string(),
            path: path.to_path_buf(),
        })?;
    write_atomic_with(path, durability, |w| w.write_all(&encoded))
}

/// Writes a depth image as a 16-bit grayscale PNG, atomically (see [`write_atomic`]).
///
/// # Errors
/// [`IoError::InvalidImage`] when `depth_mm` does not hold `width * height` values or the
/// image is empty (nothing is written); [`IoError::Write`] on I/O failure.
pub fn write_depth_png(path: &Path, image: &DepthImage) -> Result<(), IoError> {
    check_size(path, image.width, image.height, image.depth_mm.len())?;
    let bytes: Vec<u8> = image
        .depth_mm
        .iter()
        .flat_map(|d| d.to_ne_bytes())
        .collect();
    write_png(
        path,
        &bytes,
        image.width,
        image.height,
        ExtendedColorType::L16,
        Durability::Synced,
    )
}

/// Writes a label image as an 8-bit grayscale PNG of class ids (255 = unknown),
/// atomically. Probabilities, if any, are not stored.
///
/// # Errors
/// As [`write_depth_png`].
pub fn write_label_png(path: &Path, image: &LabelImage) -> Result<(), IoError> {
    write_label_png_with(path, image, Durability::Synced)
}

/// [`write_label_png`] with a choice of [`Durability`].
///
/// # Errors
/// As [`write_label_png`].
pub fn write_label_png_with(
    path: &Path,
    image: &LabelImage,
    durability: Durability,
) -> Result<(), IoError> {
    check_size(path, image.width, image.height, image.labels.len())?;
    let bytes: Vec<u8> = image.labels.iter().map(|l| l.id()).collect();
    write_png(
        path,
        &bytes,
        image.width,
        image.height,
        ExtendedColorType::L8,
        durability,
    )
}

/// Writes an RGB8 image (`rgb` row-major, 3 bytes per pixel) as PNG, atomically.
///
/// # Errors
/// As [`write_depth_png`].
pub fn write_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), IoError> {
    check_size(path, width, height, rgb.len() / 3)?;
    if !rgb.len().is_multiple_of(3) {
        return Err(IoError::InvalidImage {
            reason: format!("RGB buffer of {} bytes is not a multiple of 3", rgb.len()),
            path: path.to_path_buf(),
        });
    }
    write_png(
        path,
        rgb,
        width,
        height,
        ExtendedColorType::Rgb8,
        Durability::Synced,
    )
}

/// Writes 8-bit values (class ids, person ids) as an 8-bit grayscale PNG, atomically.
///
/// # Errors
/// As [`write_depth_png`].
pub fn write_gray8_png(path: &Path, width: u32, height: u32, values: &[u8]) -> Result<(), IoError> {
    check_size(path, width, height, values.len())?;
    write_png(
        path,
        values,
        width,
        height,
        ExtendedColorType::L8,
        Durability::Synced,
    )
}

/// `len == width * height > 0`, else [`IoError::InvalidImage`].
fn check_size(path: &Path, width: u32, height: u32, len: usize) -> Result<(), IoError> {
    let want = width as usize * height as usize;
    if want == 0 || len != want {
        return Err(IoError::InvalidImage {
            reason: format!("{width}x{height} image with {len} pixel values"),
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::Class;

    fn tempdir() -> tempfile::TempDir {
        tempfile::tempdir().expect("create temp dir")
    }

    #[test]
    fn depth_round_trips_every_value() {
        let dir = tempdir();
        let path = dir.path().join("d.png");
        // Values that differ in both bytes: a byte-order slip would show.
        let depth_mm: Vec<u16> = (0..12u16).map(|i| i.wrapping_mul(5471) ^ 0x0102).collect();
        let image = DepthImage {
            width: 4,
            height: 3,
            depth_mm,
        };
        write_depth_png(&path, &image).expect("write");
        assert_eq!(read_depth_png(&path).expect("read"), image);
    }

    #[test]
    fn labels_round_trip_with_unknown() {
        let dir = tempdir();
        let path = dir.path().join("l.png");
        let mut labels = vec![Label::BACKGROUND; 6];
        labels[1] = Label::from(Class::Head);
        labels[5] = Label::UNKNOWN;
        let image = LabelImage::new(3, 2, labels).expect("6 labels");
        write_label_png(&path, &image).expect("write");
        assert_eq!(read_label_png(&path).expect("read"), image);
    }

    #[test]
    fn rgb_png_round_trips_and_junk_is_a_decode_error() {
        let dir = tempdir();
        let path = dir.path().join("c.png");
        let rgb: Vec<u8> = (0..18u8).map(|i| i.wrapping_mul(37)).collect();
        write_rgb_png(&path, 3, 2, &rgb).expect("write");
        let image = read_rgb_image(&path).expect("read");
        assert_eq!((image.width, image.height), (3, 2));
        assert_eq!(image.rgb, rgb);

        // A grayscale PNG reads as RGB with equal channels.
        let gray = dir.path().join("g.png");
        write_gray8_png(&gray, 2, 1, &[10, 200]).expect("write");
        let image = read_rgb_image(&gray).expect("read gray");
        assert_eq!(image.rgb, vec![10, 10, 10, 200, 200, 200]);

        let junk = dir.path().join("junk.jpg");
        std::fs::write(&junk, b"not an image at all").expect("write junk");
        let e = read_rgb_image(&junk).expect_err("junk").to_string();
        assert!(
            e.starts_with(&format!("{}: cannot decode colour image: ", junk.display())),
            "{e}"
        );
    }

    #[test]
    fn color_file_keeps_the_bytes_and_reads_the_size_from_the_header() {
        let dir = tempdir();
        let path = dir.path().join("c.png");
        let rgb: Vec<u8> = (0..18u8).map(|i| i.wrapping_mul(37)).collect();
        write_rgb_png(&path, 3, 2, &rgb).expect("write");
        let file = read_color_file(&path).expect("read");
        assert_eq!(file.bytes, std::fs::read(&path).expect("bytes"));
        assert_eq!(
            (file.format, file.width, file.height),
            (ColorFileFormat::Png, 3, 2)
        );
        assert_eq!(
            file.decode(&path).expect("decode"),
            read_rgb_image(&path).expect("decode")
        );

        let junk = dir.path().join("junk.png");
        std::fs::write(&junk, b"not an image at all").expect("write junk");
        let e = read_color_file(&junk).expect_err("junk").to_string();
        assert!(
            e.starts_with(&format!("{}: cannot decode colour image: ", junk.display())),
            "{e}"
        );
        // A PNG signature with a truncated header.
        let truncated = dir.path().join("t.png");
        let bytes = std::fs::read(&path).expect("bytes");
        std::fs::write(&truncated, &bytes[..12]).expect("write truncated");
        assert!(read_color_file(&truncated).is_err());
    }

    #[test]
    fn jpeg_decodes_to_rgb() {
        let dir = tempdir();
        let path = dir.path().join("c.jpg");
        let rgb = vec![128u8; 8 * 8 * 3];
        let mut encoded = Vec::new();
        image::codecs::jpeg::JpegEncoder::new(&mut encoded)
            .write_image(&rgb, 8, 8, ExtendedColorType::Rgb8)
            .expect("encode JPEG");
        std::fs::write(&path, &encoded).expect("write");
        let image = read_rgb_image(&path).expect("read JPEG");
        assert_eq!((image.width, image.height), (8, 8));
        // JPEG is lossy: a flat grey stays within a few levels.
        assert!(
            image.rgb.iter().all(|&b| b.abs_diff(128) <= 2),
            "{:?}",
            &image.rgb[..6]
        );
    }

    #[test]
    fn eight_bit_depth_is_refused_naming_the_file() {
        let dir = tempdir();
        let path = dir.path().join("d8.png");
        let image = LabelImage::filled(4, 2, Label::BACKGROUND);
        write_label_png(&path, &image).expect("write");
        let e = read_depth_png(&path).expect_err("8-bit").to_string();
        assert_eq!(
            e,
            format!(
                "{}: depth PNG is 8-bit, expected 16-bit millimetres",
                path.display()
            )
        );
    }

    #[test]
    fn sixteen_bit_labels_and_bad_ids_are_refused() {
        let dir = tempdir();
        let path = dir.path().join("l16.png");
        let depth = DepthImage {
            width: 2,
            height: 2,
            depth_mm: vec![0; 4],
        };
        write_depth_png(&path, &depth).expect("write");
        let e = read_label_png(&path).expect_err("16-bit").to_string();
        assert!(
            e.ends_with("label PNG is 16-bit, expected 8-bit grayscale class ids"),
            "{e}"
        );

        let path = dir.path().join("bad.png");
        let mut bytes = vec![0u8; 6];
        bytes[4] = 7; // (u 1, v 1) of a 3x2 image
        write_png(
            &path,
            &bytes,
            3,
            2,
            ExtendedColorType::L8,
            Durability::Synced,
        )
        .expect("write");
        let e = read_label_png(&path).expect_err("id 7").to_string();
        assert!(
            e.contains("pixel (u 1, v 1): label id 7 is not a class id"),
            "{e}"
        );
    }

    #[test]
    fn missing_and_corrupt_files_name_the_file() {
        let dir = tempdir();
        let path = dir.path().join("none.png");
        let e = read_depth_png(&path).expect_err("missing").to_string();
        assert!(
            e.starts_with(&format!("{}: cannot read: ", path.display())),
            "{e}"
        );
        std::fs::write(&path, b"not a png").expect("write junk");
        let e = read_label_png(&path).expect_err("junk").to_string();
        assert!(
            e.starts_with(&format!("{}: bad PNG: ", path.display())),
            "{e}"
        );
    }

    #[test]
    fn writers_refuse_inconsistent_images_and_write_nothing() {
        let dir = tempdir();
        let path = dir.path().join("x.png");
        let image = DepthImage {
            width: 3,
            height: 2,
            depth_mm: vec![0; 5],
        };
        assert!(matches!(
            write_depth_png(&path, &image),
            Err(IoError::InvalidImage { .. })
        ));
        assert!(!path.exists());
    }
}
