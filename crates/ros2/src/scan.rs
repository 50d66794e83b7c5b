//! The first pass over a bag: every message's header (not its pixels), every CameraInfo
//! and transform, kept as a few numbers per image message; then the plan: the cameras,
//! the rig, and which messages make up which frame.
//!
//! Errors are found here, before anything is written: an unknown encoding, an image whose
//! size changes, a camera without CameraInfo, a transform missing between depth and
//! colour. Each names the topic (or field) and the stamp.

use crate::intrinsics::intrinsics_of;
use crate::msg::{
    CameraInfoMsg, MsgKind, Stamp, decode_camera_info, decode_compressed_image, decode_image,
    decode_tf_message,
};
use crate::pairing::{group_cameras, pair_nearest};
use crate::pixels::{
    COLOR_ENCODINGS, DEPTH_ENCODINGS, ImageRole, check_image, compressed_image_size,
    compressed_role, image_role,
};
use crate::tf::{TfSource, TfTree};
use crate::topics::{CameraTopics, ImageTopic, StreamName, find_cameras};
use crate::{BagMessage, Ros2Error};
use bodyseg_calib::{Intrinsics, RgbdCamera, Rig};
use std::collections::BTreeMap;

/// The topic of static transforms.
pub const TF_STATIC: &str = "/tf_static";
/// The topic of transforms that may change.
pub const TF: &str = "/tf";

/// What the user chose.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// `(camera name, topic prefix)`, in rig order; empty = find the cameras by layout.
    pub cameras: Vec<(String, String)>,
    /// The tf frame that becomes bodyseg's world; `None` = the root of the cameras' tree.
    pub world_frame: Option<String>,
    /// Largest stamp difference between a camera's depth and colour image, and between
    /// the cameras of one frame, nanoseconds.
    pub max_skew_ns: i64,
}

/// The first message of an image topic.
#[derive(Clone, Debug)]
struct First {
    stamp: Stamp,
    frame_id: String,
    /// `encoding` of an Image, `format` of a CompressedImage.
    coding: String,
    size: (u32, u32),
}

/// What the scan keeps of one image topic.
#[derive(Debug)]
struct TopicScan {
    kind: MsgKind,
    first: Option<First>,
    /// `(stamp ns, ordinal)` of every message, in bag order.
    messages: Vec<(i64, u64)>,
    /// The first problem seen (the error names the topic and stamp); reported only if
    /// the topic is used.
    problem: Option<Ros2Error>,
}

/// The first pass's state: feed it every message with [`BagScan::observe`], then call
/// [`BagScan::plan`].
#[derive(Debug, Default)]
pub struct BagScan {
    topics: BTreeMap<String, TopicScan>,
    infos: BTreeMap<String, Result<CameraInfoMsg, Ros2Error>>,
    tf: TfTree,
    /// Messages seen.
    pub messages: u64,
}

impl BagScan {
    /// Takes in one message.
    ///
    /// # Errors
    /// A `/tf_static` or `/tf` message that does not decode or holds an invalid rotation
    /// (naming the topic and stamp). Problems of image and CameraInfo messages are kept
    /// and reported by [`BagScan::plan`] if the topic is used.
    pub fn observe(&mut self, m: &BagMessage) -> Result<(), Ros2Error> {
        self.messages += 1;
        let Some(kind) = m.kind else {
            return Ok(());
        };
        let log_stamp = Stamp::from_ns(m.log_time_ns as i64);
        match kind {
            MsgKind::Tf => {
                let source = match &*m.topic {
                    TF_STATIC => TfSource::Static,
                    TF => TfSource::Dynamic,
                    _ => return Ok(()),
                };
                let transforms =
                    decode_tf_message(&m.data).map_err(|e| e.at(&m.topic, log_stamp))?;
                self.tf.add(&transforms, &m.topic, source)?;
            }
            MsgKind::CameraInfo => {
                if !self.infos.contains_key(&*m.topic) {
                    let info = decode_camera_info(&m.data).map_err(|e| e.at(&m.topic, log_stamp));
                    self.infos.insert(m.topic.to_string(), info);
                }
            }
            MsgKind::Image | MsgKind::CompressedImage => self.observe_image(m, kind, log_stamp),
        }
        Ok(())
    }

    fn observe_image(&mut self, m: &BagMessage, kind: MsgKind, log_stamp: Stamp) {
        let scan = self
            .topics
            .entry(m.topic.to_string())
            .or_insert_with(|| TopicScan {
                kind,
                first: None,
                messages: Vec::new(),
                problem: None,
            });
        let seen = match kind {
            MsgKind::Image => decode_image(&m.data).and_then(|img| {
                // The role by encoding; an unknown encoding is reported when the topic is
                // used (an IR stream beside the depth is no error).
                if let Some(role) = image_role(&img.encoding) {
                    check_image(&img, role).map_err(|e| e.at(&m.topic, img.header.stamp))?;
                }
                Ok((img.header, img.encoding, (img.width, img.height)))
            }),
            _ => decode_compressed_image(&m.data).and_then(|img| {
                let size = compressed_image_size(&img, compressed_role(&img.format))
                    .map_err(|e| e.at(&m.topic, img.header.stamp))?;
                Ok((img.header, img.format, size))
            }),
        };
        let (header, coding, size) = match seen {
            Ok(s) => s,
            Err(e) => {
                let e = match e {
                    e @ Ros2Error::AtMessage { .. } => e,
                    e => e.at(&m.topic, log_stamp),
                };
                scan.problem.get_or_insert(e);
                return;
            }
        };
        let stamp = header.stamp;
        match &scan.first {
            None => {
                scan.first = Some(First {
                    stamp,
                    frame_id: header.frame_id,
                    coding,
                    size,
                });
            }
            Some(first) if scan.problem.is_none() => {
                let field = if kind == MsgKind::Image {
                    "encoding"
                } else {
                    "format"
                };
                if first.coding != coding {
                    scan.problem = Some(
                        Ros2Error::invalid(format!(
                            "field {field}: {coding:?}, the topic's first image has {:?}",
                            first.coding
                        ))
                        .at(&m.topic, stamp),
                    );
                } else if first.size != size {
                    scan.problem = Some(
                        Ros2Error::invalid(format!(
                            "image is {}x{}, the topic's first image is {}x{}",
                            size.0, size.1, first.size.0, first.size.1
                        ))
                        .at(&m.topic, stamp),
                    );
                }
            }
            Some(_) => {}
        }
        scan.messages.push((stamp.ns(), m.ordinal));
    }

    /// The image topics seen, with the role their first message suggests.
    fn image_topics(&self) -> Vec<ImageTopic> {
        self.topics
            .iter()
            .map(|(topic, scan)| ImageTopic {
                name: StreamName::parse(topic),
                role_by_content: scan.first.as_ref().and_then(|f| match scan.kind {
                    MsgKind::Image => image_role(&f.coding),
                    _ => Some(compressed_role(&f.coding)),
                }),
            })
            .collect()
    }

    /// The plan: cameras, rig and frames.
    ///
    /// # Errors
    /// See the module documentation; every error names the topic or field and the stamp.
    pub fn plan(&self, options: &ImportOptions) -> Result<ImportPlan, Ros2Error> {
        let cameras = find_cameras(&self.image_topics(), &options.cameras)?;
        let mut notes: Vec<String> = cameras.iter().flat_map(|c| c.notes.clone()).collect();
        let mut sources = Vec::new();
        for cam in &cameras {
            sources.push(self.camera_source(cam)?);
        }
        let world = self.world_frame(&sources, options, &mut notes)?;
        let mut rig_cameras = Vec::new();
        for s in &sources {
            rig_cameras.push(self.rig_camera(s, &world, &mut notes)?);
        }
        let rig = Rig {
            cameras: rig_cameras,
        };
        rig.validate().map_err(|e| Ros2Error::Camera {
            reason: format!("the rig assembled from the bag is invalid: {e}"),
        })?;
        let (frames, unpaired) = self.frames(&sources, options.max_skew_ns);
        Ok(ImportPlan {
            rig,
            world_frame: world,
            sources,
            frames,
            unpaired,
            notes,
        })
    }

    /// The scanned topic of a camera's stream, checked.
    fn stream(
        &self,
        camera: &str,
        name: &StreamName,
        role: ImageRole,
    ) -> Result<Stream, Ros2Error> {
        let scan = self
            .topics
            .get(&name.topic)
            .ok_or_else(|| Ros2Error::Camera {
                reason: format!("camera {camera}: topic {} has no message", name.topic),
            })?;
        if let Some(problem) = &scan.problem {
            return Err(clone_error(problem));
        }
        let first = scan.first.as_ref().ok_or_else(|| Ros2Error::Camera {
            reason: format!("camera {camera}: topic {} has no image", name.topic),
        })?;
        let content_role = match scan.kind {
            MsgKind::Image => image_role(&first.coding),
            _ => Some(compressed_role(&first.coding)),
        };
        if content_role != Some(role) {
            let (field, supported) = match (scan.kind, role) {
                (MsgKind::Image, ImageRole::Depth) => ("encoding", DEPTH_ENCODINGS.to_string()),
                (MsgKind::Image, ImageRole::Color) => ("encoding", COLOR_ENCODINGS.to_string()),
                (_, ImageRole::Depth) => ("format", "compressedDepth png".to_string()),
                (_, ImageRole::Color) => ("format", "JPEG or PNG".to_string()),
            };
            let what = if role == ImageRole::Depth {
                "depth"
            } else {
                "colour"
            };
            return Err(Ros2Error::Unsupported {
                field: field.into(),
                value: first.coding.clone(),
                supported: format!("camera {camera}'s {what} images: {supported}"),
            }
            .at(&name.topic, first.stamp));
        }
        let info_topic = name.info_topic();
        let info = match self.infos.get(&info_topic) {
            Some(Ok(info)) => info,
            Some(Err(e)) => return Err(clone_error(e)),
            None => {
                return Err(Ros2Error::Camera {
                    reason: format!(
                        "camera {camera}: no CameraInfo on {info_topic} for its images on {} \
                         (first at stamp {}): bodyseg needs the intrinsics",
                        name.topic, first.stamp
                    ),
                });
            }
        };
        let intrinsics = intrinsics_of(info, name.is_rect())
            .map_err(|e| e.at(&info_topic, info.header.stamp))?;
        if (intrinsics.width, intrinsics.height) != first.size {
            return Err(Ros2Error::invalid(format!(
                "fields width, height: CameraInfo is for {}x{} images, {} has {}x{} (first at \
                 stamp {})",
                intrinsics.width,
                intrinsics.height,
                name.topic,
                first.size.0,
                first.size.1,
                first.stamp
            ))
            .at(&info_topic, info.header.stamp));
        }
        let mut messages = scan.messages.clone();
        messages.sort_unstable();
        // Two messages of one stamp on one topic: the first recorded is kept.
        messages.dedup_by_key(|m| m.0);
        Ok(Stream {
            topic: name.topic.clone(),
            info_topic,
            kind: scan.kind,
            rect: name.is_rect(),
            frame_id: first.frame_id.clone(),
            first_stamp: first.stamp,
            coding: first.coding.clone(),
            intrinsics,
            messages,
        })
    }

    fn camera_source(&self, cam: &CameraTopics) -> Result<CameraSource, Ros2Error> {
        Ok(CameraSource {
            name: cam.name.clone(),
            depth: self.stream(&cam.name, &cam.depth, ImageRole::Depth)?,
            color: self.stream(&cam.name, &cam.color, ImageRole::Color)?,
        })
    }

    /// The world frame: the option, else the root of the first camera's depth frame.
    fn world_frame(
        &self,
        sources: &[CameraSource],
        options: &ImportOptions,
        notes: &mut Vec<String>,
    ) -> Result<String, Ros2Error> {
        let world = match &options.world_frame {
            Some(w) => w.clone(),
            None => {
                let first = sources.first().ok_or_else(|| Ros2Error::Camera {
                    reason: "no camera".into(),
                })?;
                self.tf.root(&first.depth.frame_id)
            }
        };
        if world.contains("optical") {
            notes.push(format!(
                "warning: the world frame {world:?} is an optical frame (x right, y down, z \
                 forward), not z up as bodyseg's world: person boxes and floor steps assume z \
                 up; name a z-up frame (map, world, base_link) with --world-frame"
            ));
        }
        Ok(world)
    }

    fn rig_camera(
        &self,
        s: &CameraSource,
        world: &str,
        notes: &mut Vec<String>,
    ) -> Result<RgbdCamera, Ros2Error> {
        let (depth, color) = (&s.depth, &s.color);
        let missing = |target: &str, target_topic: &str| Ros2Error::Transform {
            reason: format!(
                "camera {}: no transform from the depth frame {:?} ({}, stamp {}) to {:?} ({}) \
                 in {TF_STATIC} or {TF}{}",
                s.name,
                depth.frame_id,
                depth.topic,
                depth.first_stamp,
                target,
                target_topic,
                if self.tf.is_empty() {
                    ": the bag has no transforms"
                } else {
                    ""
                }
            ),
        };
        let (color_from_depth, dyn_c) = self
            .tf
            .lookup(&color.frame_id, &depth.frame_id)
            .ok_or_else(|| missing(&color.frame_id, &color.topic))?;
        let (world_from_depth, dyn_w) = self
            .tf
            .lookup(world, &depth.frame_id)
            .ok_or_else(|| missing(world, "the world frame"))?;
        if dyn_c || dyn_w {
            notes.push(format!(
                "camera {}: a transform came from {TF} (its first value is used; a rig is static)",
                s.name
            ));
        }
        let mut camera = RgbdCamera::new(&s.name, depth.intrinsics, color.intrinsics);
        camera.color_from_depth = color_from_depth;
        camera.world_from_depth = world_from_depth;
        Ok(camera)
    }

    /// Pairs and groups the cameras' messages into frames.
    fn frames(
        &self,
        sources: &[CameraSource],
        max_skew_ns: i64,
    ) -> (Vec<PlannedFrame>, Vec<Unpaired>) {
        let mut pairs_per_camera = Vec::new();
        let mut unpaired = Vec::new();
        for s in sources {
            let d: Vec<i64> = s.depth.messages.iter().map(|m| m.0).collect();
            let c: Vec<i64> = s.color.messages.iter().map(|m| m.0).collect();
            let pairs = pair_nearest(&d, &c, max_skew_ns);
            unpaired.push(Unpaired {
                camera: s.name.clone(),
                depth: d.len() - pairs.len(),
                color: c.len() - pairs.len(),
                pairs: 0,
            });
            pairs_per_camera.push(pairs);
        }
        let stamps: Vec<Vec<i64>> = sources
            .iter()
            .zip(&pairs_per_camera)
            .map(|(s, pairs)| pairs.iter().map(|&(i, _)| s.depth.messages[i].0).collect())
            .collect();
        let groups = group_cameras(&stamps, max_skew_ns);
        for (u, pairs) in unpaired.iter_mut().zip(&pairs_per_camera) {
            u.pairs = pairs.len() - groups.len();
        }
        let frames = groups
            .iter()
            .map(|group| {
                let views = group
                    .iter()
                    .zip(sources.iter().zip(&pairs_per_camera))
                    .map(|(&k, (s, pairs))| {
                        let (i, j) = pairs[k];
                        PlannedView {
                            depth: MessageRef::of(&s.depth, i),
                            color: MessageRef::of(&s.color, j),
                        }
                    })
                    .collect::<Vec<_>>();
                PlannedFrame {
                    stamp: views[0].depth.stamp,
                    views,
                }
            })
            .collect();
        (frames, unpaired)
    }
}

/// A copy of an error kept by the scan (errors are not `Clone`: the text is kept).
fn clone_error(e: &Ros2Error) -> Ros2Error {
    match e {
        Ros2Error::AtMessage {
            topic,
            stamp,
            source,
        } => Ros2Error::AtMessage {
            topic: topic.clone(),
            stamp: stamp.clone(),
            source: Box::new(clone_error(source)),
        },
        other => Ros2Error::invalid(other.to_string()),
    }
}

/// One image stream of a camera, as scanned.
#[derive(Clone, Debug, PartialEq)]
pub struct Stream {
    /// The topic.
    pub topic: String,
    /// Its CameraInfo topic.
    pub info_topic: String,
    /// `Image` or `CompressedImage`.
    pub kind: MsgKind,
    /// Whether the images are rectified (intrinsics from `p`, no distortion).
    pub rect: bool,
    /// The optical frame of its images (`header.frame_id`).
    pub frame_id: String,
    /// The first image's stamp.
    pub first_stamp: Stamp,
    /// Encoding (Image) or format (CompressedImage).
    pub coding: String,
    /// The sensor's intrinsics (for these images).
    pub intrinsics: Intrinsics,
    /// `(stamp ns, ordinal)`, sorted by stamp, one per stamp.
    pub messages: Vec<(i64, u64)>,
}

/// Where a camera's images come from.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSource {
    /// The camera's name.
    pub name: String,
    /// Its depth stream.
    pub depth: Stream,
    /// Its colour stream.
    pub color: Stream,
}

impl CameraSource {
    /// One line saying what was imported for the camera.
    pub fn describe(&self) -> String {
        let line = |s: &Stream| {
            format!(
                "{} ({}, {}x{}, {}, {})",
                s.topic,
                s.coding,
                s.intrinsics.width,
                s.intrinsics.height,
                s.frame_id,
                if s.rect {
                    "rectified: CameraInfo p"
                } else {
                    "raw: CameraInfo k, d"
                }
            )
        };
        let registered = if self.depth.frame_id == self.color.frame_id {
            "; registered (one frame)"
        } else {
            ""
        };
        format!(
            "camera {}: depth {}, colour {}{registered}",
            self.name,
            line(&self.depth),
            line(&self.color)
        )
    }
}

/// A message of the bag, by position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MessageRef {
    /// Its ordinal ([`BagMessage::ordinal`]).
    pub ordinal: u64,
    /// Its `header.stamp`.
    pub stamp: Stamp,
    /// `Image` or `CompressedImage`.
    pub kind: MsgKind,
}

impl MessageRef {
    fn of(stream: &Stream, index: usize) -> MessageRef {
        let (ns, ordinal) = stream.messages[index];
        MessageRef {
            ordinal,
            stamp: Stamp::from_ns(ns),
            kind: stream.kind,
        }
    }
}

/// One camera's images of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlannedView {
    /// The depth image.
    pub depth: MessageRef,
    /// The colour image.
    pub color: MessageRef,
}

/// One frame: a view per camera, rig order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedFrame {
    /// The first camera's depth stamp.
    pub stamp: Stamp,
    /// Per camera, rig order.
    pub views: Vec<PlannedView>,
}

/// Messages of a camera left out of every frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unpaired {
    /// The camera.
    pub camera: String,
    /// Depth images without a colour image within the skew.
    pub depth: usize,
    /// Colour images without a depth image within the skew.
    pub color: usize,
    /// Depth-colour pairs that no frame took (another camera had none within the skew).
    pub pairs: usize,
}

/// What [`BagScan::plan`] decided.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportPlan {
    /// The cameras: intrinsics from CameraInfo, transforms from tf.
    pub rig: Rig,
    /// The tf frame that is the world.
    pub world_frame: String,
    /// Per camera (rig order), where its images come from.
    pub sources: Vec<CameraSource>,
    /// The frames, in stamp order.
    pub frames: Vec<PlannedFrame>,
    /// Per camera, what no frame took.
    pub unpaired: Vec<Unpaired>,
    /// Choices and warnings, one line each.
    pub notes: Vec<String>,
}
