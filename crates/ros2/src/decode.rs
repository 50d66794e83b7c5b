//! The second pass: the pixels of the messages a plan chose, checked against the rig's
//! sensor sizes.

use crate::Ros2Error;
use crate::msg::{MsgKind, decode_compressed_image, decode_image};
use crate::pixels::{Color, depth_mm_of_compressed, depth_mm_of_image, rgb_of_image};

/// `Err` unless `got` is `want`.
fn check_size(got: (u32, u32), want: (u32, u32), what: &str) -> Result<(), Ros2Error> {
    if got != want {
        return Err(Ros2Error::invalid(format!(
            "{what} image is {}x{}, its CameraInfo (the rig) says {}x{}",
            got.0, got.1, want.0, want.1
        )));
    }
    Ok(())
}

/// The depth image (millimetres, row-major) of a depth message of `kind`, which must be
/// `size` (width, height).
///
/// # Errors
/// The message does not decode, its encoding or format is not a depth one, or its size
/// is not `size`. The caller adds the topic and stamp.
pub fn decode_depth(kind: MsgKind, data: &[u8], size: (u32, u32)) -> Result<Vec<u16>, Ros2Error> {
    let (got, depth) = match kind {
        MsgKind::CompressedImage => {
            let (w, h, d) = depth_mm_of_compressed(&decode_compressed_image(data)?)?;
            ((w, h), d)
        }
        _ => {
            let msg = decode_image(data)?;
            ((msg.width, msg.height), depth_mm_of_image(&msg)?)
        }
    };
    check_size(got, size, "depth")?;
    Ok(depth)
}

/// The colour image of a colour message of `kind` (RGB, or a JPEG passed through), which
/// must be `size` (width, height).
///
/// # Errors
/// As [`decode_depth`].
pub fn decode_color(kind: MsgKind, data: &[u8], size: (u32, u32)) -> Result<Color, Ros2Error> {
    let color = match kind {
        MsgKind::CompressedImage => {
            crate::pixels::color_of_compressed(&decode_compressed_image(data)?)?
        }
        _ => {
            let msg = decode_image(data)?;
            Color::Rgb {
                width: msg.width,
                height: msg.height,
                rgb: rgb_of_image(&msg)?,
            }
        }
    };
    check_size(color.size(), size, "colour")?;
    Ok(color)
}
