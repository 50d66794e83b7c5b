//! bodyseg-ros2: ROS 2 bags (rosbag2 with MCAP storage) read into bodyseg's rig and frames.
//!
//! Place in the pipeline: before it. `bodyseg import ros2` (bodyseg-pipeline's
//! `import_ros2`) turns a bag of a multi-camera RGB-D session (iai_kinect2 or OpenPTrack
//! topics) into a recording (FORMATS.md), which every other command reads.
//!
//! ```text
//! bag messages (BagReader, streamed) → BagScan::observe (headers, CameraInfo, tf)
//!   → BagScan::plan → ImportPlan (Rig, frames: which messages, paired by stamp)
//! bag messages again → decode_depth / decode_colour → depth mm (u16) / RGB or JPEG
//! ```
//!
//! Two passes over the bag, both streamed: the first keeps a few numbers per image
//! message and finds every error before anything is written; the second decodes only the
//! messages the plan chose. Memory holds an MCAP chunk and the frames being assembled,
//! whatever the bag's length. Nothing here opens a file: the caller hands over readers.
//!
//! Messages are decoded from CDR by hand ([`cdr`]); the message definitions read are in
//! [`msg`]. The iai_kinect2 topic layout and the choice of streams are in [`topics`].
//!
//! # Conventions
//! - ROS optical frames are OpenCV's (x right, y down, z forward), bodyseg's camera frames.
//! - A tf transform with parent P and child C is `P_from_C` (`p_P = R · p_C + t`),
//!   metres; `color_from_depth` is the transform from the depth image's `frame_id` to the
//!   colour image's, `world_from_depth` from the depth image's frame to the world frame
//!   (`--world-frame`, default the root of the tf tree; ROS' `map`/`world`/`base_link` are
//!   z up, as bodyseg's world).
//! - Intrinsics (ROS semantics): a raw image uses CameraInfo's `k` and `d`, a rectified
//!   (`*_rect`) image its `p` and no distortion ([`intrinsics_of`]).
//! - Depth is written in millimetres (`u16`, 0 = no measurement): `16UC1`/`mono16` are
//!   millimetres already, `32FC1` metres are rounded to millimetres (NaN → 0).
//! - Stamps are `header.stamp` ([`Stamp`]); the log time only where a header cannot be read.

pub mod bag;
pub mod cdr;
mod decode;
mod error;
mod intrinsics;
pub mod msg;
mod pairing;
pub mod pixels;
mod scan;
mod tf;
pub mod topics;

pub use bag::{BagMessage, BagMetadata, BagReader, parse_metadata, sqlite_error};
pub use decode::{decode_color, decode_depth};
pub use error::Ros2Error;
pub use intrinsics::intrinsics_of;
pub use msg::{MsgKind, Stamp};
pub use pairing::{group_cameras, pair_nearest};
pub use pixels::Color;
pub use scan::{
    BagScan, CameraSource, ImportOptions, ImportPlan, MessageRef, PlannedFrame, PlannedView,
    Stream, TF, TF_STATIC, Unpaired,
};
pub use tf::{TfSource, TfTree};
