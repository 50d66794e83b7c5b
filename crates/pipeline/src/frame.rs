//! The first two stage types: [`Frame`] (the images of one instant, read from a
//! [`Recording`]) and [`ParsedFrame`] (the frame with one label image per camera), and
//! [`parse_frame`] between them: the one place the pipeline calls a
//! [`Segmenter`].
//!
//! ```text
//! Recording ─ Frame::read ─→ Frame ─ parse_frame (Segmenter) ─→ ParsedFrame ─ project ─→ LabeledCloud
//! ```
//!
//! A segmenter that needs more than the images gets them through [`ViewInput`], filled
//! here: for one that needs person regions (BlazePose), [`parse_frame`] first finds the
//! frame's people from depth and projects their boxes into every camera
//! ([`crate::regions`]), so the order is depth → people → parse.

use crate::batch::InputFile;
use crate::config::PipelineConfig;
use crate::recording::{Layer, Recording, check_stem};
use crate::stage::{Stage, plural, timed};
use anyhow::{Context, Result, bail};
use bodyseg_calib::Rig;
use bodyseg_core::{LabelImage, LabeledCloud, PersonBoxes, RgbImage};
use bodyseg_io::{ColorFile, DepthImage};
use bodyseg_parsing::{RecordedSegmenter, Segmenter, ViewInput};
use bodyseg_project::{CameraImages, FrameProjector, ProjectMode};
use std::path::Path;

/// Which of a frame's images to read ([`Frame::read`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameNeeds {
    /// The depth images (`depth/`): for everything after parsing.
    pub depth: bool,
    /// The colour images (`color/`): for a segmenter that looks at them, or for the
    /// points' colours.
    pub color: bool,
    /// The colour image files as stored (`color/`, PNG or JPEG bytes): for the Rerun
    /// view, which logs them as they are. Without [`FrameNeeds::color`] they are not
    /// decoded; with it each file is read once and decoded from the bytes kept.
    pub color_files: bool,
    /// The recorded predictions (`parsing/`): for [`bodyseg_parsing::RecordedSegmenter`].
    pub parsing: bool,
    /// The ground truth of every depth pixel (`depth_labels/`), for scoring.
    pub truth: bool,
}

impl FrameNeeds {
    /// What `segmenter` needs to run: the colour images and/or the recorded predictions,
    /// and the depth images when it takes person regions (found from depth); add what the
    /// later stages need.
    pub fn of(segmenter: &dyn Segmenter) -> FrameNeeds {
        FrameNeeds {
            depth: segmenter.needs_regions(),
            color: segmenter.needs_images(),
            parsing: segmenter.needs_recorded(),
            ..FrameNeeds::default()
        }
    }
}

/// The images of one frame of a recording, each checked against the rig's sensor sizes;
/// per-camera vectors are in rig order.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The frame's stem (`000012`).
    pub stem: String,
    /// Raw depth per camera, the depth sensor's size; empty when not read
    /// ([`FrameNeeds::depth`]: `bodyseg parse` reads none).
    pub depth: Vec<DepthImage>,
    /// Colour per camera, the colour sensor's size, when read ([`FrameNeeds::color`]).
    pub color: Option<Vec<RgbImage>>,
    /// Colour image files per camera, as stored, when read ([`FrameNeeds::color_files`]).
    pub color_files: Option<Vec<ColorFile>>,
    /// Recorded predictions per camera (`parsing/`), when read ([`FrameNeeds::parsing`]).
    pub parsing: Option<Vec<LabelImage>>,
    /// Ground truth per depth pixel per camera (`depth_labels/`), when read
    /// ([`FrameNeeds::truth`]).
    pub truth: Option<Vec<LabelImage>>,
    /// The files read, with size and modification time: the frame's record lists them, and
    /// a changed input makes a resumed batch redo the frame.
    pub inputs: Vec<InputFile>,
}

impl Frame {
    /// Reads frame `stem` of `rec`: every camera's images that `needs` asks for.
    ///
    /// # Errors
    /// `stem` is not a frame stem; a file is missing, does not decode, or has another size
    /// than the rig says (the error names the camera and the file).
    pub fn read(rec: &Recording, stem: &str, needs: FrameNeeds) -> Result<Frame> {
        check_stem(stem)?;
        let mut inputs = Vec::new();
        let mut note = |path: &std::path::Path| inputs.extend(InputFile::of(path));
        let mut depth = Vec::new();
        let mut color = Vec::new();
        let mut color_files = Vec::new();
        let mut parsing = Vec::new();
        let mut truth = Vec::new();
        for index in 0..rec.rig().cameras.len() {
            if needs.depth {
                let (image, path) = rec.read_depth(index, stem)?;
                note(&path);
                depth.push(image);
            }
            if needs.color_files {
                let (file, path) = rec.read_color_file(index, stem)?;
                note(&path);
                if needs.color {
                    let camera = &rec.rig().cameras[index].name;
                    color.push(
                        file.decode(&path)
                            .with_context(|| format!("camera {camera}"))?,
                    );
                }
                color_files.push(file);
            } else if needs.color {
                let (image, path) = rec.read_color(index, stem)?;
                note(&path);
                color.push(image);
            }
            if needs.parsing {
                let (labels, path) = rec.read_labels(index, Layer::Parsing, stem)?;
                note(&path);
                parsing.push(labels);
            }
            if needs.truth {
                let (labels, path) = rec.read_labels(index, Layer::DepthLabels, stem)?;
                note(&path);
                truth.push(labels);
            }
        }
        Ok(Frame {
            stem: stem.to_string(),
            depth,
            color: needs.color.then_some(color),
            color_files: needs.color_files.then_some(color_files),
            parsing: needs.parsing.then_some(parsing),
            truth: needs.truth.then_some(truth),
            inputs,
        })
    }
}

/// A frame with its 2D body-part labels: one label image per camera (rig order, the
/// colour sensor's size), with the probability of each pixel's label when the segmenter
/// gives one.
#[derive(Clone, Debug)]
pub struct ParsedFrame {
    /// The frame.
    pub frame: Frame,
    /// The labels per camera.
    pub labels: Vec<LabelImage>,
    /// The people found from depth before parsing (geometry-mode boxes), when the
    /// segmenter took person regions.
    pub people: Option<PersonBoxes>,
}

impl ParsedFrame {
    /// Each camera's depth image and labels, rig order: the projection's input.
    pub(crate) fn camera_images(&self) -> Vec<CameraImages<'_>> {
        self.frame
            .depth
            .iter()
            .zip(&self.labels)
            .map(|(d, labels)| CameraImages {
                depth_raw: &d.depth_mm,
                labels,
            })
            .collect()
    }
}

/// Runs `segmenter` on every camera of `frame` (one call, the views batched): the one call
/// site of [`Segmenter::segment`] in the pipeline. The frame must hold what the segmenter
/// needs ([`FrameNeeds::of`]); camera names come from `rig`. A segmenter that takes person
/// regions gets them from the people found in the frame's depth images
/// ([`crate::regions::find_people`], with `config`'s `[backproject]` and `[boxes]` values)
/// projected into each camera; a frame read without depth gives it none (it falls back to
/// the images alone).
///
/// # Errors
/// The frame lacks the images the segmenter needs, finding the people fails, or the
/// segmenter fails (the error names the view).
pub fn parse_frame(
    frame: Frame,
    rig: &Rig,
    segmenter: &mut dyn Segmenter,
    config: &PipelineConfig,
) -> Result<ParsedFrame> {
    let cameras = rig.cameras.len();
    let lengths = [
        frame.color.as_ref().map(Vec::len),
        frame.parsing.as_ref().map(Vec::len),
    ];
    if lengths.iter().flatten().any(|&n| n != cameras) {
        bail!(
            "frame {}: images of another number of cameras than the rig's {cameras}",
            frame.stem
        );
    }
    let missing = |what: &str| format!("frame {}: the parser needs the {what}", frame.stem);
    if segmenter.needs_images() && frame.color.is_none() {
        bail!("{}, which were not read", missing("colour images"));
    }
    if segmenter.needs_recorded() && frame.parsing.is_none() {
        bail!(
            "{}, which were not read",
            missing("recorded parsing/ images")
        );
    }
    let people = if segmenter.needs_regions() && !frame.depth.is_empty() {
        Some(crate::regions::find_people(
            &frame.stem,
            &frame.depth,
            frame.color.as_deref(),
            rig,
            config,
        )?)
    } else {
        None
    };
    let regions = people
        .as_ref()
        .map(|p| crate::regions::person_regions(rig, &p.boxes));
    let views: Vec<ViewInput<'_>> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(i, camera)| ViewInput {
            camera: &camera.name,
            frame: &frame.stem,
            image: frame.color.as_ref().and_then(|c| c.get(i)),
            recorded: frame.parsing.as_ref().and_then(|p| p.get(i)),
            regions: regions.as_ref().and_then(|r| r.get(i)).map(Vec::as_slice),
        })
        .collect();
    let parsed = segmenter.segment(&views)?;
    drop(views);
    if parsed.len() != cameras {
        bail!(
            "frame {}: the parser gave {} label images for {cameras} cameras",
            frame.stem,
            parsed.len()
        );
    }
    let labels = parsed.into_iter().map(|p| p.labels).collect();
    Ok(ParsedFrame {
        frame,
        labels,
        people,
    })
}

/// Projects a parsed frame's labels onto its depth points
/// ([`bodyseg_project::FrameProjector::project_frame`]; with the points' camera colours
/// when `color`, which then needs the frame's colour images).
///
/// # Errors
/// The frame has no depth images, or not the colour images asked for; the images do not
/// fit the rig.
pub fn project_parsed(
    parsed: &ParsedFrame,
    rig: &Rig,
    config: &PipelineConfig,
    color: bool,
) -> Result<LabeledCloud> {
    let frame = &parsed.frame;
    if frame.depth.len() != rig.cameras.len() {
        bail!(
            "frame {}: {} depth images for a rig of {} cameras",
            frame.stem,
            frame.depth.len(),
            rig.cameras.len()
        );
    }
    let images = parsed.camera_images();
    let projector = FrameProjector::new(rig)?;
    let backproject = config.backproject.options();
    if color {
        let color: Vec<&RgbImage> = frame
            .color
            .as_ref()
            .with_context(|| format!("frame {}: the colour images were not read", frame.stem))?
            .iter()
            .collect();
        Ok(projector.project_frame_colored(&images, &color, &backproject, &config.project)?)
    } else {
        Ok(projector.project_frame(&images, &backproject, &config.project)?)
    }
}

/// The `read` stage of a one-frame command (`parse`, `project`, `boxes`): opens
/// `recording` and reads frame `stem` with what `needs` asks of that recording. The
/// stage's line counts the cameras' images as `images` (singular, plural).
///
/// # Errors
/// As [`Recording::open`] and [`Frame::read`].
pub(crate) fn read_one_frame(
    recording: &Path,
    stem: &str,
    needs: impl FnOnce(&Recording) -> FrameNeeds,
    images: (&str, &str),
) -> Result<(Recording, Frame, Stage)> {
    let ((rec, frame), took) = timed(|| -> Result<_> {
        let rec = Recording::open(recording)?;
        let frame = Frame::read(&rec, stem, needs(&rec))?;
        Ok((rec, frame))
    })?;
    let cameras = plural(rec.rig().cameras.len(), images.0, images.1);
    let stage = Stage::new("read", took, format!("{cameras}, frame {stem}"));
    Ok((rec, frame, stage))
}

/// Reads frame `stem` of the recording at `recording` with its recorded predictions
/// (`parsing/`), and projects it: `bodyseg project`, and `bodyseg boxes --recording`. The
/// points carry their camera colours when the box finder uses them. Returns the rig, the
/// cloud and the stages `read`, `project`.
///
/// # Errors
/// The recording cannot be opened; a file is missing, does not decode or does not fit the
/// rig (the error names it); the projection fails.
pub(crate) fn read_and_project(
    recording: &Path,
    stem: &str,
    config: &PipelineConfig,
) -> Result<(Rig, LabeledCloud, Vec<Stage>)> {
    check_stem(stem)?;
    let color = config.boxes.uses_colors();
    let mut segmenter = RecordedSegmenter::new();
    let needs = FrameNeeds {
        depth: true,
        color,
        ..FrameNeeds::of(&segmenter)
    };
    let (rec, frame, read) = read_one_frame(recording, stem, |_| needs, ("camera", "cameras"))?;
    let rig = rec.rig();
    let mut stages = vec![read];
    tracing::info!(recording = %recording.display(), frame = %stem, "read frame");

    let context = || format!("{}: frame {stem}", recording.display());
    let (cloud, took) = timed(|| {
        let parsed = parse_frame(frame, rig, &mut segmenter, config).with_context(context)?;
        // Geometry-mode boxes split people from what is nobody's by colour too.
        project_parsed(&parsed, rig, config, color).with_context(context)
    })?;
    crate::sanity::warn_all(crate::sanity::projected_scale_warning(
        &cloud,
        rig,
        &context(),
    ));
    let unknown = cloud.labels.iter().filter(|l| l.is_unknown()).count();
    let mode_name = match config.project.mode {
        ProjectMode::Naive => "naive",
        ProjectMode::Dsa => "dsa",
    };
    stages.push(Stage::new(
        "project",
        took,
        format!(
            "{}, {} unknown (mode {mode_name})",
            plural(cloud.len(), "point", "points"),
            unknown
        ),
    ));
    Ok((rec.rig().clone(), cloud, stages))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::tests::rig;
    use bodyseg_core::Label;
    use bodyseg_parsing::{ParsedView, ParsingError};

    fn frame(parsing: Option<Vec<LabelImage>>) -> Frame {
        Frame {
            stem: "000001".into(),
            depth: Vec::new(),
            color: None,
            color_files: None,
            parsing,
            truth: None,
            inputs: Vec::new(),
        }
    }

    /// Gives one view fewer than asked for.
    struct Short;

    impl Segmenter for Short {
        fn needs_images(&self) -> bool {
            false
        }

        fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError> {
            Ok(views
                .iter()
                .skip(1)
                .map(|_| ParsedView {
                    labels: LabelImage::filled(1, 1, Label::BACKGROUND),
                    class_probs: None,
                })
                .collect())
        }
    }

    #[test]
    fn recorded_predictions_go_through_the_segmenter_in_camera_order() {
        let rig = rig();
        let cfg = PipelineConfig::default();
        let recorded: Vec<LabelImage> = (0..rig.cameras.len())
            .map(|i| LabelImage::filled(2, 1, Label::from_id(i as u8).expect("class id")))
            .collect();
        let mut segmenter = RecordedSegmenter::new();
        assert_eq!(
            FrameNeeds::of(&segmenter),
            FrameNeeds {
                parsing: true,
                ..FrameNeeds::default()
            }
        );
        let parsed =
            parse_frame(frame(Some(recorded.clone())), &rig, &mut segmenter, &cfg).expect("parsed");
        assert_eq!(parsed.labels, recorded);
        assert_eq!(parsed.frame.stem, "000001");

        let e = format!(
            "{:#}",
            parse_frame(frame(None), &rig, &mut segmenter, &cfg).expect_err("not read")
        );
        assert!(e.contains("needs the recorded parsing/ images"), "{e}");
        let e = format!(
            "{:#}",
            parse_frame(
                frame(Some(recorded[..1].to_vec())),
                &rig,
                &mut segmenter,
                &cfg
            )
            .expect_err("one camera")
        );
        assert!(e.contains("another number of cameras"), "{e}");
        let e = format!(
            "{:#}",
            parse_frame(frame(None), &rig, &mut Short, &cfg).expect_err("short")
        );
        assert!(e.contains("gave 2 label images for 3 cameras"), "{e}");
    }
}
