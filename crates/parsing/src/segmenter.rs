//! The [`Segmenter`] trait and [`RecordedSegmenter`].

use crate::ParsingError;
use bodyseg_core::{LabelImage, NUM_CLASSES, RgbImage};

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
pub trait Segmenter {
    /// Whether [`Segmenter::segment`] needs [`ViewInput::image`]; when false the caller
    /// may skip decoding the colour images.
    fn needs_images(&self) -> bool {
        true
    }

    /// Labels every pixel of every view of one frame.
    ///
    /// # Errors
    /// A view's image is missing or unusable, inference fails, or (recorded segmenters)
    /// a stored result cannot be read; the error names the view.
    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError>;
}

/// Where a [`RecordedSegmenter`] gets a view's stored labels: (camera, frame) → label
/// image, or an error message that names the file.
pub type LabelSource = Box<dyn FnMut(&str, &str) -> Result<LabelImage, String> + Send>;

/// A segmenter that returns label images computed earlier: the `parsing/` images of a
/// recording (simulated predictions of synthetic recordings, or a parser run elsewhere).
/// The file reading is the caller's (`source`), so this crate stays free of I/O.
pub struct RecordedSegmenter {
    source: LabelSource,
}

impl RecordedSegmenter {
    /// A segmenter that asks `source` for each view's labels.
    pub fn new(source: LabelSource) -> RecordedSegmenter {
        RecordedSegmenter { source }
    }
}

impl std::fmt::Debug for RecordedSegmenter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecordedSegmenter").finish_non_exhaustive()
    }
}

impl Segmenter for RecordedSegmenter {
    fn needs_images(&self) -> bool {
        false
    }

    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError> {
        views
            .iter()
            .enumerate()
            .map(|(view, input)| {
                let labels = (self.source)(input.camera, input.frame)
                    .map_err(|reason| ParsingError::Recorded { view, reason })?;
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
                    labels,
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
    fn recorded_segmenter_returns_what_the_source_gives_in_view_order() {
        let mut seg = RecordedSegmenter::new(Box::new(|camera: &str, _frame: &str| match camera {
            "cam0" => Ok(LabelImage::filled(2, 1, Label::from(Class::Head))),
            "cam1" => Ok(LabelImage::filled(2, 1, Label::BACKGROUND)),
            _ => Err(format!("rec/{camera}/parsing/000001.png: cannot read")),
        }));
        assert!(!seg.needs_images());
        let view = |camera| ViewInput {
            camera,
            frame: "000001",
            image: None,
        };
        let out = seg
            .segment(&[view("cam1"), view("cam0")])
            .expect("both exist");
        assert_eq!(out[0].labels.get(0, 0), Some(Label::BACKGROUND));
        assert_eq!(out[1].labels.get(1, 0), Some(Label::from(Class::Head)));
        let e = seg
            .segment(&[view("cam0"), view("cam9")])
            .expect_err("cam9");
        assert_eq!(
            e.to_string(),
            "view 1: rec/cam9/parsing/000001.png: cannot read"
        );
        let image = RgbImage::new(3, 1, vec![0; 9]).expect("3x1");
        let e = seg
            .segment(&[ViewInput {
                image: Some(&image),
                ..view("cam0")
            }])
            .expect_err("size");
        assert!(
            e.to_string()
                .contains("recorded labels are 2x1, the colour image is 3x1")
        );
    }
}
