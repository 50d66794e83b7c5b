//! The [`Segmenter`] trait, what it is handed per view ([`ViewInput`], [`PersonRegion`]),
//! and [`RecordedSegmenter`].

use crate::ParsingError;
use bodyseg_core::{LabelImage, NUM_CLASSES, RgbImage};

/// A box in image pixels: inclusive pixel-centre bounds (u = column, v = row).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelBox {
    /// Left, px.
    pub x0: f64,
    /// Top, px.
    pub y0: f64,
    /// Right, px.
    pub x1: f64,
    /// Bottom, px.
    pub y1: f64,
}

/// Where one person is in one colour image: the person's box found in 3D (from depth)
/// projected into the camera, for segmenters that look at one person at a time
/// ([`Segmenter::needs_regions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PersonRegion {
    /// The projected box's extent in the colour image, clipped to it, px.
    pub bounds: PixelBox,
    /// The box centre's depth along the colour camera's optical axis, metres (> 0): who
    /// is in front where two people overlap in the image.
    pub depth_m: f64,
}

/// One camera's view of a frame, as handed to a [`Segmenter`].
#[derive(Clone, Copy, Debug)]
pub struct ViewInput<'a> {
    /// Camera name (`cam0`), for messages and for segmenters that look results up.
    pub camera: &'a str,
    /// Frame stem (`000012`).
    pub frame: &'a str,
    /// The colour image; `None` when the segmenter does not need it
    /// ([`Segmenter::needs_images`] is false).
    pub image: Option<&'a RgbImage>,
    /// Labels computed earlier for this view (a recording's `parsing/` image, read by the
    /// caller); `None` unless the segmenter needs them ([`Segmenter::needs_recorded`]).
    pub recorded: Option<&'a LabelImage>,
    /// The people in this view, from person boxes found in 3D ([`PersonRegion`]); an empty
    /// slice when nobody was found. `None` when the segmenter does not need them
    /// ([`Segmenter::needs_regions`]) or the caller has no depth to find people in (a
    /// segmenter then falls back to what it can do on the image alone).
    pub regions: Option<&'a [PersonRegion]>,
}

impl<'a> ViewInput<'a> {
    /// The view's colour image, checked: present, not empty, its bytes those of its size.
    /// `view` is the view's index, for the error.
    ///
    /// # Errors
    /// [`ParsingError::BadImage`] naming the camera.
    pub fn checked_image(&self, view: usize) -> Result<&'a RgbImage, ParsingError> {
        let bad = |reason| ParsingError::BadImage { view, reason };
        let image = self
            .image
            .ok_or_else(|| bad(format!("camera {}: no colour image", self.camera)))?;
        if image.width == 0 || image.height == 0 || image.rgb.len() != image.num_pixels() * 3 {
            return Err(bad(format!(
                "camera {}: colour image {}x{} with {} bytes",
                self.camera,
                image.width,
                image.height,
                image.rgb.len()
            )));
        }
        Ok(image)
    }
}

/// The parser's output for one view.
#[derive(Clone, Debug, PartialEq)]
pub struct ParsedView {
    /// Label per pixel at the colour image's size, with the probability of that label
    /// (`probs`) when the segmenter has one.
    pub labels: LabelImage,
    /// All 7 class probabilities, planar `[class][v * width + u]` (`7 * width * height`
    /// values), when asked for and available.
    pub class_probs: Option<Vec<f32>>,
}

impl ParsedView {
    /// The probability of `class` at row-major pixel `index`, when class probabilities
    /// were kept.
    pub fn class_prob(&self, class: usize, index: usize) -> Option<f32> {
        let n = self.labels.num_pixels();
        if class >= NUM_CLASSES || index >= n {
            return None;
        }
        self.class_probs.as_ref()?.get(class * n + index).copied()
    }
}

/// 2D human parsing: colour images of one frame (one per camera) → one label map per view
/// (ALGORITHM.md §2), in the order given.
///
/// Object-safe: the pipeline holds one as `Box<dyn Segmenter + Send>` and reads what its
/// `needs_*` methods ask for before calling [`Segmenter::segment`].
pub trait Segmenter {
    /// Whether [`Segmenter::segment`] needs [`ViewInput::image`]; when false the caller
    /// may skip decoding the colour images.
    fn needs_images(&self) -> bool {
        true
    }

    /// Whether [`Segmenter::segment`] needs [`ViewInput::recorded`] (labels computed
    /// earlier); when false the caller need not read them.
    fn needs_recorded(&self) -> bool {
        false
    }

    /// Whether [`Segmenter::segment`] wants [`ViewInput::regions`] (people found in 3D
    /// before parsing); when true the caller finds the frame's people from depth first.
    fn needs_regions(&self) -> bool {
        false
    }

    /// Labels every pixel of every view of one frame.
    ///
    /// # Errors
    /// A view's image is missing or unusable, inference fails, or (recorded segmenters)
    /// a stored result cannot be read; the error names the view.
    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError>;
}

/// A segmenter that returns label images computed earlier: the `parsing/` images of a
/// recording (simulated predictions of synthetic recordings, or a parser run elsewhere),
/// which the caller reads and hands over in [`ViewInput::recorded`], so this crate stays
/// free of I/O. The labels carry no probabilities.
#[derive(Clone, Copy, Debug, Default)]
pub struct RecordedSegmenter;

impl RecordedSegmenter {
    /// The segmenter.
    pub fn new() -> RecordedSegmenter {
        RecordedSegmenter
    }
}

impl Segmenter for RecordedSegmenter {
    fn needs_images(&self) -> bool {
        false
    }

    fn needs_recorded(&self) -> bool {
        true
    }

    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError> {
        views
            .iter()
            .enumerate()
            .map(|(view, input)| {
                let Some(labels) = input.recorded else {
                    return Err(ParsingError::Recorded {
                        view,
                        reason: format!(
                            "camera {}: frame {}: no recorded labels given",
                            input.camera, input.frame
                        ),
                    });
                };
                if let Some(image) = input.image
                    && (image.width, image.height) != (labels.width, labels.height)
                {
                    return Err(ParsingError::Recorded {
                        view,
                        reason: format!(
                            "camera {}: recorded labels are {}x{}, the colour image is {}x{}",
                            input.camera, labels.width, labels.height, image.width, image.height
                        ),
                    });
                }
                Ok(ParsedView {
                    labels: labels.clone(),
                    class_probs: None,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::{Class, Label};

    #[test]
    fn recorded_segmenter_returns_the_given_labels_in_view_order() {
        let mut seg: Box<dyn Segmenter + Send> = Box::new(RecordedSegmenter::new());
        assert!(!seg.needs_images() && seg.needs_recorded());
        let head = LabelImage::filled(2, 1, Label::from(Class::Head));
        let background = LabelImage::filled(2, 1, Label::BACKGROUND);
        let view = |camera, recorded| ViewInput {
            camera,
            frame: "000001",
            image: None,
            recorded,
            regions: None,
        };
        let out = seg
            .segment(&[view("cam1", Some(&background)), view("cam0", Some(&head))])
            .expect("both given");
        assert_eq!(out[0].labels, background);
        assert_eq!(out[1].labels, head);
        assert!(out[1].class_probs.is_none());
        let e = seg
            .segment(&[view("cam0", Some(&head)), view("cam9", None)])
            .expect_err("cam9");
        assert_eq!(
            e.to_string(),
            "view 1: camera cam9: frame 000001: no recorded labels given"
        );
        let image = RgbImage::new(3, 1, vec![0; 9]).expect("3x1");
        let e = seg
            .segment(&[ViewInput {
                image: Some(&image),
                ..view("cam0", Some(&head))
            }])
            .expect_err("size");
        assert!(
            e.to_string()
                .contains("recorded labels are 2x1, the colour image is 3x1")
        );
    }
}
