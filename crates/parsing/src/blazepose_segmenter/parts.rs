//! Body parts from BodyPix inside [`BlazePoseSegmenter`] (`parsing.body_parts = "bodypix"`):
//! every region runs BlazePose and BodyPix on the same worker (regions at once, as
//! BlazePose alone), then BlazePose's merged labels and BodyPix's merged map are fused
//! ([`crate::bodypix::fuse`]: fusion C of docs/notes/2026-12-04-bodypix-probe.md).

use super::{BlazePoseOptions, BlazePoseSegmenter, Worker};
use crate::ParsingError;
use crate::blazepose::{PersonLabels, merge_people};
use crate::bodypix::{BodyPix, PartMap, fuse_part_maps};
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
    /// merged, BodyPix's regions merged and fused with them row by row.
    ///
    /// # Errors
    /// [`ParsingError::Inference`].
    pub(super) fn segment_with_bodypix(
        &mut self,
        image: &RgbImage,
        regions: Option<&[PersonRegion]>,
    ) -> Result<LabelImage, ParsingError> {
        let (w, h) = (image.width as usize, image.height as usize);
        let (people, maps): (Vec<_>, Vec<_>) = self
            .per_region(image, regions, Worker::person_and_parts)?
            .into_iter()
            .unzip();
        let people: Vec<PersonLabels> = people.into_iter().flatten().collect();
        let maps: Vec<PartMap> = maps.into_iter().flatten().collect();
        let mut labels = merge_people(w, h, &people);
        fuse_part_maps(&mut labels, &maps, self.options.bodypix.threshold);
        Ok(labels)
    }
}

impl Worker {
    /// BlazePose's person of `region` and BodyPix's map of it (either `None` where the
    /// region gives nothing: BodyPix runs on every usable region, whatever BlazePose finds).
    fn person_and_parts(
        &mut self,
        image: &RgbImage,
        region: &PersonRegion,
        model_path: &Path,
        options: &BlazePoseOptions,
    ) -> Result<(Option<PersonLabels>, Option<PartMap>), ParsingError> {
        let person = self.person(image, region, model_path, options)?;
        let parts = match self.bodypix.as_mut() {
            Some(bodypix) => bodypix.run_region(image, &region.bounds, &options.bodypix)?,
            None => None,
        };
        Ok((person, parts))
    }
}
