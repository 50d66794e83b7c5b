//! [`ViewWriter`]: a [`FrameSink`] that streams frames into a `.rrd` file with the Rerun
//! SDK (`re_sdk`). The rig, the class palette and the blueprint are logged once (static);
//! each frame on the `frame` timeline (and `time`), then dropped. A frame's images and
//! clouds are made into chunks and encoded by the worker that gives the frame, and written
//! at once (`crate::sink`); its boxes and scores are gathered with other frames' into one
//! chunk per entity (`crate::rows`). What grows with the recording is the footer's index of
//! chunks, kept compact until the file ends (`crate::manifest`;
//! docs/notes/2026-12-02-rerun.md).

use crate::encoder::Lz4;
use crate::order::{self, CloudBatch, Layers, Paint};
use crate::paths;
use crate::rows::{self, ROWS_PER_CHUNK, Row, SmallRows};
use crate::{CameraView, CloudView, FrameSink, ImageFileFormat, ViewError, ViewFrame};
use bodyseg_calib::{Intrinsics, Pose, Rig};
use bodyseg_core::{Class, Label, LabelImage, PersonBox};
use re_sdk::blueprint::{
    Blueprint, BlueprintActivation, ContainerLike, Horizontal, Spatial2DView, Spatial3DView,
    TimeSeriesView, Vertical,
};
use re_sdk::external::arrow::array::ArrayRef;
use re_sdk::external::re_log_types::StoreId;
use re_sdk::log::{Chunk, RowId};
use re_sdk::{AsComponents, RecordingStream, RecordingStreamBuilder, SerializedComponentBatch};
use re_sdk_types::archetypes::{
    AnnotationContext, Boxes3D, DepthImage, EncodedImage, Image, Pinhole, Points3D, Scalars,
    SegmentationImage, Transform3D, ViewCoordinates,
};
use re_sdk_types::components::{ImageFormat, MediaType};
use re_sdk_types::datatypes::{
    Angle, AnnotationInfo, ChannelDatatype, ClassDescription, Quaternion, Rgba32, RotationAxisAngle,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The application id the files carry (the viewer groups recordings by it).
const APPLICATION_ID: &str = "bodyseg";

/// Colour of unknown points and pixels (id 255): light grey, apart from every class.
const UNKNOWN_RGB: [u8; 3] = [200, 200, 200];

/// Radius of logged points, metres: about the spacing of a Kinect v2's points at 2 m
/// with stride 2, so a cloud reads as a surface.
const POINT_RADIUS_M: f32 = 0.004;

/// Streams a run's frames into a `.rrd` file (see the crate documentation for what is
/// logged where). Thread-safe: frames may come from any worker in any order; the
/// timeline, not the order of calls, orders them.
///
/// The file is written to `<path>.partial` and renamed to `path` by
/// [`ViewWriter::finish`]; a writer dropped without `finish` leaves only the partial file.
/// Frames given after `finish` are dropped (the file is closed).
pub struct ViewWriter {
    rec: RecordingStream,
    /// The file, also the SDK's sink: the images and clouds are written here directly.
    file: Arc<crate::sink::RrdFile>,
    /// The recording's id (its chunks' store).
    store_id: StoreId,
    path: PathBuf,
    partial: PathBuf,
    /// Camera names, rig order.
    cameras: Vec<String>,
    /// Each camera's raw depth units per metre (`depth_scale`), rig order.
    depth_scales: Vec<f32>,
    /// Frame stem → (index on the `frame` timeline, time stamp in ns).
    frames: BTreeMap<String, (i64, Option<i64>)>,
    /// Whether the clusters layer is written (off by default: a third copy of the cloud).
    clusters: bool,
    /// The boxes and scores of frames, gathered into chunks of many frames (`crate::rows`).
    small_rows: SmallRows,
}

impl std::fmt::Debug for ViewWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ViewWriter")
            .field("path", &self.path)
            .field("cameras", &self.cameras)
            .field("frames", &self.frames.len())
            .finish_non_exhaustive()
    }
}

impl ViewWriter {
    /// Creates the file for a recording named `name` with this rig; `frames` are all the
    /// recording's frames in order (their index is the `frame` timeline), `stamps` their
    /// time stamps (ns since the Unix epoch, by stem; frames without one get none).
    /// Logs the cameras, the class annotation and the blueprint.
    ///
    /// # Errors
    /// [`ViewError::Rerun`] when the file cannot be created or the static data not logged.
    pub fn create(
        path: &Path,
        name: &str,
        rig: &Rig,
        frames: &[String],
        stamps: &[(String, i64)],
    ) -> Result<ViewWriter, ViewError> {
        let partial = partial_path(path);
        let err = |e: &dyn std::fmt::Display| ViewError::Rerun {
            message: e.to_string(),
            path: path.to_path_buf(),
        };
        // The SDK's sink for a file, but written past the page cache (`sink` module).
        let rec = RecordingStreamBuilder::new(APPLICATION_ID)
            .recording_name(name)
            .buffered()
            .map_err(|e| err(&e))?;
        let file = crate::sink::RrdFile::create(&partial).map_err(|e| err(&e))?;
        rec.set_sink(Box::new(crate::sink::RrdFileSink::new(file.clone())));
        let store_id = rec
            .store_info()
            .ok_or_else(|| err(&"the recording stream is disabled"))?
            .store_id;
        // No `log_time` timeline: the wall-clock time at which a worker logged a frame says
        // nothing about the recording (frames come from parallel workers, out of order),
        // and it doubled the footer manifest's columns, which grow with every chunk
        // (docs/notes/2026-12-02-rerun.md, 2026-12-04, session 43).
        rec.set_log_time_enabled(false);
        let stamps: BTreeMap<&str, i64> = stamps.iter().map(|(s, t)| (s.as_str(), *t)).collect();
        let frames = frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.clone(), (i as i64, stamps.get(f.as_str()).copied())))
            .collect();
        let writer = ViewWriter {
            rec,
            file,
            store_id,
            path: path.to_path_buf(),
            partial,
            cameras: rig.cameras.iter().map(|c| c.name.clone()).collect(),
            depth_scales: rig.cameras.iter().map(|c| c.depth_scale as f32).collect(),
            frames,
            clusters: false,
            small_rows: SmallRows::new(ROWS_PER_CHUNK),
        };
        writer.log_static(rig).map_err(|e| err(&e))?;
        // The store info and the static data in the file before any frame's chunk.
        writer.rec.flush_blocking().map_err(|e| err(&e))?;
        Ok(writer)
    }

    /// Also writes the clusters layer (`world/clusters`: the refined cloud's positions once
    /// more, coloured by cluster). Off by default: it adds about half again to the file and
    /// to the time spent writing it.
    #[must_use]
    pub fn with_clusters(mut self, on: bool) -> ViewWriter {
        self.clusters = on;
        self
    }

    /// The final path of the file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes everything to the file, closes it and renames it into place. Frames
    /// written after this are dropped.
    ///
    /// # Errors
    /// [`ViewError::Rerun`] when the flush or the rename fails.
    pub fn finish(&self) -> Result<PathBuf, ViewError> {
        let err = |e: &dyn std::fmt::Display| ViewError::Rerun {
            message: e.to_string(),
            path: self.path.clone(),
        };
        self.write_rows(self.small_rows.take_all())?;
        self.rec.flush_blocking().map_err(|e| err(&e))?;
        // Nothing more from the SDK; then the end of the stream and the footer.
        self.rec.disconnect();
        self.file.close().map_err(|e| err(&e))?;
        std::fs::rename(&self.partial, &self.path).map_err(|e| err(&e))?;
        Ok(self.path.clone())
    }

    fn log_static(&self, rig: &Rig) -> re_sdk::RecordingStreamResult<()> {
        let rec = &self.rec;
        rec.log_static(paths::WORLD, &ViewCoordinates::RIGHT_HAND_Z_UP())?;
        rec.log_static(paths::WORLD, &annotation_context())?;
        for camera in &rig.cameras {
            let world_from_color = camera
                .world_from_depth
                .compose(&camera.color_from_depth.inverse());
            for (entity, pose, intrinsics) in [
                (paths::color(&camera.name), &world_from_color, &camera.color),
                (
                    paths::depth(&camera.name),
                    &camera.world_from_depth,
                    &camera.depth,
                ),
            ] {
                rec.log_static(entity.as_str(), &transform(pose))?;
                rec.log_static(entity.as_str(), &pinhole(intrinsics))?;
            }
        }
        self.blueprint().send(rec, BlueprintActivation::default())
    }

    /// The layout: the 3D world (clusters left out: add `world/clusters` back in the
    /// view's entity list), each camera's colour image with its labels, the scores.
    fn blueprint(&self) -> Blueprint {
        let world = Spatial3DView::new("world")
            .with_origin(paths::WORLD)
            .with_contents([
                format!("+ /{}/**", paths::WORLD),
                format!("- /{}", paths::CLUSTERS),
            ]);
        let cameras: Vec<ContainerLike> = self
            .cameras
            .iter()
            .map(|c| {
                Spatial2DView::new(c.as_str())
                    .with_origin(paths::color(c).as_str())
                    .into()
            })
            .collect();
        let scores = TimeSeriesView::new("scores").with_origin(paths::SCORES);
        Blueprint::new(Horizontal::new([
            ContainerLike::from(world),
            Vertical::new([
                ContainerLike::from(Vertical::new(cameras)),
                ContainerLike::from(scores),
            ])
            .into(),
        ]))
    }

    fn write(&self, frame: &ViewFrame<'_>) -> Result<(), ViewError> {
        let stem = frame.stem;
        let &(index, stamp) = self
            .frames
            .get(stem)
            .ok_or_else(|| ViewError::UnknownFrame { stem: stem.into() })?;
        if !frame.cameras.is_empty() && frame.cameras.len() != self.cameras.len() {
            return Err(ViewError::CameraCount {
                stem: stem.into(),
                got: frame.cameras.len(),
                want: self.cameras.len(),
            });
        }
        let rec = &self.rec;
        // Per thread: this worker's logs below go to this frame's time.
        rec.set_time_sequence(paths::FRAME_TIMELINE, index);
        match stamp {
            Some(ns) => rec.set_timestamp_nanos_since_epoch(paths::TIME_TIMELINE, ns),
            None => rec.disable_timeline(paths::TIME_TIMELINE),
        }
        let result = self.write_at_time(frame, index);
        rec.reset_time();
        result
    }

    fn write_at_time(&self, frame: &ViewFrame<'_>, index: i64) -> Result<(), ViewError> {
        let stem = frame.stem;
        for ((name, scale), camera) in self
            .cameras
            .iter()
            .zip(&self.depth_scales)
            .zip(&frame.cameras)
        {
            self.log_camera(stem, name, *scale, camera)?;
        }
        for (layer, cloud) in [("projected", frame.projected), ("refined", frame.refined)] {
            if let Some(cloud) = cloud
                && cloud.labels.len() != cloud.positions_m.len()
            {
                return Err(ViewError::CloudLength {
                    stem: stem.into(),
                    layer,
                    positions: cloud.positions_m.len(),
                    labels: cloud.labels.len(),
                });
            }
        }
        let clusters = match (
            self.clusters,
            frame.clusters,
            frame.refined.or(frame.projected),
        ) {
            (true, Some(clusters), Some(cloud)) => {
                if clusters.len() != cloud.positions_m.len() {
                    return Err(ViewError::CloudLength {
                        stem: stem.into(),
                        layer: "clusters",
                        positions: cloud.positions_m.len(),
                        labels: clusters.len(),
                    });
                }
                Some(clusters)
            }
            _ => None,
        };
        for batch in frame_cloud_batches(frame.projected, frame.refined, clusters) {
            for row in points_rows(batch.positions, batch.paint) {
                self.log_chunk(batch.entity, &row, Lz4::WhereWorth)?;
            }
        }
        // The small rows: gathered with other frames' (`crate::rows`).
        let time = self.rec.now();
        let row = |what: &dyn AsComponents| Row {
            frame: index,
            time: time.clone(),
            components: what.as_serialized_batches(),
        };
        let boxes = frame
            .boxes
            .map(|boxes| (paths::BOXES.to_string(), row(&boxes_3d(boxes))));
        let scores = frame
            .scores
            .iter()
            .map(|(name, value)| (paths::score(name), row(&Scalars::single(*value))));
        let full = self.small_rows.add(boxes.into_iter().chain(scores));
        self.write_rows(full)
    }

    /// Writes each entity's rows as one chunk.
    fn write_rows(&self, batches: Vec<rows::Batch>) -> Result<(), ViewError> {
        for (entity, rows) in batches {
            let chunk = rows::chunk(&entity, rows).map_err(|e| self.entity_error(&entity, e))?;
            self.write_chunk(&chunk, Lz4::WhereWorth)
                .map_err(|e| self.entity_error(&entity, e))?;
        }
        Ok(())
    }

    fn log_camera(
        &self,
        stem: &str,
        name: &str,
        depth_scale: f32,
        camera: &CameraView<'_>,
    ) -> Result<(), ViewError> {
        let size_err = |what: &'static str, got: usize, width: u32, height: u32, per: usize| {
            ViewError::ImageSize {
                stem: stem.into(),
                camera: name.into(),
                what,
                got,
                want: width as usize * height as usize * per,
                width,
                height,
            }
        };
        if let Some(f) = camera.color_file {
            // The file as it is: no decode here, and a fraction of the pixels' bytes to
            // encode and write (docs/notes/2026-12-02-rerun.md, 2026-12-04).
            let media_type = match f.format {
                ImageFileFormat::Png => MediaType::png(),
                ImageFileFormat::Jpeg => MediaType::jpeg(),
            };
            self.log_chunk(
                paths::color_image(name).as_str(),
                &EncodedImage::new(f.bytes.to_vec()).with_media_type(media_type),
                Lz4::WhereWorth,
            )?;
        } else if let Some(c) = camera.color {
            if c.rgb.len() != c.width as usize * c.height as usize * 3 {
                return Err(size_err("colour", c.rgb.len(), c.width, c.height, 3));
            }
            self.log_chunk(
                paths::color_image(name).as_str(),
                &Image::from_rgb24(c.rgb.clone(), [c.width, c.height]),
                Lz4::WhereWorth,
            )?;
        }
        if let Some(d) = camera.depth {
            if d.raw.len() != d.width as usize * d.height as usize {
                return Err(size_err("depth", d.raw.len(), d.width, d.height, 1));
            }
            // Little-endian bytes, written in place (a copy the compiler vectorises; pushing
            // value by value was most of this function's time).
            let mut bytes = vec![0_u8; d.raw.len() * 2];
            for (b, v) in bytes.chunks_exact_mut(2).zip(d.raw) {
                b.copy_from_slice(&v.to_le_bytes());
            }
            // Rerun's `meter`: raw units per metre, the rig's depth_scale. Not compressed
            // (`Lz4::Never`: LZ4 halves it, but slowly).
            self.log_chunk(
                paths::depth_image(name).as_str(),
                &DepthImage::new(
                    bytes,
                    ImageFormat::depth([d.width, d.height], ChannelDatatype::U16),
                )
                .with_meter(depth_scale),
                Lz4::Never,
            )?;
        }
        for (what, entity, labels) in [
            ("labels", paths::parsed_labels(name), camera.parsed),
            (
                "refined labels",
                paths::refined_labels(name),
                camera.refined,
            ),
        ] {
            if let Some(l) = labels {
                if l.labels.len() != l.width as usize * l.height as usize {
                    return Err(size_err(what, l.labels.len(), l.width, l.height, 1));
                }
                self.log_chunk(entity.as_str(), &segmentation(l), Lz4::WhereWorth)?;
            }
        }
        Ok(())
    }

    /// Logs `what` at `entity`, at this thread's time, as a chunk of its own, encoded and
    /// written by this thread (`crate::sink`; LZ4 as `lz4` allows): a frame's images and
    /// clouds, each large enough to be a chunk.
    fn log_chunk(&self, entity: &str, what: &dyn AsComponents, lz4: Lz4) -> Result<(), ViewError> {
        let chunk = Chunk::builder(entity)
            .with_archetype(RowId::new(), self.rec.now(), what)
            .build()
            .map_err(|e| self.entity_error(entity, e))?;
        self.write_chunk(&chunk, lz4)
            .map_err(|e| self.entity_error(entity, e))
    }

    /// An error of the SDK or the file about `entity`.
    fn entity_error(&self, entity: &str, e: impl std::fmt::Display) -> ViewError {
        ViewError::Rerun {
            message: format!("{entity}: {e}"),
            path: self.path.clone(),
        }
    }

    /// Encodes `chunk` in this thread and writes it into the file (`crate::sink`).
    fn write_chunk(&self, chunk: &Chunk, lz4: Lz4) -> Result<(), String> {
        let msg = chunk.to_arrow_msg().map_err(|e| e.to_string())?;
        self.file
            .append_chunk(&self.store_id, &msg, lz4)
            .map_err(|e| e.to_string())
    }
}

impl FrameSink for ViewWriter {
    fn write_frame(&self, frame: &ViewFrame<'_>) -> Result<(), ViewError> {
        self.write(frame)
    }

    fn wants_clusters(&self) -> bool {
        self.clusters
    }
}

/// `OUT.rrd` → `OUT.rrd.partial`.
fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// Our classes with their names and palette, and unknown (255).
fn annotation_context() -> AnnotationContext {
    let mut classes: Vec<ClassDescription> = Class::ALL
        .iter()
        .map(|c| {
            let [r, g, b] = c.color();
            AnnotationInfo::from((u16::from(c.id()), c.name(), Rgba32::from_rgb(r, g, b))).into()
        })
        .collect();
    let [r, g, b] = UNKNOWN_RGB;
    classes.push(
        AnnotationInfo::from((
            u16::from(Label::UNKNOWN_ID),
            "unknown",
            Rgba32::from_rgb(r, g, b),
        ))
        .into(),
    );
    AnnotationContext::new(classes)
}

/// A pose as a Rerun transform (child to parent: `a_from_b` logged at b's entity).
fn transform(pose: &Pose) -> Transform3D {
    let [w, x, y, z] = pose.quaternion_wxyz();
    let [tx, ty, tz] = pose.translation_m();
    Transform3D::from_translation_rotation(
        [tx as f32, ty as f32, tz as f32],
        Quaternion::from_xyzw([x as f32, y as f32, z as f32, w as f32]),
    )
}

/// A sensor's pinhole (its distortion is not modelled by Rerun).
fn pinhole(k: &Intrinsics) -> Pinhole {
    Pinhole::from_focal_length_and_resolution(
        [k.fx as f32, k.fy as f32],
        [k.width as f32, k.height as f32],
    )
    .with_principal_point([k.cx as f32, k.cy as f32])
}

/// The batches of a frame's clouds ([`order::cloud_batches`]): the projected and the
/// refined cloud gathered together when they share their points (the same slice), else
/// each on its own; the clusters (of the refined cloud, else the projected) with them.
fn frame_cloud_batches(
    projected: Option<CloudView<'_>>,
    refined: Option<CloudView<'_>>,
    clusters: Option<&[Option<(u32, u32)>]>,
) -> Vec<CloudBatch> {
    let shared = match (projected, refined) {
        (Some(p), Some(r)) => std::ptr::eq(p.positions_m, r.positions_m),
        _ => true,
    };
    if shared {
        let Some(cloud) = refined.or(projected) else {
            return Vec::new();
        };
        return order::cloud_batches(
            Layers {
                positions_m: cloud.positions_m,
                projected: projected.map(|c| c.labels),
                refined: refined.map(|c| c.labels),
                clusters,
            },
            cluster_color,
        );
    }
    let mut batches = Vec::new();
    for (cloud, is_refined) in [(projected, false), (refined, true)] {
        let Some(cloud) = cloud else { continue };
        batches.extend(order::cloud_batches(
            Layers {
                positions_m: cloud.positions_m,
                projected: (!is_refined).then_some(cloud.labels),
                refined: is_refined.then_some(cloud.labels),
                clusters: clusters.filter(|_| is_refined),
            },
            cluster_color,
        ));
    }
    batches
}

/// A `Points3D` of these positions (a `Position3D` batch) painted so, as ready-made Arrow
/// arrays, in one or two rows of the same entity and time: the positions (with the radius),
/// then the class ids or colours of each point, each written as a chunk of its own
/// (`ViewWriter::log_chunk`). Float positions are written as they are (LZ4 leaves them as
/// they are) and only the class ids go through LZ4; in one chunk LZ4 ran over both
/// (docs/notes/2026-12-02-rerun.md, 2026-12-04, session 43). Through `Position3D` / `ClassId` values the SDK rebuilds each array by growing a `Vec`
/// point by point: ~16 ms of user CPU per 3-camera frame of ~350k points, and the fresh
/// pages of its reallocations showed as system time (same notes, 2026-12-03).
fn points_rows(positions: ArrayRef, paint: Paint) -> Vec<Points3D> {
    let mut p = Points3D::update_fields();
    p.positions = Some(SerializedComponentBatch::new(
        positions,
        Points3D::descriptor_positions(),
    ));
    let p = p.with_radii([POINT_RADIUS_M]);
    match paint {
        Paint::Classes(ids) => {
            let mut c = Points3D::update_fields();
            c.class_ids = Some(SerializedComponentBatch::new(
                ids,
                Points3D::descriptor_class_ids(),
            ));
            vec![p, c]
        }
        Paint::Unknown => vec![p.with_class_ids([u16::from(Label::UNKNOWN_ID)])],
        Paint::Colors(colors) => vec![p, Points3D::update_fields().with_colors(colors)],
    }
}

fn segmentation(l: &LabelImage) -> SegmentationImage {
    let ids: Vec<u8> = l.labels.iter().map(|l| l.id()).collect();
    SegmentationImage::new(
        ids,
        ImageFormat::segmentation([l.width, l.height], ChannelDatatype::U8),
    )
}

fn boxes_3d(boxes: &[PersonBox]) -> Boxes3D {
    Boxes3D::from_centers_and_half_sizes(
        boxes.iter().map(|b| b.center_m),
        boxes.iter().map(|b| b.half_extents_m),
    )
    .with_rotation_axis_angles(
        boxes
            .iter()
            .map(|b| RotationAxisAngle::new([0.0, 0.0, 1.0], Angle::from_radians(b.yaw_rad))),
    )
    .with_labels(boxes.iter().map(|b| format!("person {}", b.id)))
}

/// A cluster's colour: a fixed hash of `(person, cluster)` to a bright hue; noise grey.
fn cluster_color(c: Option<(u32, u32)>) -> Rgba32 {
    let Some((person, cluster)) = c else {
        return Rgba32::from_rgb(90, 90, 90);
    };
    let h = (person.wrapping_mul(0x9E37_79B9) ^ cluster.wrapping_mul(0x85EB_CA6B))
        .wrapping_mul(0xC2B2_AE35);
    let [r, g, b, _] = h.to_le_bytes();
    // Lifted so that no cluster is near black (the background class's colour).
    let lift = |v: u8| 64 + v / 4 * 3;
    Rgba32::from_rgb(lift(r), lift(g), lift(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_sdk::external::arrow::array::{Array, AsArray};
    use re_sdk::external::arrow::datatypes::Float32Type;

    fn allocation(b: &CloudBatch) -> *const u8 {
        let list = b.positions.as_fixed_size_list();
        let values = list.values().as_primitive::<Float32Type>().values();
        values.inner().data_ptr().as_ptr()
    }

    #[test]
    fn layers_of_one_slice_share_one_positions_array_others_do_not() {
        let xyz: Vec<[f32; 3]> = (0..4).map(|i| [i as f32, 0.0, 0.0]).collect();
        let copy = xyz.clone();
        let p = [
            Label::BACKGROUND,
            Label::UNKNOWN,
            Label::BACKGROUND,
            Label::UNKNOWN,
        ];
        let r = [
            Label::BACKGROUND,
            Label::UNKNOWN,
            Label::UNKNOWN,
            Label::UNKNOWN,
        ];
        let clusters = [None; 4];
        let view = |positions_m, labels| CloudView {
            positions_m,
            labels,
        };
        // The same slice (C empty): every entity, the clusters too, in one allocation.
        let batches =
            frame_cloud_batches(Some(view(&xyz, &p)), Some(view(&xyz, &r)), Some(&clusters));
        assert_eq!(batches.len(), 5);
        assert!(
            batches
                .iter()
                .all(|b| allocation(b) == allocation(&batches[0]))
        );
        // Equal values in another slice: one array per layer, the clusters the refined's.
        let batches =
            frame_cloud_batches(Some(view(&xyz, &p)), Some(view(&copy, &r)), Some(&clusters));
        let entities: Vec<&str> = batches.iter().map(|b| b.entity).collect();
        assert_eq!(
            entities,
            [
                paths::PROJECTED,
                paths::PROJECTED_UNKNOWN,
                paths::REFINED,
                paths::REFINED_UNKNOWN,
                paths::CLUSTERS
            ]
        );
        assert_eq!(allocation(&batches[0]), allocation(&batches[1]));
        assert_ne!(allocation(&batches[0]), allocation(&batches[2]));
        assert!(
            batches[2..]
                .iter()
                .all(|b| allocation(b) == allocation(&batches[2]))
        );
        assert_eq!(batches[0].positions.len(), 2);
        assert_eq!(batches[3].positions.len(), 3);
        assert!(frame_cloud_batches(None, None, None).is_empty());
    }
}
