//! Colour images (the input of 2D human parsing, ALGORITHM.md §2) and per-pixel label maps
//! of a colour image (its output, and the input of label projection, §3).

use crate::class::Label;

/// Why a [`LabelImage`] is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// A per-pixel array does not hold `width * height` values.
    #[error("label image has {want} pixels but {got} {field}")]
    SizeMismatch {
        /// Name of the array (`labels`, `probs`).
        field: &'static str,
        /// Its length.
        got: usize,
        /// `width * height`.
        want: usize,
    },
    /// A probability is NaN or outside `[0, 1]`.
    #[error("label image pixel {index}: probability {value} is not in [0, 1]")]
    BadProbability {
        /// Row-major index of the first such pixel.
        index: usize,
        /// Its value.
        value: f32,
    },
}

/// The label of every pixel of one colour image, row-major (`v * width + u`), with
/// optionally the probability the parser gave the winning label.
///
/// Pixel (u, v) = (column, row); integer coordinates are pixel centres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabelImage {
    /// Width, pixels (the colour sensor's).
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Label per pixel, row-major; `width * height` entries.
    pub labels: Vec<Label>,
    /// Optional probability in `[0, 1]` of the winning label per pixel, row-major
    /// (ALGORITHM.md §2: the softmax value of the argmax class).
    pub probs: Option<Vec<f32>>,
}

impl LabelImage {
    /// A label image without probabilities; errors when `labels` does not hold
    /// `width * height` entries.
    pub fn new(width: u32, height: u32, labels: Vec<Label>) -> Result<LabelImage, ImageError> {
        let image = LabelImage {
            width,
            height,
            labels,
            probs: None,
        };
        image.validate()?;
        Ok(image)
    }

    /// An image whose every pixel has `label`.
    pub fn filled(width: u32, height: u32, label: Label) -> LabelImage {
        LabelImage {
            width,
            height,
            labels: vec![label; width as usize * height as usize],
            probs: None,
        }
    }

    /// Number of pixels, `width * height`.
    pub fn num_pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Checks the array lengths and that every probability is in `[0, 1]`.
    pub fn validate(&self) -> Result<(), ImageError> {
        let want = self.num_pixels();
        if self.labels.len() != want {
            return Err(ImageError::SizeMismatch {
                field: "labels",
                got: self.labels.len(),
                want,
            });
        }
        if let Some(p) = &self.probs {
            if p.len() != want {
                return Err(ImageError::SizeMismatch {
                    field: "probs",
                    got: p.len(),
                    want,
                });
            }
            if let Some(index) = p.iter().position(|x| !(0.0..=1.0).contains(x)) {
                return Err(ImageError::BadProbability {
                    index,
                    value: p[index],
                });
            }
        }
        Ok(())
    }

    /// Row-major index of pixel (u, v), `None` outside the image.
    pub fn index(&self, u: u32, v: u32) -> Option<usize> {
        (u < self.width && v < self.height).then(|| v as usize * self.width as usize + u as usize)
    }

    /// The label of pixel (u, v), `None` outside the image.
    pub fn get(&self, u: u32, v: u32) -> Option<Label> {
        self.index(u, v).and_then(|i| self.labels.get(i).copied())
    }

    /// The probability of pixel (u, v)'s label; `None` outside the image or when the
    /// image has no probabilities.
    pub fn prob(&self, u: u32, v: u32) -> Option<f32> {
        let i = self.index(u, v)?;
        self.probs.as_ref().and_then(|p| p.get(i).copied())
    }
}

/// An 8-bit RGB colour image (the input of 2D human parsing, ALGORITHM.md §2), row-major,
/// 3 bytes per pixel in R, G, B order.
///
/// Pixel (u, v) = (column, row); integer coordinates are pixel centres.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RgbImage {
    /// Width, pixels (the colour sensor's).
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width * height * 3` bytes: R, G, B of pixel `v * width + u` at `3 * (v * width + u)`.
    pub rgb: Vec<u8>,
}

impl RgbImage {
    /// An RGB image; errors when `rgb` does not hold `width * height * 3` bytes.
    pub fn new(width: u32, height: u32, rgb: Vec<u8>) -> Result<RgbImage, ImageError> {
        let want = width as usize * height as usize * 3;
        if rgb.len() != want {
            return Err(ImageError::SizeMismatch {
                field: "rgb bytes",
                got: rgb.len(),
                want,
            });
        }
        Ok(RgbImage { width, height, rgb })
    }

    /// An image of `width × height` pixels, every one `rgb`.
    pub fn filled(width: u32, height: u32, rgb: [u8; 3]) -> RgbImage {
        RgbImage {
            width,
            height,
            rgb: rgb.repeat(width as usize * height as usize),
        }
    }

    /// Number of pixels, `width * height`.
    pub fn num_pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Sets pixel (u, v) to `rgb`; a pixel outside the image is left out.
    pub fn set_pixel(&mut self, u: u32, v: u32, rgb: [u8; 3]) {
        if u >= self.width || v >= self.height {
            return;
        }
        let i = 3 * (v as usize * self.width as usize + u as usize);
        if let Some(p) = self.rgb.get_mut(i..i + 3) {
            p.copy_from_slice(&rgb);
        }
    }

    /// The R, G, B bytes of pixel (u, v), `None` outside the image.
    pub fn pixel(&self, u: u32, v: u32) -> Option<[u8; 3]> {
        if u >= self.width || v >= self.height {
            return None;
        }
        let i = 3 * (v as usize * self.width as usize + u as usize);
        self.rgb.get(i..i + 3).and_then(|p| p.try_into().ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::class::Class;

    #[test]
    fn get_is_row_major_and_none_outside() {
        let head = Label::from(Class::Head);
        let mut labels = vec![Label::BACKGROUND; 6];
        labels[4] = head; // (u 1, v 1) in a 3×2 image
        let mut image = LabelImage::new(3, 2, labels).expect("6 labels for 3×2");
        assert_eq!(image.get(1, 1), Some(head));
        assert_eq!(image.get(0, 1), Some(Label::BACKGROUND));
        assert_eq!(image.get(3, 0), None);
        assert_eq!(image.get(0, 2), None);
        assert_eq!(image.prob(1, 1), None);
        image.probs = Some(vec![0.5; 6]);
        assert_eq!(image.prob(1, 1), Some(0.5));
        assert_eq!(image.validate(), Ok(()));
    }

    #[test]
    fn set_pixel_writes_one_pixel_and_leaves_outside_alone() {
        let mut image = RgbImage::filled(3, 2, [1, 2, 3]);
        assert_eq!(image.rgb.len(), 18);
        image.set_pixel(2, 1, [9, 8, 7]);
        image.set_pixel(3, 0, [0, 0, 0]);
        image.set_pixel(0, 2, [0, 0, 0]);
        assert_eq!(image.pixel(2, 1), Some([9, 8, 7]));
        assert_eq!(image.pixel(1, 1), Some([1, 2, 3]));
        assert_eq!(image.rgb.iter().filter(|&&b| b == 0).count(), 0);
    }

    #[test]
    fn rgb_image_checks_its_length_and_reads_pixels() {
        let image = RgbImage::new(2, 1, vec![1, 2, 3, 4, 5, 6]).expect("2x1x3 bytes");
        assert_eq!(image.pixel(1, 0), Some([4, 5, 6]));
        assert_eq!(image.pixel(2, 0), None);
        let err = RgbImage::new(2, 2, vec![0; 11]).expect_err("11 ≠ 12");
        assert!(err.to_string().contains("11 rgb bytes"), "{err}");
    }

    #[test]
    fn validate_names_the_array() {
        let err = LabelImage::new(3, 2, vec![Label::BACKGROUND; 5]).expect_err("5 ≠ 6");
        assert!(err.to_string().contains("5 labels"), "{err}");
        let mut image = LabelImage::filled(2, 2, Label::BACKGROUND);
        image.probs = Some(vec![0.5; 3]);
        assert!(matches!(
            image.validate(),
            Err(ImageError::SizeMismatch { field: "probs", .. })
        ));
        image.probs = Some(vec![0.5, 1.5, f32::NAN, 0.0]);
        assert_eq!(
            image.validate(),
            Err(ImageError::BadProbability {
                index: 1,
                value: 1.5
            })
        );
    }
}
