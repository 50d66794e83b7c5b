//! Body parts from BodyPix inside [`BlazePoseSegmenter`] (`parsing.body_parts = "bodypix"`):
//! every region runs BlazePose and BodyPix on the same worker (regions at once, as
//! BlazePose alone), then BlazePose's merged labels and BodyPix's merged map are fused
//! ([`crate::bodypix::fuse`]: fusion C of docs/notes/2026-12-04-bodypix-probe.md), with the
//! person mask cleaned on both sides of the fusion ([`super::person_mask`]: BlazePose's
//! pixels where BodyPix is sure of background before, pieces held by nothing after).

use super::person_mask::{ANCHOR_MIN_VISIBILITY, Anchors, drop_detached, veto_blazepose};
use super::{BlazePoseOptions, BlazePoseSegmenter, Worker, person_of};
use crate::ParsingError;
use crate::blazepose::{DecodedPose, PersonLabels, merge_people};
use crate::bodypix::{BodyPix, PartMap, fuse, merge_part_maps};
use crate::segmenter::PersonRegion;
use bodyseg_core::{LabelImage, RgbImage};
use std::path::Path;

impl BlazePoseSegmenter {
    /// The same segmenter with its body parts from BodyPix (`model_bytes`, `model_path`
    /// naming it in errors): one BodyPix session per BlazePose session, with the same
    /// threads ([`BlazePoseOptions::bodypix`] sets its crop and threshold).
    ///
    /// # Errors
    /// [`ParsingError::RuntimeLibrary`], [`ParsingError::ModelLoad`],
    /// [`ParsingError::NotBodyPix`] naming the file.
    pub fn with_bodypix(
        mut self,
        runtime_library: &Path,
        model_bytes: &[u8],
        model_path: &Path,
    ) -> Result<BlazePoseSegmenter, ParsingError> {
        let load = |threads| BodyPix::new(runtime_library, model_bytes, model_path, threads);
        self.wide.bodypix = Some(load(self.options.threads)?);
        for worker in &mut self.narrow {
            worker.bodypix = Some(load(1)?);
        }
        tracing::debug!(model = %model_path.display(), "body parts from BodyPix");
        Ok(self)
    }

    /// Whether the body parts come from BodyPix ([`BlazePoseSegmenter::with_bodypix`]).
    pub fn uses_bodypix(&self) -> bool {
        self.wide.bodypix.is_some()
    }

    /// [`BlazePoseSegmenter::segment_image`] with BodyPix's parts: BlazePose's people
    /// (their rims vetoed where BodyPix sees background) merged, BodyPix's regions merged,
    /// the two fused, pieces held by nothing dropped.
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    pub(super) fn segment_with_bodypix(
        &mut self,
        image: &RgbImage,
        regions: Option<&[PersonRegion]>,
    ) -> Result<LabelImage, ParsingError> {
        let (w, h) = (image.width as usize, image.height as usize);
        let found = self.per_region(image, regions, Worker::person_and_parts)?;
        let options = &self.options;
        let mut anchors = Anchors::default();
        let (mut people, mut maps) = (Vec::new(), Vec::new());
        for region in found {
            match (region.person, region.parts) {
                (Some(person), parts) => {
                    anchors.landmarks.extend(region.landmarks);
                    people.push(person);
                    maps.extend(parts);
                }
                (None, Some(parts)) => {
                    anchors
                        .free_windows
                        .push((parts.u0, parts.u1, parts.v0, parts.v1));
                    maps.push(parts);
                }
                (None, None) => {}
            }
        }
        let merged = merge_part_maps(w, h, &maps);
        for person in &mut people {
            veto_blazepose(
                person,
                &merged,
                options.bodypix_background_below,
                options.bodypix.threshold,
                w,
            );
        }
        let mut labels = merge_people(w, h, &people);
        if options.drop_detached {
            anchors.blazepose = labels
                .labels
                .iter()
                .map(|l| (1..7).contains(&l.id()))
                .collect();
        }
        fuse(&mut labels, &merged, options.bodypix.threshold);
        if options.drop_detached {
            drop_detached(&mut labels, &anchors);
        }
        Ok(labels)
    }
}

/// What one region gives the fusion.
struct RegionParts {
    /// BlazePose's person (`None`: nobody found, or the region is unusable).
    person: Option<PersonLabels>,
    /// BodyPix's map of the region (`None`: the region is unusable or misses the image).
    parts: Option<PartMap>,
    /// The person's confident landmarks, image px: visibility ≥
    /// [`ANCHOR_MIN_VISIBILITY`], presence ≥ the rule's `min_presence`.
    landmarks: Vec<[f64; 2]>,
}

/// The landmarks of `pose` that anchor its person's pieces of the mask
/// (`person_mask::drop_detached`).
fn confident_landmarks(pose: &DecodedPose, options: &BlazePoseOptions) -> Vec<[f64; 2]> {
    pose.xy
        .iter()
        .zip(pose.visibility.iter().zip(&pose.presence))
        .filter(|&(xy, (&visibility, &presence))| {
            xy.iter().all(|c| c.is_finite())
                && visibility >= ANCHOR_MIN_VISIBILITY
                && presence >= options.rule.min_presence
        })
        .map(|(&xy, _)| xy)
        .collect()
}

impl Worker {
    /// BlazePose's person of `region`, its confident landmarks and BodyPix's map of the
    /// region (BodyPix runs on every usable region, whatever BlazePose finds).
    fn person_and_parts(
        &mut self,
        image: &RgbImage,
        region: &PersonRegion,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<RegionParts, ParsingError> {
        let pose = self.accepted_pose(image, region, model_path, options)?;
        let person = pose
            .as_ref()
            .and_then(|pose| person_of(pose, image, region, options));
        let landmarks = match (&pose, &person) {
            (Some(pose), Some(_)) => confident_landmarks(pose, options),
            _ => Vec::new(),
        };
        let parts = match self.bodypix.as_mut() {
            Some(bodypix) => bodypix.run_region(image, &region.bounds, &options.bodypix)?,
            None => None,
        };
        Ok(RegionParts {
            person,
            parts,
            landmarks,
        })
    }
}
