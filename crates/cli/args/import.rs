//! `bodyseg import ros2` and `bodyseg import cloud`.

use anyhow::Result;
use bodyseg_pipeline::{ImportCloudOptions, Ros2ImportOptions};
use clap::{Args, Subcommand};
use std::path::PathBuf;

use super::floor::FloorArgs;

/// `bodyseg import ...`.
#[derive(Debug, Subcommand)]
pub enum ImportCommand {
    /// A ROS 2 bag (MCAP; iai_kinect2 or other RGB-D topics, CameraInfo, /tf_static) into
    /// a recording: rig.toml, depth and colour images per camera
    #[command(long_about = IMPORT_ROS2_LONG_ABOUT, after_help = IMPORT_ROS2_EXAMPLES)]
    Ros2(ImportRos2Args),
    /// Organised point clouds of one depth camera (PCD, organised PLY) → a one-camera
    /// recording: depth and colour images, intrinsics fitted from the grid, world frame
    /// from the floor
    #[command(long_about = IMPORT_CLOUD_LONG_ABOUT, after_help = IMPORT_CLOUD_EXAMPLES)]
    Cloud(ImportCloudArgs),
}

const IMPORT_ROS2_LONG_ABOUT: &str = "\
Import a ROS 2 bag into a recording (shared/FORMATS.md) that every other command reads. \
BAG is an .mcap file or a rosbag2 folder (metadata.yaml and its MCAP files); SQLite (.db3) \
bags are refused with the `ros2 bag convert` command that turns them into MCAP.

Read: sensor_msgs/Image (depth 16UC1/mono16 in mm, 32FC1 in metres; colour rgb8, bgr8, \
bgra8, rgba8, mono8), sensor_msgs/CompressedImage (JPEG or PNG colour, written as it is for \
JPEG; compressedDepth PNG depth), sensor_msgs/CameraInfo (plumb_bob, rational_polynomial), \
tf2_msgs/TFMessage on /tf_static and /tf.

Cameras: iai_kinect2's /<name>/{sd,qhd,hd}/{image_depth,image_depth_rect,image_color,\
image_color_rect} topics are found by name: per camera the raw sd depth (IR frame) and the \
raw qhd (else hd) colour first, else a registered qhd/hd depth with the colour of its \
resolution (one frame, colour_from_depth the identity). Other layouts: --camera \
NAME=TOPIC_PREFIX (repeatable, in rig order) takes the depth and colour image topics under \
the prefix. Intrinsics as ROS means them: a raw image uses CameraInfo's k and d, a *_rect \
image its p and no distortion. color_from_depth is the tf from the depth image's frame to \
the colour image's; world_from_depth the tf from the depth frame to --world-frame (default: \
the root of the tf tree; bodyseg's world is z up, a warning says when the root is an \
optical frame).

Frames: per camera, depth and colour images paired by nearest stamp within --max-skew-ms, \
the cameras' pairs grouped by stamp within the same skew; frames are named 000000, 000001, \
... in stamp order, OUT/stamps.csv maps them to the stamps, OUT/import_ros2/import.json \
says what was imported; unpaired images are counted in a note. Depth is written as 16-bit \
millimetre PNG (32FC1 rounded, NaN → 0), colour as PNG (JPEG as it is).

The bag is read twice, streamed (memory does not grow with its length): every error (a \
truncated bag, an unknown encoding, a camera without CameraInfo, no transform between depth \
and colour) is found in the first pass and reported as one line naming the topic or field \
and the stamp, before anything is written. Resumable like `run`: a frame complete in OUT \
is skipped (--force writes it again). Exit status: 0, 3 when some frames failed to decode \
(listed; the others written), 1 on an error.";

const IMPORT_ROS2_EXAMPLES: &str = "\
Examples:
  bodyseg import ros2 session.mcap --out rec
  bodyseg import ros2 rosbag2_2026_12_01-10_00_00/ --out rec --world-frame map
  bodyseg import ros2 bag/ --out rec --camera left=/kinect2_left --camera right=/kinect2_right
  bodyseg import ros2 bag/ --out rec --camera front=/camera --max-skew-ms 10
  bodyseg run --recording rec --out run1";

/// `bodyseg import ros2`.
#[derive(Debug, Args)]
pub struct ImportRos2Args {
    /// The bag: an .mcap file, or a rosbag2 folder (metadata.yaml and MCAP files)
    #[arg(value_name = "BAG")]
    pub bag: PathBuf,

    /// The recording to write (created; frames complete in it are skipped)
    #[arg(long, value_name = "REC")]
    pub out: PathBuf,

    /// A camera and the topic prefix of its images, e.g. left=/kinect2_left (repeatable,
    /// rig order) [default: found by topic layout, sorted by name]
    #[arg(long = "camera", value_name = "NAME=TOPIC_PREFIX", value_parser = parse_camera)]
    pub cameras: Vec<(String, String)>,

    /// The tf frame that becomes the world (z up) [default: the root of the tf tree]
    #[arg(long, value_name = "FRAME")]
    pub world_frame: Option<String>,

    /// Largest stamp difference between a camera's depth and colour images, and between
    /// the cameras of a frame, milliseconds
    #[arg(long, value_name = "MS", default_value_t = 20.0)]
    pub max_skew_ms: f64,

    /// Write frames already complete in REC again
    #[arg(long)]
    pub force: bool,
}

/// `NAME=TOPIC_PREFIX`.
fn parse_camera(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((name, prefix)) if !name.is_empty() && !prefix.is_empty() => {
            Ok((name.to_string(), prefix.to_string()))
        }
        _ => Err(format!(
            "expected NAME=TOPIC_PREFIX (e.g. left=/kinect2_left), got {s:?}"
        )),
    }
}

impl ImportRos2Args {
    /// The pipeline's options.
    pub fn options(&self) -> Ros2ImportOptions {
        Ros2ImportOptions {
            bag: self.bag.clone(),
            out: self.out.clone(),
            cameras: self.cameras.clone(),
            world_frame: self.world_frame.clone(),
            max_skew_ms: self.max_skew_ms,
            redo: self.force,
        }
    }
}

const IMPORT_CLOUD_LONG_ABOUT: &str = "\
Turn organised point clouds of one depth camera into a bodyseg recording (shared/FORMATS.md) \
that `bodyseg run` reads: one frame per cloud, in the order given (a folder: its .pcd and \
.ply files sorted by name), named 000000, 000001, ...

Reads: organised clouds in the camera's own frame (x right, y down, z forward, metres), as \
PCL's grabbers and ROS's depth_image_proc write them: a PCD with WIDTH x HEIGHT (HEIGHT > 1) \
and fields x y z [rgb|rgba], or a PLY with obj_info num_cols / num_rows (and PCL's \
range_grid). NaN points are cells without depth. All clouds come from one static camera \
and have the same grid.

Writes into OUT: cam0/depth/<frame>.png (z in millimetres, 16-bit, 0 = no point), \
cam0/color/<frame>.png (the points' colours; grey without colours) and rig.toml: one \
camera whose depth and colour sensor are the cloud's grid (color_from_depth identity, no \
distortion), with fx, fy, cx, cy fitted by least squares of u = fx*x/z + cx, \
v = fy*y/z + cy over every valid point (the RMS residual is printed; a cloud that is no \
pinhole grid, e.g. one moved into another frame, is refused), and world_from_depth from \
the floor: the largest plane that the points stand on, found as `bodyseg boxes` finds it \
(or --ground, --up), at z = 0 with z up. Nothing is written when an input is refused; an \
existing OUT is only replaced with --force.

Then: `bodyseg run --recording OUT --out RUN --set boxes.mode=geometry` finds every \
person without labels (a parser labels the body parts for the refinement).";

const IMPORT_CLOUD_EXAMPLES: &str = "\
Examples:
  bodyseg import cloud five_people.pcd --out rec
  bodyseg import cloud grabber_frames/ --out rec --up -y
  bodyseg run --recording rec --out run1 --set boxes.mode=geometry";

/// `bodyseg import cloud`.
#[derive(Debug, Args)]
pub struct ImportCloudArgs {
    /// Organised clouds (.pcd, .ply), or folders of them, in frame order
    #[arg(required = true, value_name = "CLOUD")]
    pub inputs: Vec<PathBuf>,

    /// The recording folder to write
    #[arg(long, value_name = "REC")]
    pub out: PathBuf,

    #[command(flatten)]
    pub floor: FloorArgs,

    /// Replace OUT if it exists
    #[arg(long)]
    pub force: bool,
}

impl ImportCloudArgs {
    /// The pipeline's options for `import_cloud`.
    pub fn options(&self) -> ImportCloudOptions {
        ImportCloudOptions {
            inputs: self.inputs.clone(),
            out: self.out.clone(),
            floor: self.floor.hint(),
            force: self.force,
        }
    }
}
