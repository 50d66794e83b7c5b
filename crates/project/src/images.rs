//! [`CameraImages`]: one camera's input images of a frame.

use bodyseg_core::LabelImage;

/// One camera's images of a frame: the raw depth image (depth sensor size) and the
/// parser's label image (colour sensor size).
#[derive(Debug, Clone, Copy)]
pub struct CameraImages<'a> {
    /// Raw depth, row-major, `u16`, 0 = no measurement.
    pub depth_raw: &'a [u16],
    /// Labels of the colour image.
    pub labels: &'a LabelImage,
}
