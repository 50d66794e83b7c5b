//! [`BlazePoseSegmenter`]: the BlazePose landmark model run on person regions (one ROI per
//! person, from boxes found in 3D), its landmarks and mask turned into the 7 classes by
//! the rule of [`crate::blazepose`].

use crate::ParsingError;
use crate::blazepose::{
    DecodedPose, INPUT, NUM_LANDMARKS, PersonLabels, Roi, RuleConfig, average_masks, blank_outside,
    crop_into, decode_landmarks, label_person, landmark, mask_from_logits, merge_people,
    mirror_crop, unmirror_outputs,
};
use crate::bodypix::{BodyPix, BodyPixOptions};
use crate::onnx::{
    float_dims, inference_error, load_session, named_output, run_one_input, without_outputs,
};
use crate::segmenter::{ParsedView, PersonRegion, PixelBox, Segmenter, ViewInput};
use bodyseg_core::{LabelImage, RgbImage};
use ort::session::Session;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

mod parts;
mod person_mask;

/// Which of BlazePose's landmark models runs (the sizes MediaPipe ships).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BlazePoseVariant {
    /// `pose_landmark_lite` (2.8 MB): fastest, least accurate.
    Lite,
    /// `pose_landmark_full` (6.4 MB): the default.
    #[default]
    Full,
    /// `pose_landmark_heavy` (27.7 MB, not in git: `scripts/convert_blazepose.py` makes it).
    Heavy,
}

impl BlazePoseVariant {
    /// `lite`, `full` or `heavy`.
    pub fn name(self) -> &'static str {
        match self {
            BlazePoseVariant::Lite => "lite",
            BlazePoseVariant::Full => "full",
            BlazePoseVariant::Heavy => "heavy",
        }
    }
}

/// How a [`BlazePoseSegmenter`] runs; defaults are the values tuned on the tune split of
/// the real photographs (docs/notes/2026-12-02-blazepose-rule.md §5–6).
#[derive(Clone, Debug, PartialEq)]
pub struct BlazePoseOptions {
    /// Threads. A view with one region runs on one session with this many ONNX Runtime
    /// intra-op threads (0: ONNX Runtime's default); a view with several runs up to this
    /// many regions at once, each on its own single-threaded session (a second region at
    /// once gains more than a second intra-op thread; the labels do not depend on the
    /// value). Default 2.
    pub threads: usize,
    /// The first ROI's side, × the region's longer side. Default 2.0 (a region from a
    /// person box; the model is trained on MediaPipe's ROIs, which hold the body with a
    /// wide margin).
    pub roi_scale: f64,
    /// Runs on the ROI that the previous run's alignment points give (MediaPipe's
    /// landmarks-to-ROI), each accepted only when the pose flag stays ≥ 0.8 × the
    /// previous one. Default 1.
    pub refine_passes: u32,
    /// A region whose pose flag is below this gives no person. Default 0.1.
    pub min_pose_flag: f64,
    /// The second try of a region (when the first pose's centre left it, see
    /// [`RETRY_ROI_SCALE`]) sees only the region: the crop is blanked (black) outside the
    /// region widened by [`REGION_SLACK`]. The first pose drifted to a neighbour; with the
    /// neighbours out of sight the model finds the region's own person (on the real
    /// photographs: a seated man beside two others, a woman among children). Only the retry:
    /// blanking every run loses the context the model needs (the body beyond a tight box).
    /// Default on.
    pub blank_retry: bool,
    /// The accepted pose's mask is averaged with the mask of a run on the mirrored crop of
    /// the same ROI (test-time flip, [`crate::blazepose::average_masks`]); landmarks, flag
    /// and every acceptance decision stay the first runs'. One more model run per person:
    /// the two-person view takes a third longer (108.5 → 144.1 ms in one loaded bench run,
    /// so ≈ 83 ms from the quiet 62.4 ms, past issue 29's 80 ms). Default off: on the real
    /// photographs (docs/notes/2026-12-03-blazepose.md, 2026-12-04 session 41) it moved
    /// the tune split by noise only (mIoU 0.465 → 0.467, person 0.825 → 0.827), test and
    /// coarse up, the hold-out down (0.355 → 0.339, person 0.694 → 0.669).
    pub mirror_average: bool,
    /// The landmarks + mask → classes rule.
    pub rule: RuleConfig,
    /// BodyPix's crop and threshold, when the body parts come from BodyPix
    /// ([`BlazePoseSegmenter::with_bodypix`]).
    pub bodypix: BodyPixOptions,
    /// With BodyPix's parts: a pixel of BlazePose's person where BodyPix's person
    /// probability is below this is not the person's, on people BodyPix sees (at least
    /// half of their pixels at BodyPix's threshold; `person_mask::veto_blazepose`). 0: off.
    /// Default 0.15, chosen on the tune split of the real photographs
    /// (docs/notes/2026-12-03-blazepose.md, 2026-12-04 session 42: tune mIoU + person IoU
    /// over 0, 0.05, 0.1, 0.15, 0.2, 0.3, flat from 0.1 to 0.2): BlazePose's mask, cut at
    /// the rule's 0.35, is a few pixels wider than the body, and BodyPix's probability
    /// below 0.15 there marks background far more often than body.
    pub bodypix_background_below: f64,
    /// With BodyPix's parts: pieces of the fused person mask that hold no pixel of
    /// BlazePose's person and no confident landmark, in no region where BlazePose found
    /// nobody, are background (`person_mask::drop_detached`: BodyPix's parts on a horse
    /// under its rider). Default on (the tune split does not move; test and hold-out rise).
    pub drop_detached: bool,
}

impl Default for BlazePoseOptions {
    fn default() -> Self {
        BlazePoseOptions {
            threads: 2,
            roi_scale: 2.0,
            refine_passes: 1,
            min_pose_flag: 0.1,
            blank_retry: true,
            mirror_average: false,
            rule: RuleConfig::default(),
            bodypix: BodyPixOptions::default(),
            bodypix_background_below: 0.15,
            drop_detached: true,
        }
    }
}

/// The landmark model's input and outputs used here: name and shape (ONNX conversion of
/// `scripts/convert_blazepose.py`, sidecar `models/blazepose_*.json`).
const INPUT_NAME: &str = "input_1";
const LANDMARKS: (&str, [i64; 2]) = ("Identity", [1, 195]);
const FLAG: (&str, [i64; 2]) = ("Identity_1", [1, 1]);
const MASK: (&str, [i64; 4]) = ("Identity_2", [1, 256, 256, 1]);
const HEATMAP: (&str, [i64; 4]) = ("Identity_3", [1, 64, 64, 39]);

/// A pose refined by [`BlazePoseOptions::refine_passes`] is accepted when its ROI's side
/// is within this factor of the previous one (a jump means the landmarks are lost).
const MAX_ROI_CHANGE: f64 = 2.0;
/// The refined pose is kept when its flag is at least this × the previous flag.
const MIN_FLAG_RATIO: f64 = 0.8;
/// Refinement runs only from a pose whose flag is at least this (MediaPipe's threshold).
const MIN_FLAG_TO_REFINE: f64 = 0.5;
/// MediaPipe's scale of the box around the alignment points.
const ALIGNMENT_ROI_SCALE: f64 = 1.5;
/// A pose belongs to its region when its body centre lies within the region widened by
/// this fraction of the region's width and height on each side.
pub const REGION_SLACK: f64 = 0.1;
/// The ROI's side, × the region's longer side, of the second try when the first pose's
/// centre left the region (a tighter crop holds fewer neighbours: on PCL's five_people
/// frame it finds the three people in the middle whom the 2.0 crop lost to neighbours).
pub const RETRY_ROI_SCALE: f64 = 1.25;

/// Whether `pose`'s body centre (alignment centre) lies in `bounds` widened by
/// [`REGION_SLACK`], the centre first clamped to the image of `width`×`height` px.
///
/// Regions are clipped to the image, so the centre is compared after the same clipping: in
/// a close-up the mid-hip point lies below the image, outside every clipped region, though
/// the pose is the region's person (on the real photographs the unclamped test dropped or
/// re-cropped most close-ups).
fn centre_inside(pose: &DecodedPose, bounds: &PixelBox, width: usize, height: usize) -> bool {
    let Some(&[x, y]) = pose.xy.get(landmark::ALIGN_CENTRE) else {
        return false;
    };
    if !(x.is_finite() && y.is_finite()) {
        return false;
    }
    let c = [
        x.clamp(0.0, width.saturating_sub(1) as f64),
        y.clamp(0.0, height.saturating_sub(1) as f64),
    ];
    let wide = widened(bounds);
    (wide.x0..=wide.x1).contains(&c[0]) && (wide.y0..=wide.y1).contains(&c[1])
}

/// `bounds` widened by [`REGION_SLACK`] of its width and height on each side.
fn widened(bounds: &PixelBox) -> PixelBox {
    let (sx, sy) = (
        REGION_SLACK * (bounds.x1 - bounds.x0).max(1.0),
        REGION_SLACK * (bounds.y1 - bounds.y0).max(1.0),
    );
    PixelBox {
        x0: bounds.x0 - sx,
        y0: bounds.y0 - sy,
        x1: bounds.x1 + sx,
        y1: bounds.y1 + sy,
    }
}

/// BlazePose (MediaPipe Pose's landmark model, converted to ONNX) as a [`Segmenter`]: for
/// each person region of a view, the model runs on a square ROI around it (and once more
/// on the ROI its alignment points give), its landmarks and mask become the 7 classes with
/// a probability per pixel (`label_person`), and the people of the view are merged, the
/// one in front winning where they overlap (`merge_people`).
///
/// Without regions ([`ViewInput::regions`] `None`: colour-only input) the whole image is
/// one region; with an empty list (nobody found in 3D) the view is all background.
pub struct BlazePoseSegmenter {
    /// The session of a view with one region: all [`BlazePoseOptions::threads`] as ONNX
    /// Runtime intra-op threads.
    wide: Worker,
    /// Single-threaded sessions, one per region run at once, for views with several
    /// regions (empty when `threads` < 2): this model gains far less from a second
    /// intra-op thread than from a second region at once.
    narrow: Vec<Worker>,
    model_path: PathBuf,
    options: BlazePoseOptions,
}

/// One run's pose before its mask: the landmarks and flag decoded (`mask` empty) and the
/// mask's logits, made into the mask ([`Decoding::finish`]) only for the pose a region
/// keeps: the sigmoid of 256×256 logits is most of decoding, and the first run's pose is
/// dropped whenever the refinement pass is kept (that run has no mask at all when it is
/// made without the mask head, [`Worker::landmarks_only`]). Reads as its pose (`Deref`) for the
/// choices between runs, which look at landmarks and flags only.
struct Decoding {
    pose: DecodedPose,
    /// `None` for a run of [`Worker::landmarks_only`].
    mask_logits: Option<Vec<f32>>,
}

impl std::ops::Deref for Decoding {
    type Target = DecodedPose;
    fn deref(&self) -> &DecodedPose {
        &self.pose
    }
}

impl std::ops::DerefMut for Decoding {
    fn deref_mut(&mut self) -> &mut DecodedPose {
        &mut self.pose
    }
}

/// One ONNX Runtime session with its crop buffer: a region's runs stay on one worker.
struct Worker {
    session: Session,
    /// The same model without its mask output and the nodes only the mask needs (`None`
    /// when the graph could not be cut): a region's first run, whose mask is dropped
    /// whenever the refinement pass is kept, runs on it (the 256×256 mask decoder is over
    /// a third of a run with ONNX Runtime's AVX-512 kernels, its 8 channels padded to 16);
    /// landmarks, flag and heatmap are the same values as the full model's (the same nodes).
    landmarks_only: Option<Session>,
    /// The crop, reused from run to run (NHWC, 256×256×3).
    input: Vec<f32>,
    /// Inferences run so far (for benches and logs).
    runs: u64,
    /// BodyPix's session when the body parts come from it ([`parts`]).
    bodypix: Option<BodyPix>,
}

impl std::fmt::Debug for BlazePoseSegmenter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlazePoseSegmenter")
            .field("model_path", &self.model_path)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// Whether `got` (dims, −1 = dynamic) fits `want`.
fn dims_fit(got: &[i64], want: &[i64]) -> bool {
    got.len() == want.len() && got.iter().zip(want).all(|(&g, &w)| g == w || g == -1)
}

impl BlazePoseSegmenter {
    /// Loads a BlazePose landmark model from its bytes (read by the caller; `model_path`
    /// names it in errors) in the ONNX Runtime of `runtime_library`, and checks that it is
    /// one: input `input_1` float32 `[1,256,256,3]`; outputs `Identity` `[1,195]`,
    /// `Identity_1` `[1,1]`, `Identity_2` `[1,256,256,1]`, `Identity_3` `[1,64,64,39]`.
    ///
    /// # Errors
    /// [`ParsingError::RuntimeLibrary`], [`ParsingError::ModelLoad`],
    /// [`ParsingError::NotBlazePose`] naming the model file and what differs.
    pub fn new(
        runtime_library: &Path,
        model_bytes: &[u8],
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<BlazePoseSegmenter, ParsingError> {
        // A spinning pool is several times slower on a shared 2-core machine.
        let load = |intra_op_threads| {
            load_session(
                runtime_library,
                model_bytes,
                model_path,
                intra_op_threads,
                false,
            )
        };
        let session = load(options.threads)?;
        let not_blazepose = |reason: String| ParsingError::NotBlazePose {
            reason,
            path: model_path.to_path_buf(),
        };
        let inputs = session.inputs();
        let input_ok = inputs.len() == 1
            && inputs[0].name() == INPUT_NAME
            && float_dims(inputs[0].dtype()).is_some_and(|d| dims_fit(&d, &[1, 256, 256, 3]));
        if !input_ok {
            let got: Vec<String> = inputs
                .iter()
                .map(|i| format!("{} {:?}", i.name(), float_dims(i.dtype())))
                .collect();
            return Err(not_blazepose(format!(
                "inputs [{}], expected one: {INPUT_NAME} float32 [1, 256, 256, 3]",
                got.join(", ")
            )));
        }
        let wanted: [(&str, &[i64]); 4] = [
            (LANDMARKS.0, &LANDMARKS.1),
            (FLAG.0, &FLAG.1),
            (MASK.0, &MASK.1),
            (HEATMAP.0, &HEATMAP.1),
        ];
        for (name, want) in wanted {
            let Some(out) = session.outputs().iter().find(|o| o.name() == name) else {
                return Err(not_blazepose(format!(
                    "no output {name} (float32 {want:?})"
                )));
            };
            let dims = float_dims(out.dtype());
            if !dims.as_ref().is_some_and(|d| dims_fit(d, want)) {
                return Err(not_blazepose(format!(
                    "output {name} is {dims:?}, expected float32 {want:?}"
                )));
            }
        }
        let landmarks_only = without_outputs(model_bytes, &[MASK.0]);
        let worker = |session, intra_op_threads| -> Result<Worker, ParsingError> {
            let landmarks_only = landmarks_only
                .as_deref()
                .map(|bytes| {
                    load_session(runtime_library, bytes, model_path, intra_op_threads, false)
                })
                .transpose()?;
            Ok(Worker {
                session,
                landmarks_only,
                input: Vec::with_capacity(INPUT * INPUT * 3),
                runs: 0,
                bodypix: None,
            })
        };
        let narrow = if options.threads >= 2 {
            (0..options.threads)
                .map(|_| worker(load(1)?, 1))
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        tracing::debug!(model = %model_path.display(), "loaded BlazePose landmark model");
        Ok(BlazePoseSegmenter {
            wide: worker(session, options.threads)?,
            narrow,
            model_path: model_path.to_path_buf(),
            options: options.clone(),
        })
    }

    /// The options it runs with.
    pub fn options(&self) -> &BlazePoseOptions {
        &self.options
    }

    /// Landmark-model runs so far.
    pub fn runs(&self) -> u64 {
        self.wide.runs + self.narrow.iter().map(|w| w.runs).sum::<u64>()
    }

    /// Labels one view: every region's person (or the whole image as one region when
    /// `regions` is `None`), merged. Several regions are shared out over the single-threaded
    /// sessions and run at once; the people are merged in region order, so the labels do
    /// not depend on how many sessions there are.
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    pub fn segment_image(
        &mut self,
        image: &RgbImage,
        regions: Option<&[PersonRegion]>,
    ) -> Result<LabelImage, ParsingError> {
        if self.wide.bodypix.is_some() {
            return self.segment_with_bodypix(image, regions);
        }
        let (w, h) = (image.width as usize, image.height as usize);
        let people: Vec<PersonLabels> = self
            .per_region(image, regions, Worker::person)?
            .into_iter()
            .flatten()
            .collect();
        Ok(merge_people(w, h, &people))
    }

    /// The pose found for each region (in region order; the whole image as one region when
    /// `regions` is `None`), as [`BlazePoseSegmenter::segment_image`] labels them: `None`
    /// where the region is unusable or its pose flag is below
    /// [`BlazePoseOptions::min_pose_flag`]. For figures and studies of the rule.
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    pub fn poses(
        &mut self,
        image: &RgbImage,
        regions: Option<&[PersonRegion]>,
    ) -> Result<Vec<Option<DecodedPose>>, ParsingError> {
        self.per_region(image, regions, Worker::accepted_pose)
    }

    /// `f` on every region (the whole image when `regions` is `None`), results in region
    /// order: one region on the wide session, several shared out over the single-threaded
    /// ones and run at once.
    fn per_region<T: Send>(
        &mut self,
        image: &RgbImage,
        regions: Option<&[PersonRegion]>,
        f: fn(
            &mut Worker,
            &RgbImage,
            &PersonRegion,
            &Path,
            &BlazePoseOptions,
        ) -> Result<T, ParsingError>,
    ) -> Result<Vec<T>, ParsingError> {
        let (w, h) = (image.width as usize, image.height as usize);
        let whole = [PersonRegion {
            bounds: PixelBox {
                x0: 0.0,
                y0: 0.0,
                x1: (w.max(1) - 1) as f64,
                y1: (h.max(1) - 1) as f64,
            },
            depth_m: f64::NAN,
        }];
        let regions = regions.unwrap_or(&whole);
        let (model_path, options) = (&self.model_path, &self.options);
        if regions.len() < 2 || self.narrow.is_empty() {
            return regions
                .iter()
                .map(|region| f(&mut self.wide, image, region, model_path, options))
                .collect();
        }
        let n = self.narrow.len();
        let per_worker: Vec<Result<Vec<(usize, T)>, ParsingError>> = self
            .narrow
            .par_iter_mut()
            .enumerate()
            .map(|(k, worker)| {
                regions
                    .iter()
                    .enumerate()
                    .skip(k)
                    .step_by(n)
                    .map(|(i, region)| Ok((i, f(worker, image, region, model_path, options)?)))
                    .collect()
            })
            .collect();
        let mut out = Vec::with_capacity(regions.len());
        for part in per_worker {
            out.extend(part?);
        }
        out.sort_by_key(|&(i, _)| i);
        Ok(out.into_iter().map(|(_, t)| t).collect())
    }
}

/// The labels of `pose`, the person of `region` in `image`, with the region's depth;
/// `None` when the pose labels no pixel.
fn person_of(
    pose: &DecodedPose,
    image: &RgbImage,
    region: &PersonRegion,
    options: &BlazePoseOptions,
) -> Option<PersonLabels> {
    let (w, h) = (image.width as usize, image.height as usize);
    label_person(pose, &options.rule, w, h).map(|mut person| {
        person.depth_m =
            (region.depth_m.is_finite() && region.depth_m > 0.0).then_some(region.depth_m);
        person
    })
}

impl Worker {
    /// The labels of `region`'s person, `None` when the region is unusable or nobody is
    /// found there.
    fn person(
        &mut self,
        image: &RgbImage,
        region: &PersonRegion,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<Option<PersonLabels>, ParsingError> {
        let pose = self.accepted_pose(image, region, model_path, options)?;
        Ok(pose.and_then(|pose| person_of(&pose, image, region, options)))
    }

    /// The pose of `region`'s person, `None` when the region is unusable or its pose flag
    /// is below [`BlazePoseOptions::min_pose_flag`].
    fn accepted_pose(
        &mut self,
        image: &RgbImage,
        region: &PersonRegion,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<Option<DecodedPose>, ParsingError> {
        let b = &region.bounds;
        let usable =
            [b.x0, b.y0, b.x1, b.y1].iter().all(|v| v.is_finite()) && b.x1 >= b.x0 && b.y1 >= b.y0;
        if !usable {
            return Ok(None);
        }
        self.pose_in(image, b, model_path, options)
    }

    /// One run of the landmark model on `roi` of `image`.
    ///
    /// # Errors
    /// [`ParsingError::Inference`] naming the model file.
    fn run(
        &mut self,
        image: &RgbImage,
        roi: &Roi,
        model_path: &Path,
    ) -> Result<Decoding, ParsingError> {
        self.run_seeing(image, roi, None, false, true, model_path)
    }

    /// A region's first run: [`Worker::run`] without the mask when there is a
    /// [`Worker::landmarks_only`] session ([`Worker::finish`] makes the mask if the pose
    /// is kept).
    ///
    /// # Errors
    /// [`ParsingError::Inference`] naming the model file.
    fn first_run(
        &mut self,
        image: &RgbImage,
        roi: &Roi,
        model_path: &Path,
    ) -> Result<Decoding, ParsingError> {
        self.run_seeing(image, roi, None, false, false, model_path)
    }

    /// The pose of `run` with its mask (as [`crate::blazepose::decode`] gives it). A run
    /// without the mask ([`Worker::first_run`]) is made again on the full model, on the
    /// same ROI (unblanked, unmirrored, as first runs are); the pose is that run's but for
    /// the flag, which stays `run`'s (a pose that left its region has flag 0).
    ///
    /// # Errors
    /// [`ParsingError::Inference`] naming the model file.
    fn finish(
        &mut self,
        image: &RgbImage,
        run: Decoding,
        model_path: &Path,
    ) -> Result<DecodedPose, ParsingError> {
        let Decoding { pose, mask_logits } = match run.mask_logits {
            Some(_) => run,
            None => {
                let mut full = self.run(image, &run.roi, model_path)?;
                full.pose.flag = run.flag;
                full
            }
        };
        Ok(DecodedPose {
            mask: mask_from_logits(mask_logits.as_deref().unwrap_or(&[])),
            ..pose
        })
    }

    /// [`Worker::run`] on a crop blanked (black) outside `only` when given, and mirrored
    /// (left ↔ right, the outputs brought back to the unmirrored crop) when `mirror`; on
    /// [`Worker::landmarks_only`] (no mask logits) when `mask` is false and there is one.
    ///
    /// # Errors
    /// [`ParsingError::Inference`] naming the model file.
    fn run_seeing(
        &mut self,
        image: &RgbImage,
        roi: &Roi,
        only: Option<&PixelBox>,
        mirror: bool,
        mask: bool,
        model_path: &Path,
    ) -> Result<Decoding, ParsingError> {
        crop_into(image, roi, INPUT, &mut self.input);
        if let Some(keep) = only {
            blank_outside(&mut self.input, roi, INPUT, keep, 0.0);
        }
        if mirror {
            mirror_crop(&mut self.input, INPUT);
        }
        let path = model_path;
        let infer = |cause: String| inference_error(path, cause);
        let (session, with_mask) = match self.landmarks_only.as_mut() {
            Some(session) if !mask => (session, false),
            _ => (&mut self.session, true),
        };
        let outputs = run_one_input(session, INPUT_NAME, [1, INPUT, INPUT, 3], &self.input, path)?;
        let get = |name: &str| named_output::<f32>(&outputs, name, path).map(|(_, data)| data);
        let landmarks = get(LANDMARKS.0)?;
        let flag = get(FLAG.0)?.first().copied().unwrap_or(0.0);
        let mask = if with_mask { get(MASK.0)? } else { &[] };
        let heatmap = get(HEATMAP.0)?;
        self.runs += 1;
        let unmirrored;
        let (landmarks, mask, heatmap) = if mirror {
            unmirrored = unmirror_outputs(landmarks, mask, heatmap);
            let [l, m, h] = &unmirrored;
            (&l[..], &m[..], &h[..])
        } else {
            (landmarks, mask, heatmap)
        };
        let pose = decode_landmarks(roi, landmarks, flag, Some(heatmap))
            .filter(|_| !with_mask || mask.len() >= INPUT * INPUT);
        let pose = pose.ok_or_else(|| {
            infer(format!(
                "outputs shorter than BlazePose's ({} landmark values, {} mask values)",
                landmarks.len(),
                mask.len()
            ))
        })?;
        Ok(Decoding {
            pose,
            mask_logits: with_mask.then(|| mask[..INPUT * INPUT].to_vec()),
        })
    }

    /// The pose of the person in `bounds` (image px): a run on the ROI around it
    /// ([`BlazePoseOptions::roi_scale`]), then up to
    /// [`BlazePoseOptions::refine_passes`] runs on the ROI of the previous run's alignment
    /// points, each kept only while the pose flag holds and the pose stays in the region.
    ///
    /// A crowded crop may lock onto a neighbour: a pose whose body centre (MediaPipe's
    /// alignment centre, the mid-hip point) lies outside `bounds` widened by
    /// [`REGION_SLACK`] of its size is not this person's. Then (and when the first pose's
    /// flag is below [`BlazePoseOptions::min_pose_flag`]) one run on the tighter ROI of
    /// [`RETRY_ROI_SCALE`] × the region is tried, and kept when its centre is in the region
    /// (and its flag higher); the retry's crop is blanked outside the widened region
    /// ([`BlazePoseOptions::blank_retry`]). When neither pose is in the region the result
    /// has flag 0 (no person). `None` when the pose's flag is below
    /// [`BlazePoseOptions::min_pose_flag`] (its mask is then never made).
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    fn pose_in(
        &mut self,
        image: &RgbImage,
        bounds: &PixelBox,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<Option<DecodedPose>, ParsingError> {
        let (pose, only) = self.first_pose_in(image, bounds, model_path, options)?;
        if pose.flag < options.min_pose_flag {
            return Ok(None);
        }
        let pose = self.finish(image, pose, model_path)?;
        if !options.mirror_average {
            return Ok(Some(pose));
        }
        let mirrored = self.run_seeing(image, &pose.roi, only.as_ref(), true, true, model_path)?;
        let mirrored = self.finish(image, mirrored, model_path)?;
        Ok(Some(average_masks(&pose, &mirrored)))
    }

    /// [`Worker::pose_in`] before the mirrored run: the pose and the box its crop was
    /// blanked outside (the blanked retry's), if any.
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    fn first_pose_in(
        &mut self,
        image: &RgbImage,
        bounds: &PixelBox,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<(Decoding, Option<PixelBox>), ParsingError> {
        let (w, h) = (image.width as usize, image.height as usize);
        let roi = Roi::from_box(bounds, options.roi_scale);
        let mut pose = self.first_run(image, &roi, model_path)?;
        let inside = centre_inside(&pose, bounds, w, h);
        if !inside || pose.flag < options.min_pose_flag {
            let wide = widened(bounds);
            let only = options.blank_retry.then_some(&wide);
            let retry = self.run_seeing(
                image,
                &Roi::from_box(bounds, RETRY_ROI_SCALE),
                only,
                false,
                true,
                model_path,
            )?;
            if centre_inside(&retry, bounds, w, h) && (!inside || retry.flag > pose.flag) {
                return Ok((retry, only.copied()));
            }
            if !inside {
                pose.flag = 0.0;
            }
            return Ok((pose, None));
        }
        for _ in 0..options.refine_passes {
            if pose.flag < MIN_FLAG_TO_REFINE || pose.xy.len() < NUM_LANDMARKS {
                break;
            }
            let roi = Roi::from_alignment(
                pose.xy[landmark::ALIGN_CENTRE],
                pose.xy[landmark::ALIGN_SCALE],
                ALIGNMENT_ROI_SCALE,
            );
            let side = pose.roi.side_px;
            if !(roi.side_px.is_finite()
                && roi.side_px >= side / MAX_ROI_CHANGE
                && roi.side_px <= side * MAX_ROI_CHANGE)
            {
                break;
            }
            let next = self.run(image, &roi, model_path)?;
            if next.flag < pose.flag * MIN_FLAG_RATIO || !centre_inside(&next, bounds, w, h) {
                break;
            }
            pose = next;
        }
        Ok((pose, None))
    }
}

impl Segmenter for BlazePoseSegmenter {
    fn needs_regions(&self) -> bool {
        true
    }

    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError> {
        let mut parsed = Vec::with_capacity(views.len());
        for (view, input) in views.iter().enumerate() {
            let image = input.checked_image(view)?;
            let labels = self.segment_image(image, input.regions)?;
            parsed.push(ParsedView {
                labels,
                class_probs: None,
            });
        }
        Ok(parsed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blazepose::figure::sure_pose;

    fn pose_centred_at(c: [f64; 2]) -> DecodedPose {
        let mut xy = vec![[0.0, 0.0]; NUM_LANDMARKS];
        xy[landmark::ALIGN_CENTRE] = c;
        sure_pose(xy, c, 100.0, Vec::new())
    }

    /// A pose drifted onto a neighbour (centre beyond the region's 10 % slack) is not the
    /// region's person; one at the edge of the slack still is.
    #[test]
    fn a_pose_belongs_to_the_region_holding_its_centre() {
        let region = PixelBox {
            x0: 100.0,
            y0: 50.0,
            x1: 200.0,
            y1: 450.0,
        };
        assert!(centre_inside(
            &pose_centred_at([150.0, 250.0]),
            &region,
            1000,
            1000
        ));
        assert!(
            centre_inside(&pose_centred_at([209.0, 250.0]), &region, 1000, 1000),
            "slack"
        );
        assert!(
            !centre_inside(&pose_centred_at([211.0, 250.0]), &region, 1000, 1000),
            "neighbour"
        );
        assert!(!centre_inside(
            &pose_centred_at([150.0, 500.0]),
            &region,
            1000,
            1000
        ));
        assert!(!centre_inside(
            &pose_centred_at([f64::NAN, 250.0]),
            &region,
            1000,
            1000
        ));
        let mut short = pose_centred_at([150.0, 250.0]);
        short.xy.truncate(10);
        assert!(
            !centre_inside(&short, &region, 1000, 1000),
            "no alignment point"
        );
    }

    /// A close-up: the region reaches the image's bottom and the mid-hip point lies below
    /// the image; clamped to the image it is in the region. Beside the region it is not.
    #[test]
    fn a_centre_below_the_image_counts_where_it_enters_it() {
        let region = PixelBox {
            x0: 100.0,
            y0: 50.0,
            x1: 300.0,
            y1: 479.0,
        };
        let below = pose_centred_at([200.0, 700.0]);
        assert!(centre_inside(&below, &region, 640, 480));
        assert!(!centre_inside(&below, &region, 640, 1000), "taller image");
        assert!(!centre_inside(
            &pose_centred_at([500.0, 700.0]),
            &region,
            640,
            480
        ));
    }

    /// The landmark model cut at its mask output gives the full model's landmarks, flag and
    /// heatmap bit for bit (the first run's decisions are the full model's) and no mask, on
    /// crops of a patterned image. Needs ONNX Runtime (ORT_DYLIB_PATH or the project's
    /// copy), as the crate's other model tests.
    #[test]
    fn the_maskless_model_gives_the_full_models_landmarks() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let model = root.join("models/blazepose_full.onnx");
        let bytes = std::fs::read(&model).expect("committed BlazePose model");
        let cut = without_outputs(&bytes, &[MASK.0]).expect("the mask output can be cut");
        assert!(cut.len() < bytes.len());
        let library = std::env::var_os("ORT_DYLIB_PATH")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join(".deps/onnxruntime/libonnxruntime.so"));
        let mut full = load_session(&library, &bytes, &model, 1, false).expect("full model");
        let mut maskless = load_session(&library, &cut, &model, 1, false).expect("cut model");
        assert!(maskless.outputs().iter().all(|o| o.name() != MASK.0));
        let (w, h) = (320u32, 240u32);
        let rgb = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
        let image = RgbImage::new(w, h, rgb).expect("w*h*3 bytes");
        let mut input = Vec::new();
        for (centre_px, angle_rad) in [([160.0, 120.0], 0.0), ([100.0, 150.0], 0.4)] {
            let roi = Roi {
                centre_px,
                side_px: 200.0,
                angle_rad,
            };
            crop_into(&image, &roi, INPUT, &mut input);
            let outputs_of = |session: &mut Session| -> Vec<Vec<u32>> {
                let outputs =
                    run_one_input(session, INPUT_NAME, [1, INPUT, INPUT, 3], &input, &model)
                        .expect("a run");
                [LANDMARKS.0, FLAG.0, HEATMAP.0]
                    .iter()
                    .map(|name| {
                        let (_, data) = named_output::<f32>(&outputs, name, &model).expect(name);
                        data.iter().map(|v| v.to_bits()).collect()
                    })
                    .collect()
            };
            let want = outputs_of(&mut full);
            assert_eq!(outputs_of(&mut maskless), want);
            assert_eq!(want[0].len(), 195);
        }
    }
}
