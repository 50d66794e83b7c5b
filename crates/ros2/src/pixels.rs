//! Pixels out of image messages: depth in millimetres (`u16`, 0 = no measurement) and
//! colour as 8-bit RGB, or a JPEG passed through as it is.
//!
//! | message | encoding / format | becomes |
//! |---|---|---|
//! | `Image` | `16UC1`, `mono16` (millimetres) | depth as is |
//! | `Image` | `32FC1` (metres) | depth `round(1000 z)`; NaN, ±inf, ≤ 0 and > 65.535 m → 0 |
//! | `Image` | `rgb8`, `bgr8`, `rgba8`, `bgra8`, `mono8` | RGB (alpha dropped, grey repeated) |
//! | `CompressedImage` | JPEG (`jpeg`, `bgr8; jpeg compressed bgr8`, ...) | the JPEG's bytes |
//! | `CompressedImage` | PNG, 8-bit | RGB |
//! | `CompressedImage` | `16UC1; compressedDepth png` (image_transport_plugins) | depth as is |
//! | `CompressedImage` | `32FC1; compressedDepth png` | depth `A / (q - B)` metres → mm (q = 0 → 0) |
//! | `CompressedImage` | `16UC1; png compressed ...` (a plain 16-bit PNG) | depth as is |
//!
//! `compressedDepth` (compressed_depth_image_transport, `codec.cpp`) prefixes the PNG with
//! a 12-byte `ConfigHeader`: an `int32` format (0 = inverse depth) and two `float32`
//! quantisation parameters A, B, in the publisher's byte order (little endian on every
//! platform ROS 2 ships for). RVL-compressed depth is not read.

use crate::Ros2Error;
use crate::msg::{CompressedImageMsg, ImageMsg};
use image::{ImageFormat, ImageReader};
use std::io::Cursor;

/// Size of compressed_depth_image_transport's `ConfigHeader`, bytes.
const COMPRESSED_DEPTH_HEADER_LEN: usize = 12;

/// Largest depth a 16-bit millimetre image holds, metres.
const MAX_DEPTH_M: f32 = 65.535;

/// What an image topic carries, told by its first message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageRole {
    /// Depth (16-bit millimetres or 32-bit float metres).
    Depth,
    /// Colour or grey.
    Color,
}

/// Image encodings read as depth.
pub const DEPTH_ENCODINGS: &str = "16UC1, mono16 (millimetres), 32FC1 (metres)";
/// Image encodings read as colour.
pub const COLOR_ENCODINGS: &str = "rgb8, bgr8, rgba8, bgra8, mono8";

/// The role of a `sensor_msgs/Image` by its encoding; `None` for other encodings.
pub fn image_role(encoding: &str) -> Option<ImageRole> {
    match encoding {
        "16UC1" | "mono16" | "32FC1" => Some(ImageRole::Depth),
        "rgb8" | "bgr8" | "rgba8" | "bgra8" | "mono8" => Some(ImageRole::Color),
        _ => None,
    }
}

/// The role of a `sensor_msgs/CompressedImage` by its format: depth when the format names
/// `compressedDepth` or a depth encoding before its `;`.
pub fn compressed_role(format: &str) -> ImageRole {
    let encoding = format.split(';').next().unwrap_or("").trim();
    if format.contains("compressedDepth") || matches!(encoding, "16UC1" | "mono16" | "32FC1") {
        ImageRole::Depth
    } else {
        ImageRole::Color
    }
}

/// Bytes per pixel of a supported encoding.
fn bytes_per_pixel(encoding: &str) -> Option<usize> {
    Some(match encoding {
        "mono8" => 1,
        "16UC1" | "mono16" => 2,
        "rgb8" | "bgr8" => 3,
        "rgba8" | "bgra8" | "32FC1" => 4,
        _ => return None,
    })
}

/// Checks that an `Image` has a supported encoding for `role`, a non-empty size, and rows
/// that fit its data; returns the bytes per pixel.
///
/// # Errors
/// [`Ros2Error::Unsupported`] naming `encoding`, or [`Ros2Error::Invalid`] naming `step`,
/// `width`/`height` or `data`.
pub fn check_image(msg: &ImageMsg<'_>, role: ImageRole) -> Result<usize, Ros2Error> {
    let supported = match role {
        ImageRole::Depth => DEPTH_ENCODINGS,
        ImageRole::Color => COLOR_ENCODINGS,
    };
    let bpp = bytes_per_pixel(&msg.encoding)
        .filter(|_| image_role(&msg.encoding) == Some(role))
        .ok_or_else(|| Ros2Error::Unsupported {
            field: "encoding".into(),
            value: msg.encoding.clone(),
            supported: format!("{} images: {supported}", role_name(role)),
        })?;
    if msg.width == 0 || msg.height == 0 {
        return Err(Ros2Error::invalid(format!(
            "width x height is {}x{}: an empty image",
            msg.width, msg.height
        )));
    }
    let row = msg.width as usize * bpp;
    if (msg.step as usize) < row {
        return Err(Ros2Error::invalid(format!(
            "step is {} bytes, a row of {} {} pixels needs {row}",
            msg.step, msg.width, msg.encoding
        )));
    }
    let need = msg.step as usize * (msg.height as usize - 1) + row;
    if msg.data.len() < need {
        return Err(Ros2Error::invalid(format!(
            "data has {} bytes, {}x{} {} with step {} needs {need}",
            msg.data.len(),
            msg.width,
            msg.height,
            msg.encoding,
            msg.step
        )));
    }
    Ok(bpp)
}

fn role_name(role: ImageRole) -> &'static str {
    match role {
        ImageRole::Depth => "depth",
        ImageRole::Color => "colour",
    }
}

/// Rows of an image's pixels, each `width * bpp` bytes (the row padding dropped).
fn rows<'a>(msg: &'a ImageMsg<'_>, bpp: usize) -> impl Iterator<Item = &'a [u8]> + 'a {
    let row = msg.width as usize * bpp;
    (0..msg.height as usize).map(move |y| {
        let start = y * msg.step as usize;
        &msg.data[start..start + row]
    })
}

/// Metres to millimetres as a 16-bit depth (0 where there is no measurement or it does
/// not fit).
fn metres_to_mm(z_m: f32) -> u16 {
    if z_m.is_finite() && z_m > 0.0 && z_m <= MAX_DEPTH_M {
        (z_m * 1000.0).round() as u16
    } else {
        0
    }
}

/// A depth `Image` in millimetres, row-major, `width * height` values.
///
/// # Errors
/// As [`check_image`] for [`ImageRole::Depth`].
pub fn depth_mm_of_image(msg: &ImageMsg<'_>) -> Result<Vec<u16>, Ros2Error> {
    let bpp = check_image(msg, ImageRole::Depth)?;
    let mut out = Vec::with_capacity(msg.width as usize * msg.height as usize);
    let big = msg.is_bigendian;
    for row in rows(msg, bpp) {
        if bpp == 2 {
            out.extend(row.chunks_exact(2).map(|b| {
                let b = [b[0], b[1]];
                if big {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }
            }));
        } else {
            out.extend(row.chunks_exact(4).map(|b| {
                let b = [b[0], b[1], b[2], b[3]];
                metres_to_mm(if big {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                })
            }));
        }
    }
    Ok(out)
}

/// A colour `Image` as 8-bit RGB, row-major, `3 * width * height` bytes.
///
/// # Errors
/// As [`check_image`] for [`ImageRole::Colour`].
pub fn rgb_of_image(msg: &ImageMsg<'_>) -> Result<Vec<u8>, Ros2Error> {
    let bpp = check_image(msg, ImageRole::Color)?;
    let mut out = Vec::with_capacity(3 * msg.width as usize * msg.height as usize);
    let encoding = msg.encoding.as_str();
    for row in rows(msg, bpp) {
        match encoding {
            "rgb8" => out.extend_from_slice(row),
            "mono8" => out.extend(row.iter().flat_map(|&g| [g, g, g])),
            "bgr8" => out.extend(row.chunks_exact(3).flat_map(|p| [p[2], p[1], p[0]])),
            "rgba8" => out.extend(row.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]])),
            // bgra8, the last one check_image lets through.
            _ => out.extend(row.chunks_exact(4).flat_map(|p| [p[2], p[1], p[0]])),
        }
    }
    Ok(out)
}

/// A colour image ready to be written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Color {
    /// Decoded pixels, 8-bit RGB, row-major.
    Rgb {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// `3 * width * height` bytes.
        rgb: Vec<u8>,
    },
    /// A JPEG, passed through undecoded (its size read from its header).
    Jpeg {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// The JPEG file's bytes.
        bytes: Vec<u8>,
    },
}

impl Color {
    /// Width and height, pixels.
    pub fn size(&self) -> (u32, u32) {
        match self {
            Color::Rgb { width, height, .. } | Color::Jpeg { width, height, .. } => {
                (*width, *height)
            }
        }
    }
}

fn decode_error(what: &str, e: impl std::fmt::Display) -> Ros2Error {
    Ros2Error::invalid(format!("data: the {what} does not decode: {e}"))
}

/// The format (PNG or JPEG) of compressed bytes, from their signature.
fn compressed_format(data: &[u8], what: &str) -> Result<ImageFormat, Ros2Error> {
    match image::guess_format(data) {
        Ok(f @ (ImageFormat::Png | ImageFormat::Jpeg)) => Ok(f),
        Ok(other) => Err(Ros2Error::invalid(format!(
            "data: the {what} is {other:?}; bodyseg reads PNG and JPEG"
        ))),
        Err(e) => Err(decode_error(what, e)),
    }
}

/// Width and height of a compressed image from its header, without decoding it.
fn compressed_size(data: &[u8], what: &str) -> Result<(u32, u32), Ros2Error> {
    let format = compressed_format(data, what)?;
    ImageReader::with_format(Cursor::new(data), format)
        .into_dimensions()
        .map_err(|e| decode_error(what, e))
}

/// Size of the image in a `CompressedImage` of `role`, from its header (cheap: nothing is
/// decompressed).
///
/// # Errors
/// The format is not supported for the role ([`Ros2Error::Unsupported`] naming `format`),
/// the `compressedDepth` header is short, or the image's header does not decode.
pub fn compressed_image_size(
    msg: &CompressedImageMsg<'_>,
    role: ImageRole,
) -> Result<(u32, u32), Ros2Error> {
    match role {
        ImageRole::Color => compressed_size(msg.data, "compressed colour image"),
        ImageRole::Depth => {
            let (_, png) = compressed_depth_parts(msg)?;
            compressed_size(png, "compressed depth image")
        }
    }
}

/// A colour `CompressedImage`: a JPEG passed through, a PNG decoded to RGB.
///
/// # Errors
/// The bytes are neither PNG nor JPEG, or do not decode.
pub fn color_of_compressed(msg: &CompressedImageMsg<'_>) -> Result<Color, Ros2Error> {
    const WHAT: &str = "compressed colour image";
    match compressed_format(msg.data, WHAT)? {
        ImageFormat::Jpeg => {
            let (width, height) = compressed_size(msg.data, WHAT)?;
            Ok(Color::Jpeg {
                width,
                height,
                bytes: msg.data.to_vec(),
            })
        }
        _ => {
            let decoded = image::load_from_memory_with_format(msg.data, ImageFormat::Png)
                .map_err(|e| decode_error(WHAT, e))?
                .into_rgb8();
            Ok(Color::Rgb {
                width: decoded.width(),
                height: decoded.height(),
                rgb: decoded.into_raw(),
            })
        }
    }
}

/// How a compressed depth image stores depth.
#[derive(Clone, Copy, Debug, PartialEq)]
enum DepthCoding {
    /// 16-bit millimetres as they are.
    Millimetres,
    /// compressedDepth of a `32FC1` image: inverse depth `q = A / z + B`.
    InverseDepth { a: f32, b: f32 },
}

/// The depth coding and PNG bytes of a depth `CompressedImage`.
fn compressed_depth_parts<'a>(
    msg: &'a CompressedImageMsg<'_>,
) -> Result<(DepthCoding, &'a [u8]), Ros2Error> {
    let (encoding, rest) = match msg.format.split_once(';') {
        Some((e, rest)) => (e.trim(), rest),
        None => (msg.format.trim(), ""),
    };
    let unsupported = |supported: &str| Ros2Error::Unsupported {
        field: "format".into(),
        value: msg.format.clone(),
        supported: supported.into(),
    };
    if !msg.format.contains("compressedDepth") {
        // A plain 16-bit PNG of millimetres (compressed_image_transport's png).
        return match encoding {
            "16UC1" | "mono16" if rest.contains("png") => Ok((DepthCoding::Millimetres, msg.data)),
            _ => Err(unsupported(
                "depth: \"16UC1; compressedDepth png\", \"32FC1; compressedDepth png\" or \
                 \"16UC1; png compressed\"",
            )),
        };
    }
    if rest.contains("rvl") {
        return Err(unsupported(
            "compressedDepth png; RVL is not read: republish with format png",
        ));
    }
    if msg.data.len() <= COMPRESSED_DEPTH_HEADER_LEN {
        return Err(Ros2Error::invalid(format!(
            "data: {} bytes, a compressedDepth image has a 12-byte header and a PNG",
            msg.data.len()
        )));
    }
    let (head, png) = msg.data.split_at(COMPRESSED_DEPTH_HEADER_LEN);
    let f32_at = |i: usize| f32::from_le_bytes([head[i], head[i + 1], head[i + 2], head[i + 3]]);
    let coding = match encoding {
        "16UC1" | "mono16" => DepthCoding::Millimetres,
        "32FC1" => {
            let format = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
            if format != 0 {
                return Err(Ros2Error::invalid(format!(
                    "data: compressedDepth header format {format}, only 0 (inverse depth) \
                     exists"
                )));
            }
            DepthCoding::InverseDepth {
                a: f32_at(4),
                b: f32_at(8),
            }
        }
        _ => return Err(unsupported("compressedDepth of 16UC1, mono16 or 32FC1")),
    };
    Ok((coding, png))
}

/// A depth `CompressedImage` in millimetres: `(width, height, depth_mm)`.
///
/// # Errors
/// An unsupported format (naming `format`), a short header, a PNG that does not decode or
/// is not 16-bit grey.
pub fn depth_mm_of_compressed(
    msg: &CompressedImageMsg<'_>,
) -> Result<(u32, u32, Vec<u16>), Ros2Error> {
    const WHAT: &str = "compressed depth image";
    let (coding, png) = compressed_depth_parts(msg)?;
    if compressed_format(png, WHAT)? != ImageFormat::Png {
        return Err(Ros2Error::invalid(
            "data: a compressed depth image must be a PNG",
        ));
    }
    let decoded = image::load_from_memory_with_format(png, ImageFormat::Png)
        .map_err(|e| decode_error(WHAT, e))?;
    let image::DynamicImage::ImageLuma16(gray) = decoded else {
        return Err(Ros2Error::invalid(format!(
            "data: the compressed depth PNG is {:?}, not 16-bit grey",
            decoded.color()
        )));
    };
    let (width, height) = gray.dimensions();
    let raw = gray.into_raw();
    let depth_mm = match coding {
        DepthCoding::Millimetres => raw,
        DepthCoding::InverseDepth { a, b } => raw
            .into_iter()
            .map(|q| {
                if q == 0 {
                    0
                } else {
                    metres_to_mm(a / (f32::from(q) - b))
                }
            })
            .collect(),
    };
    Ok((width, height, depth_mm))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::Header;

    fn image<'a>(encoding: &str, width: u32, step: u32, data: &'a [u8]) -> ImageMsg<'a> {
        ImageMsg {
            header: Header::default(),
            height: (data.len() / step as usize) as u32,
            width,
            encoding: encoding.into(),
            is_bigendian: false,
            step,
            data,
        }
    }

    #[test]
    fn color_encodings_become_rgb_and_row_padding_is_dropped() {
        // 2x1 bgr8 with 2 bytes of padding per row.
        let bgr = image("bgr8", 2, 8, &[1, 2, 3, 4, 5, 6, 0, 0]);
        assert_eq!(rgb_of_image(&bgr).expect("bgr8"), [3, 2, 1, 6, 5, 4]);
        let bgra = image("bgra8", 1, 4, &[1, 2, 3, 255]);
        assert_eq!(rgb_of_image(&bgra).expect("bgra8"), [3, 2, 1]);
        let rgba = image("rgba8", 1, 4, &[1, 2, 3, 255]);
        assert_eq!(rgb_of_image(&rgba).expect("rgba8"), [1, 2, 3]);
        let mono = image("mono8", 2, 2, &[9, 8]);
        assert_eq!(rgb_of_image(&mono).expect("mono8"), [9, 9, 9, 8, 8, 8]);
    }

    #[test]
    fn depth_in_metres_becomes_millimetres_and_invalid_values_zero() {
        let values = [1.2344f32, f32::NAN, -1.0, 70.0, 0.0005];
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let msg = image("32FC1", 5, 20, &data);
        assert_eq!(depth_mm_of_image(&msg).expect("32FC1"), [1234, 0, 0, 0, 1]);
        let mut big = image("16UC1", 1, 2, &[0x01, 0x02]);
        big.is_bigendian = true;
        assert_eq!(depth_mm_of_image(&big).expect("16UC1 BE"), [0x0102]);
    }

    #[test]
    fn wrong_encodings_and_sizes_are_errors_naming_the_field() {
        let e = depth_mm_of_image(&image("rgb8", 1, 3, &[0; 3])).expect_err("colour as depth");
        assert!(e.to_string().contains("field encoding: \"rgb8\""), "{e}");
        let e = rgb_of_image(&image("yuv422", 1, 2, &[0; 2])).expect_err("yuv");
        assert!(e.to_string().contains("yuv422"), "{e}");
        let e = rgb_of_image(&image("rgb8", 2, 3, &[0; 3])).expect_err("step");
        assert!(e.to_string().contains("step"), "{e}");
        let mut short = image("rgb8", 1, 3, &[0; 3]);
        short.height = 2;
        let e = rgb_of_image(&short).expect_err("data");
        assert!(e.to_string().contains("data has 3 bytes"), "{e}");
    }

    fn png16(values: &[u16], width: u32) -> Vec<u8> {
        let mut out = Vec::new();
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut out),
            &bytes,
            width,
            values.len() as u32 / width,
            image::ExtendedColorType::L16,
        )
        .expect("png");
        out
    }

    #[test]
    fn compressed_depth_png_of_both_encodings() {
        let mut data = vec![0u8; 12];
        data.extend(png16(&[1000, 0, 65535], 3));
        let msg = CompressedImageMsg {
            header: Header::default(),
            format: "16UC1; compressedDepth png".into(),
            data: &data,
        };
        assert_eq!(
            depth_mm_of_compressed(&msg).expect("16UC1"),
            (3, 1, vec![1000, 0, 65535])
        );
        assert_eq!(
            compressed_image_size(&msg, ImageRole::Depth).expect("size"),
            (3, 1)
        );
        // 32FC1: q = A / z + B with the publisher's defaults (depth_max 10 m,
        // quantisation 100): A = 100 · 101, B = 1 - A / 10.
        let (a, b) = (100.0f32 * 101.0, 1.0 - 100.0 * 101.0 / 10.0);
        let q = |z: f32| (a / z + b) as u16;
        let mut data = vec![0u8; 4];
        data.extend(a.to_le_bytes());
        data.extend(b.to_le_bytes());
        data.extend(png16(&[q(2.0), 0], 2));
        let msg = CompressedImageMsg {
            header: Header::default(),
            format: "32FC1; compressedDepth".into(),
            data: &data,
        };
        let (_, _, mm) = depth_mm_of_compressed(&msg).expect("32FC1");
        // Quantisation at 2 m: one step of q is ~0.4 mm.
        assert!((i32::from(mm[0]) - 2000).abs() <= 1, "{mm:?}");
        assert_eq!(mm[1], 0);
        let rvl = CompressedImageMsg {
            format: "16UC1; compressedDepth rvl".into(),
            ..msg
        };
        let e = depth_mm_of_compressed(&rvl).expect_err("rvl");
        assert!(e.to_string().contains("RVL"), "{e}");
    }

    #[test]
    fn roles_of_compressed_formats() {
        assert_eq!(
            compressed_role("16UC1; compressedDepth png"),
            ImageRole::Depth
        );
        assert_eq!(compressed_role("32FC1; compressedDepth"), ImageRole::Depth);
        assert_eq!(
            compressed_role("bgr8; jpeg compressed bgr8"),
            ImageRole::Color
        );
        assert_eq!(compressed_role("jpeg"), ImageRole::Color);
    }
}
