//! Command-line arguments (clap derive) and their translation into bodyseg-pipeline's
//! option structs. No work happens here.

use anyhow::{Result, bail};
use bodyseg_pipeline::{
    AzureColorResolution, AzureDepthMode, AzureKinectMode, Board, ConvertFormat, ConvertOptions,
    DEFAULT_PREDICTION_NAME, EvalOptions, FigureChoice, FloorHint, ImportCloudOptions,
    IntrinsicsCalibOptions, NamedPrediction, ParseOptions, ParseSource, ParserChoice,
    PipelineConfig, ProjectMode, ProjectOptions, RefineOptions, RefineOverrides, ReportFormat,
    RigFormat, RigImportOptions, RigInput, Ros2ImportOptions, RunOptions, SceneSource,
    StereoCalibOptions, SynthOptions, ThreeDPeopleCamera, WorldCalibOptions,
};
use bodyseg_refine::Steps;
use bodyseg_synth::ChessboardConfig;
use clap::{ArgAction, Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

const ABOUT: &str = "Body-part labelled 3D point clouds from multi-camera RGB-D recordings";

const LONG_ABOUT: &str = "\
bodyseg labels the points of 3D point clouds of people with body parts (head, torso, \
upper arms, lower arms, upper legs, lower legs; everything else is background). Its core is \
the clustering refinement of the paper \"Clustering-based refinement for 3D human body \
parts segmentation\": it repairs the labels that go wrong when 2D \
human-parsing masks are projected onto 3D points.

Files: labelled point clouds are PLY (x y z in metres, world frame, z up; a `label` class id \
per point), person boxes are JSON; see shared/FORMATS.md. Run `bodyseg <COMMAND> --help` for \
each command.";

const MAIN_EXAMPLES: &str = "\
Examples:
  bodyseg synth --preset handover --frames 20 --seed 1 --out rec
  bodyseg parse --recording rec --frame 000012 --out parsed
  bodyseg project --recording rec --frame 000012 --out frame.ply
  bodyseg boxes --cloud frame.ply --out frame_boxes.json
  bodyseg refine --cloud frame.ply --boxes frame_boxes.json --out refined.ply
  bodyseg eval --pred refined.ply --gt truth.ply
  bodyseg rig import --from iai_kinect2 calib/cam0 calib/cam1 --out rig.toml
  bodyseg import ros2 session.mcap --out rec
  bodyseg import cloud kinect.pcd --out rec
  bodyseg run --recording rec --out run1
  bodyseg convert --input datasets/recs --format recording --out converted --shard 0/4
  bodyseg calibrate intrinsics --images calib/cam0/ir --board 9x6 --square-m 0.04 --out cam0_ir.toml
  bodyseg refine --help

Logging: RUST_LOG=debug (default warn); -v is info, -vv debug.";

/// `bodyseg`: the command line.
#[derive(Debug, Parser)]
#[command(
    name = "bodyseg",
    version,
    about = ABOUT,
    long_about = LONG_ABOUT,
    after_help = MAIN_EXAMPLES,
    propagate_version = true
)]
pub struct Cli {
    /// Log more to stderr: -v info, -vv debug, -vvv trace (default: warnings only, or
    /// RUST_LOG when set)
    #[arg(
        short,
        long,
        action = ArgAction::Count,
        global = true,
        help_heading = "Global options"
    )]
    pub verbose: u8,

    /// Do not print the per-stage summary lines (time and counts) to stderr
    #[arg(short, long, global = true, help_heading = "Global options")]
    pub quiet: bool,

    /// The command to run
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a synthetic multi-camera RGB-D recording of people with exact ground truth
    /// and simulated parser predictions
    #[command(long_about = SYNTH_LONG_ABOUT, after_help = SYNTH_EXAMPLES)]
    Synth(SynthArgs),
    /// Label the colour images of one recorded frame with body parts (2D human parsing,
    /// ONNX model) and write label images and previews
    #[command(long_about = PARSE_LONG_ABOUT, after_help = PARSE_EXAMPLES)]
    Parse(ParseArgs),
    /// Label the depth points of one recorded frame with its 2D body-part labels (naive or
    /// DSA-aware projection) and write one world-frame cloud
    #[command(long_about = PROJECT_LONG_ABOUT, after_help = PROJECT_EXAMPLES)]
    Project(ProjectArgs),
    /// Find the person boxes of a point cloud (PLY or PCD) or a recorded frame: one oriented
    /// box per person, from body labels or from geometry alone
    #[command(long_about = BOXES_LONG_ABOUT, after_help = BOXES_EXAMPLES)]
    Boxes(BoxesArgs),
    /// Repair the body-part labels of a point cloud (clustering refinement: M, R, N steps)
    #[command(long_about = REFINE_LONG_ABOUT, after_help = REFINE_EXAMPLES)]
    Refine(RefineArgs),
    /// Score labelled point clouds against ground truth (IoU, BIoU, precision, F1), or merge
    /// reports
    #[command(long_about = EVAL_LONG_ABOUT, after_help = EVAL_EXAMPLES)]
    Eval(EvalArgs),
    /// Camera rigs: import calibration files into a rig.toml, show a rig
    #[command(subcommand)]
    Rig(RigCommand),
    /// Run a whole recording through every stage (parse, project, boxes, refine, evaluate):
    /// refined clouds, boxes, label images, the paper's table and figures
    #[command(long_about = RUN_LONG_ABOUT, after_help = RUN_EXAMPLES)]
    Run(RunArgs),
    /// Convert a dataset in batch into labelled point clouds (resumable, shardable across
    /// machines): bodyseg recordings, or 3DPeople
    #[command(long_about = CONVERT_LONG_ABOUT, after_help = CONVERT_EXAMPLES)]
    Convert(ConvertArgs),
    /// Calibrate cameras from chessboard images (OpenCV): intrinsics, colour-from-depth,
    /// world poses → rig.toml
    #[command(subcommand, long_about = CALIBRATE_LONG_ABOUT)]
    Calibrate(CalibrateCommand),
    /// Print the version; with -v also the ONNX Runtime library and the model that would
    /// be loaded, and the rule that found each
    #[command(long_about = VERSION_LONG_ABOUT)]
    Version(VersionArgs),
    /// Import other tools' data as a bodyseg recording: ROS 2 bags, organised point
    /// clouds
    #[command(subcommand)]
    Import(ImportCommand),
    /// Write a Rerun recording (.rrd) of a finished run from its files: cameras, images,
    /// 2D labels, clouds, person boxes, scores on a frame timeline (feature `rerun`)
    #[command(long_about = VIEW_LONG_ABOUT, after_help = VIEW_EXAMPLES)]
    View(ViewArgs),
}

const VERSION_LONG_ABOUT: &str = "\
Print bodyseg's version. With -v, also the ONNX Runtime library and the parsing model that \
would be loaded (nothing is loaded) and where each was found: parsing.runtime_library / \
parsing.model of the configuration, ORT_DYLIB_PATH, the install prefix (<prefix>/bin/bodyseg \
with <prefix>/lib/bodyseg/libonnxruntime.so and \
<prefix>/share/bodyseg/models/bodyseg_parser_small.onnx), or the checkout bodyseg was built \
from (.deps/onnxruntime/, models/). The current folder is never searched.";

/// `bodyseg version`.
#[derive(Debug, Args)]
pub struct VersionArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
}

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

const VIEW_LONG_ABOUT: &str = "\
Write a Rerun recording (.rrd) of a finished `bodyseg run` from its files, without \
recomputing anything: the recording's colour and depth images and recorded 2D labels, the \
run's refined clouds (clouds/), projected clouds (stages/, with --write-stages), person \
boxes (boxes/), label images (labels/) and per-frame scores (frames/). Open it with the \
Rerun viewer of the same version (`pip install rerun-sdk==0.36.3`, `rerun FILE.rrd`). \
Entity paths: README \"Rerun\". Needs a build with `--features rerun`.";

const VIEW_EXAMPLES: &str = "\
Examples:
  bodyseg run --recording rec --out run1
  bodyseg view rec --run run1 --rerun run1/run.rrd
  rerun run1/run.rrd";

/// `bodyseg view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Recording folder (the one the run read)
    #[arg(value_name = "REC")]
    pub recording: PathBuf,

    /// The run's output folder (`bodyseg run --out`)
    #[arg(long, value_name = "OUT")]
    pub run: PathBuf,

    /// The Rerun file to write
    #[arg(long, value_name = "FILE.rrd")]
    pub rerun: PathBuf,
}

impl ViewArgs {
    /// The pipeline's options.
    pub fn options(&self) -> bodyseg_pipeline::ViewOptions {
        bodyseg_pipeline::ViewOptions {
            recording: self.recording.clone(),
            run: self.run.clone(),
            rerun: self.rerun.clone(),
        }
    }
}

const SYNTH_LONG_ABOUT: &str = "\
Render a synthetic recording: 1-3 articulated people (poses from a library, perturbed and \
moving smoothly), a room with optional table, boxes and robot arm, seen by Kinect v2-like \
RGB-D cameras (depth 512x424 with the intrinsics and distortion of a real device, colour \
1920x1080 or scaled). Depth has Kinect-like faults (noise growing with distance, flying \
pixels at depth edges, no return at grazing angles or outside 0.5-4.5 m).

Writes the recording layout of shared/FORMATS.md into OUT: rig.toml (the rig given to the \
pipeline, with the configured calibration error), per camera color/, depth/, parsing/ (the \
simulated parser's prediction: small parts over-segmented, boundary jitter, upper/lower \
swaps, missed parts), labels/ (exact 2D truth), depth_labels/ and depth_person/ (exact truth \
of every depth pixel), boxes/ (true person boxes), preview/ (colour | depth | truth | \
prediction per camera), scene.toml (the resolved scene) and rig_true.toml when the written \
rig is not the true one.

The same seed gives byte-identical files. OUT is written to a staging folder beside it and \
moved into place at the end; an existing OUT is only replaced with --force.

Scene keys (see configs/scenes/*.toml) can be set with --set, e.g. \
--set rig.color_width=1920, --set people.count=3, --set parsing.swap_prob=0, \
--set dsa.color_from_depth_rotation_deg=0.5, --set dsa.color_time_offset_s=0.033.";

const SYNTH_EXAMPLES: &str = "\
Examples:
  bodyseg synth --preset handover --frames 20 --seed 1 --out rec
  bodyseg synth --preset robot_cell --frames 50 --set dsa.color_from_depth_rotation_deg=0.5 --out rec_calib_err
  bodyseg synth --scene my_scene.toml --frames 5 --out rec --force
  bodyseg synth --chessboard --views 20 --out calib_views";

/// `bodyseg synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// Bundled scene: single (one person), handover (two people passing an object),
    /// robot_cell (three people, table, boxes, robot arm)
    #[arg(
        long,
        value_name = "NAME",
        conflicts_with = "scene",
        default_value = "single"
    )]
    pub preset: String,

    /// Scene configuration file (TOML, as configs/scenes/*.toml) instead of a preset
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,

    /// Override a scene key, KEY=VALUE with a dotted key (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,

    /// Number of frames
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,

    /// Random seed: people, poses, scene and noise; the same seed gives the same bytes
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

    /// Recording folder to create
    #[arg(long, value_name = "REC")]
    pub out: PathBuf,

    /// Replace OUT if it exists
    #[arg(long)]
    pub force: bool,

    /// Do not write preview/<frame>.png
    #[arg(long)]
    pub no_preview: bool,

    /// Write chessboard calibration views for the scene's rig instead of people: per
    /// camera hand-held board views (colour and IR at the same instant) and one view of a
    /// board lying on the floor, whose frame is the world frame of OUT/rig_true.toml
    #[arg(long)]
    pub chessboard: bool,

    /// Hand-held chessboard views per camera (with --chessboard)
    #[arg(long, default_value_t = 15, requires = "chessboard", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub views: u32,
}

impl SynthArgs {
    /// The pipeline's options.
    pub fn options(&self) -> SynthOptions {
        SynthOptions {
            scene: match &self.scene {
                Some(path) => SceneSource::File(path.clone()),
                None => SceneSource::Preset(self.preset.clone()),
            },
            overrides: self.overrides.clone(),
            seed: self.seed,
            frames: self.frames as usize,
            out: self.out.clone(),
            force: self.force,
            previews: !self.no_preview,
            chessboard: self.chessboard.then(|| ChessboardConfig {
                views: self.views,
                ..ChessboardConfig::default()
            }),
        }
    }
}

/// `--config` and `--set`: the pipeline configuration of every command that reads one.
#[derive(Debug, Args)]
pub struct ConfigArgs {
    /// Configuration file (TOML, as configs/default.toml); keys left out keep the
    /// defaults. Repeat to layer files: a later one overrides only the keys it sets
    #[arg(long = "config", value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// Set one configuration key, SECTION.KEY=VALUE, after the files and before the other
    /// flags (repeatable), e.g. --set refine.eps_m=0.03 --set project.mode=naive; VALUE is
    /// read as TOML (0.03, true, "M-N"), else as a string
    #[arg(long = "set", value_name = "SECTION.KEY=VALUE")]
    pub settings: Vec<String>,
}

impl ConfigArgs {
    /// Defaults < the files in order < the settings, validated.
    pub fn load(&self) -> Result<PipelineConfig> {
        PipelineConfig::resolve(&self.files, &self.settings)
    }
}

const PARSE_LONG_ABOUT: &str = "\
Run 2D human parsing on every camera of one frame: each colour image is mapped into the \
network's square input (SCHP's affine pre-processing: aspect kept, centred, black padding), \
all views go through the ONNX model in one batch, and the logits are warped back to the \
image, where each pixel takes the most probable class (shared/ALGORITHM.md §2).

Model: --model FILE.onnx with its sidecar FILE.json (input_size, channel_order, mean, std, \
class_names, output_stride, align_corners), or parsing.model of the configuration; default \
BlazePose (parsing.segmenter = blazepose, models/blazepose_full.onnx) on the people \
found from depth; parsing.segmenter = onnx without a model runs the bundled \
models/bodyseg_parser_small.onnx (trained on bodyseg synth data by scripts/train_parser.py). \
SCHP checkpoints convert with scripts/export_schp_onnx.py. \
--recorded uses the recording's own parsing/ images instead (e.g. synth's simulated \
predictions), to preview them the same way.

ONNX Runtime is loaded at run time from parsing.runtime_library, else ORT_DYLIB_PATH, else \
the install prefix's lib/bodyseg/libonnxruntime.so, else the checkout's \
.deps/onnxruntime/libonnxruntime.so, which scripts/setup_onnxruntime.sh fetches once; never \
from the current folder (`bodyseg version -v` says which).

Reads, in the recording folder REC (shared/FORMATS.md): REC/rig.toml and for each camera \
REC/<camera>/color/<FRAME>.png (or .jpg). Writes into OUT: <camera>/parsing/<FRAME>.png \
(8-bit class ids, the recording layout's parsing/ images, usable by `bodyseg project`), \
<camera>/parsing_preview/<FRAME>.png (class palette over the dimmed image) and \
parse.config.resolved.toml. Nothing is written when a view fails.

Configuration: built-in defaults (configs/default.toml, section [parsing]) < --config FILE \
(repeatable) < --set SECTION.KEY=VALUE (repeatable) < --model, --threads.";

const PARSE_EXAMPLES: &str = "\
Examples:
  scripts/setup_onnxruntime.sh            # once: the ONNX Runtime library
  bodyseg synth --preset handover --frames 5 --seed 1 --out rec
  bodyseg parse --recording rec --frame 000002 --out parsed
  # An SCHP model exported by scripts/export_schp_onnx.py, 4 threads:
  bodyseg parse --recording rec --frame 000002 --model schp_ppp.onnx --threads 4 --out parsed
  # Preview the recording's own (simulated) predictions:
  bodyseg parse --recording rec --frame 000002 --recorded --out recorded";

/// `bodyseg parse`.
#[derive(Debug, Args)]
pub struct ParseArgs {
    /// Recording folder: rig.toml and per camera <camera>/color/
    #[arg(long, value_name = "REC")]
    pub recording: PathBuf,

    /// Frame to parse: the file stem of its images (e.g. 000012 for color/000012.png)
    #[arg(long, value_name = "STEM")]
    pub frame: String,

    /// SCHP-contract ONNX model (its sidecar: the same path with .json); selects
    /// parsing.segmenter = "onnx" [default: parsing.segmenter, "blazepose"]
    #[arg(long, value_name = "FILE.onnx", conflicts_with = "recorded")]
    pub model: Option<PathBuf>,

    /// Use the recording's parsing/ label images instead of a model
    #[arg(long)]
    pub recorded: bool,

    /// ONNX Runtime threads, 0 = one per core [default: parsing.threads, 2]
    #[arg(long, value_name = "N")]
    pub threads: Option<u32>,

    #[command(flatten)]
    pub config: ConfigArgs,

    /// Output folder (created if missing): <camera>/parsing/<FRAME>.png and
    /// <camera>/parsing_preview/<FRAME>.png
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

impl ParseArgs {
    /// The pipeline's options: defaults < --config < --set < --model, --threads, validated.
    pub fn options(&self) -> Result<ParseOptions> {
        let mut config = self.config.load()?;
        if let Some(model) = &self.model {
            config.parsing.model = model.display().to_string();
            config.parsing.segmenter = bodyseg_pipeline::SegmenterKind::Onnx;
        }
        if let Some(threads) = self.threads {
            config.parsing.threads = threads;
        }
        config.validate()?;
        Ok(ParseOptions {
            recording: self.recording.clone(),
            frame: self.frame.clone(),
            config,
            source: if self.recorded {
                ParseSource::Recorded
            } else {
                ParseSource::Model
            },
            out: self.out.clone(),
        })
    }
}

const PROJECT_LONG_ABOUT: &str = "\
Label the depth points of one frame of a recording: every camera's depth image is \
back-projected, each point looks up the label of the colour pixel it projects to in that \
camera's parsing image, and the cameras' points are moved to the world frame and \
concatenated (cameras in rig order, pixels row-major).

Modes: `naive` (the paper's baseline: the nearest colour pixel's label) or `dsa` (default: \
the same, guarded against depth-segmentation association errors by an occlusion z-buffer, \
a depth-edge / flying-pixel test and a label-boundary vote; a point no check lets through \
is `unknown`, label 255).

Reads, in the recording folder REC (shared/FORMATS.md): REC/rig.toml, and for each camera \
of the rig REC/<camera>/depth/<FRAME>.png (16-bit millimetres, depth sensor size) and \
REC/<camera>/parsing/<FRAME>.png (8-bit class ids, 255 = not labelled, colour sensor size). \
Writes: the labelled cloud (--out, PLY: x y z in metres, world frame; label, camera and \
pixel per point) and beside it the exact configuration used (--out frame.ply writes \
frame.config.resolved.toml). Nothing is written when the command fails.

Configuration: built-in defaults (configs/default.toml, sections [backproject] and \
[project]) < --config FILE (repeatable) < --set SECTION.KEY=VALUE (repeatable) < --mode.";

const PROJECT_EXAMPLES: &str = "\
Examples:
  # DSA-aware projection of frame 000012 of recording rec/:
  bodyseg synth --preset handover --frames 20 --seed 1 --out rec
  bodyseg project --recording rec --frame 000012 --out frame.ply
  # The paper's naive baseline, ASCII output:
  bodyseg project --recording rec --frame 000012 --mode naive --ascii --out naive.ply
  # Settings from a file (see configs/default.toml for every key):
  bodyseg project --config my.toml --recording rec --frame 000012 --out frame.ply";

/// `bodyseg project`.
#[derive(Debug, Args)]
pub struct ProjectArgs {
    /// Recording folder: rig.toml and per camera <camera>/depth/ and <camera>/parsing/
    #[arg(long, value_name = "REC")]
    pub recording: PathBuf,

    /// Frame to project: the file stem of its images (e.g. 000012 for depth/000012.png)
    #[arg(long, value_name = "STEM")]
    pub frame: String,

    /// Projection: naive (nearest colour pixel) or dsa (with the DSA checks) [default:
    /// project.mode of the configuration, dsa]
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,

    #[command(flatten)]
    pub config: ConfigArgs,

    /// Write ASCII PLY (default: binary little-endian)
    #[arg(long)]
    pub ascii: bool,

    /// Where to write the labelled cloud (PLY); an existing file is replaced only on
    /// success
    #[arg(long, value_name = "OUT.ply")]
    pub out: PathBuf,
}

/// `--mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// The label of the nearest colour pixel (the paper's baseline)
    Naive,
    /// Nearest colour pixel guarded by the DSA checks (occlusion, depth edges, label
    /// boundaries)
    Dsa,
}

impl From<Mode> for ProjectMode {
    fn from(m: Mode) -> ProjectMode {
        match m {
            Mode::Naive => ProjectMode::Naive,
            Mode::Dsa => ProjectMode::Dsa,
        }
    }
}

impl ProjectArgs {
    /// The resolved configuration: defaults < --config < --set < --mode, validated.
    pub fn config(&self) -> Result<PipelineConfig> {
        let mut config = self.config.load()?;
        config.apply_project_mode(self.mode.map(ProjectMode::from));
        Ok(config)
    }

    /// The pipeline's options for `project_file`.
    pub fn options(&self) -> Result<ProjectOptions> {
        Ok(ProjectOptions {
            recording: self.recording.clone(),
            frame: self.frame.clone(),
            config: self.config()?,
            out: self.out.clone(),
            ascii: self.ascii,
            write_resolved_config: true,
        })
    }
}

const BOXES_LONG_ABOUT: &str = "\
Find one oriented box per person (centre, half extents, yaw about z; from the floor up), \
the boxes `bodyseg refine` works in (shared/ALGORITHM.md §4).

Modes: `labels` (default: body-labelled points are voxelized and clustered; a cluster with \
two or more separate heads, or torsos, is split between them, so two people touching hands \
get two boxes; clusters too small, too low or too wide are dropped), `geometry` (no labels \
needed: the ground plane is found by RANSAC and removed, the rest clustered and split on \
head-height maxima with a body column below them, in the spirit of Munaro et al.'s \
ground-based people detector) or `file` (read REC/boxes/<FRAME>.json, e.g. from an external \
tracker).

Reads: a cloud (--cloud: PLY, as `bodyseg project` writes it or any other tool's, or PCL's \
PCD: ascii, binary or binary_compressed, organised or not; x y z in metres, colours \
optional, a `label` field of bodyseg's class ids for labels mode; geometry mode needs no \
labels and ignores a label field of other ids, e.g. PCL's segment ids, with a note), or \
one frame of a recording (--recording, --frame: projected as `bodyseg project` does, in \
the world frame of its rig.toml).

Up and the floor: a cloud file may be in any frame, e.g. a camera's (x right, y down, z \
forward). Its floor is found: the largest plane that the points stand on (RANSAC over all \
orientations; walls and ceilings lose because nothing stands on them). When the floor is \
level in the cloud's own frame (within boxes.max_ground_tilt_deg of its z), the cloud is \
taken as it is and the boxes are in its frame. Otherwise the cloud is moved into the \
floor's frame (z up along the floor's normal, the floor at z = 0, x along the cloud's x), \
the boxes are found and written in that frame, and the JSON records the transform as \
\"world_from_cloud\" (rotation, translation_m: p_world = rotation * p_cloud + translation); \
`bodyseg refine` applies it to the cloud. --ground a,b,c,d gives the floor instead (the \
plane a*x + b*y + c*z + d = 0 in the cloud's frame, metres, as PCL's people detector takes \
it), --up AXIS the cloud axis that points up (within 45 degrees; only floors along it are \
looked for); either makes the boxes be written in the floor's frame. A warning says when \
no floor or no person is found, with the likely cause (a camera view with no floor in it, \
a cloud in millimetres).

Writes: the boxes (--out, JSON: {\"frame\", \"boxes\": [{\"id\", \"center_m\", \
\"half_extents_m\", \"yaw_rad\"}], \"world_from_cloud\" when not the cloud's own frame}), \
beside it the exact configuration used (--out b.json writes b.config.resolved.toml) and, \
with --preview, a top view of the cloud in the boxes' frame (class colours) with the boxes \
drawn. Nothing is written when the command fails.

Configuration: built-in defaults (configs/default.toml, section [boxes]; [backproject] and \
[project] for a recording) < --config FILE (repeatable) < --set SECTION.KEY=VALUE \
(repeatable) < --mode.";

const BOXES_EXAMPLES: &str = "\
Examples:
  # Boxes of a projected frame, from its body labels, with a preview:
  bodyseg project --recording rec --frame 000012 --out frame.ply
  bodyseg boxes --cloud frame.ply --out frame_boxes.json --preview frame_top.png
  # A PCL cloud without labels, in any frame (a Kinect's: its floor is found):
  bodyseg boxes --cloud scene.pcd --mode geometry --out boxes.json --preview top.png
  # ... with the floor given, as PCL's ground coefficients, or the up axis:
  bodyseg boxes --cloud scene.pcd --mode geometry --ground 0,-1,0,1.1 --out boxes.json
  bodyseg boxes --cloud scene.pcd --mode geometry --up -y --out boxes.json
  # Project and find boxes in one go; or read the recording's own boxes/000012.json:
  bodyseg boxes --recording rec --frame 000012 --out frame_boxes.json
  bodyseg boxes --recording rec --frame 000012 --mode file --out frame_boxes.json";

/// `bodyseg boxes`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("input").required(true).args(["cloud", "recording"])))]
pub struct BoxesArgs {
    /// Point cloud to find people in: .ply (bodyseg's labelled PLY) or .pcd (PCL)
    #[arg(long, value_name = "CLOUD.ply|CLOUD.pcd")]
    pub cloud: Option<PathBuf>,

    /// Recording folder (instead of --cloud): the frame is projected first, or in file
    /// mode its boxes/<FRAME>.json read
    #[arg(long, value_name = "REC", requires = "frame")]
    pub recording: Option<PathBuf>,

    /// Frame of the recording: the file stem of its images (e.g. 000012)
    #[arg(long, value_name = "STEM", requires = "recording")]
    pub frame: Option<String>,

    /// Where boxes come from: labels (body labels), geometry (no labels) or file
    /// (REC/boxes/) [default: boxes.mode of the configuration, labels]
    #[arg(long, value_enum)]
    pub mode: Option<BoxesMode>,

    #[command(flatten)]
    pub config: ConfigArgs,

    /// Where to write the boxes (JSON); an existing file is replaced only on success
    #[arg(long, value_name = "OUT.json")]
    pub out: PathBuf,

    /// Also write a top view of the cloud with the boxes drawn (PNG)
    #[arg(long, value_name = "TOP.png")]
    pub preview: Option<PathBuf>,

    #[command(flatten)]
    pub floor: FloorArgs,
}

/// `--ground` and `--up`: the floor of a cloud, when the user knows it.
#[derive(Debug, Args)]
pub struct FloorArgs {
    /// The floor of the cloud: the plane a*x + b*y + c*z + d = 0 in the cloud's frame,
    /// metres (PCL's ground coefficients) [default: found]
    #[arg(long, value_name = "A,B,C,D", value_parser = parse_plane, allow_hyphen_values = true)]
    pub ground: Option<[f32; 4]>,

    /// The axis of the cloud's frame that points up, roughly (within 45 degrees): x, y,
    /// z, -x, -y or -z (a camera's optical frame: -y) [default: found]
    #[arg(long, value_name = "AXIS", value_parser = parse_up, allow_hyphen_values = true)]
    pub up: Option<bodyseg_pipeline::Up>,
}

impl FloorArgs {
    /// The pipeline's floor hint.
    pub fn hint(&self) -> FloorHint {
        FloorHint {
            ground: self.ground,
            up: self.up,
        }
    }

    /// Whether either flag is given.
    fn given(&self) -> bool {
        self.ground.is_some() || self.up.is_some()
    }
}

/// `--ground a,b,c,d`: four finite numbers, (a, b, c) not all zero.
fn parse_plane(text: &str) -> std::result::Result<[f32; 4], String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| {
            v.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{}' is not a finite number", v.trim()))
        })
        .collect::<std::result::Result<_, _>>()?;
    let [a, b, c, d] = values[..] else {
        return Err(format!(
            "expected four numbers a,b,c,d (the plane a*x + b*y + c*z + d = 0), got {}",
            values.len()
        ));
    };
    if a == 0.0 && b == 0.0 && c == 0.0 {
        return Err("a, b and c are all 0: no plane".into());
    }
    Ok([a, b, c, d])
}

/// `--up AXIS`.
fn parse_up(text: &str) -> std::result::Result<bodyseg_pipeline::Up, String> {
    text.parse()
}

/// `bodyseg boxes --mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BoxesMode {
    /// Body-labelled points clustered and split on heads
    Labels,
    /// Ground plane removed, the rest clustered and split on head-height maxima
    Geometry,
    /// Read REC/boxes/<FRAME>.json
    File,
}

impl BoxesArgs {
    /// The resolved configuration: defaults < --config < --set < --mode, validated.
    pub fn config(&self) -> Result<PipelineConfig> {
        let mut config = self.config.load()?;
        config.apply_boxes_mode(self.mode.map(|m| match m {
            BoxesMode::Labels => bodyseg_pipeline::BoxMode::Labels,
            BoxesMode::Geometry => bodyseg_pipeline::BoxMode::Geometry,
            BoxesMode::File => bodyseg_pipeline::BoxMode::File,
        }));
        Ok(config)
    }

    /// The pipeline's options for `boxes_file`.
    pub fn options(&self) -> Result<bodyseg_pipeline::BoxesOptions> {
        if self.floor.given() && self.cloud.is_none() {
            bail!(
                "--ground and --up apply to --cloud: a recording's frame is the world frame of \
                 its rig.toml"
            );
        }
        let input = match (&self.cloud, &self.recording, &self.frame) {
            (Some(cloud), _, _) => bodyseg_pipeline::BoxesInput::Cloud(cloud.clone()),
            (None, Some(recording), Some(frame)) => bodyseg_pipeline::BoxesInput::Recording {
                recording: recording.clone(),
                frame: frame.clone(),
            },
            _ => bail!("give --cloud, or --recording and --frame"),
        };
        Ok(bodyseg_pipeline::BoxesOptions {
            input,
            config: self.config()?,
            out: self.out.clone(),
            preview: self.preview.clone(),
            write_resolved_config: true,
            floor: self.floor.hint(),
        })
    }
}

const REFINE_LONG_ABOUT: &str = "\
Repair the body-part labels of one point cloud with the clustering refinement (the paper's \
Algorithm 1). Inside each person box, points are clustered per label (DBSCAN); the M step \
merges clusters lying inside a cluster of another label, R turns clusters cut off from the \
body into background, and N gives noise points the label of the nearest clustered point. \
Body-labelled points outside every box become background.

Reads: the labelled cloud (--cloud, PLY) and its person boxes (--boxes, JSON). Writes: the \
refined cloud (--out, PLY: the same points in the same order, only `label` and the palette \
colours change) and beside it the exact configuration used (--out refined.ply writes \
refined.config.resolved.toml). Nothing is written when the command fails.

Configuration: built-in defaults (configs/default.toml) < --config FILE (repeatable) < --set \
SECTION.KEY=VALUE (repeatable) < flags.";

const REFINE_EXAMPLES: &str = "\
Examples:
  # Refine with the default configuration (M-R-N, eps 0.05 m, min 40 points):
  bodyseg refine --cloud frame.ply --boxes frame_boxes.json --out refined.ply
  # Only merge and noise steps, a 3 cm radius, ASCII output:
  bodyseg refine --cloud frame.ply --boxes frame_boxes.json --steps m,n --eps-m 0.03 \\
      --ascii --out refined.ply
  # Settings from a file (see configs/default.toml for every key):
  bodyseg refine --config my.toml --cloud frame.ply --boxes frame_boxes.json --out refined.ply";

/// `bodyseg refine`.
#[derive(Debug, Args)]
pub struct RefineArgs {
    /// Labelled point cloud to refine (PLY with x, y, z in metres and a `label` per point)
    #[arg(long, value_name = "IN.ply")]
    pub cloud: PathBuf,

    /// Person boxes of that cloud (JSON: {"boxes": [{"id", "center_m", "half_extents_m",
    /// "yaw_rad"}]})
    #[arg(long, value_name = "BOXES.json")]
    pub boxes: PathBuf,

    /// Where to write the refined cloud (PLY); an existing file is replaced only on success
    #[arg(long, value_name = "OUT.ply")]
    pub out: PathBuf,

    #[command(flatten)]
    pub config: ConfigArgs,

    /// Steps to run: m (merge), r (remove), n (noise) joined by ',' or '-', e.g. m,r,n or
    /// M-N; or `reference` (labels untouched) [default: M-R-N]
    #[arg(long, value_name = "STEPS")]
    pub steps: Option<Steps>,

    /// DBSCAN radius in metres (> 0) [default: 0.05]
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    pub eps_m: Option<f32>,

    /// DBSCAN core threshold: neighbours within the radius, the point itself included (>= 1)
    /// [default: 40]
    #[arg(long, value_name = "N")]
    pub min_points: Option<usize>,

    /// Keep the labels of body points outside every box (default: they become background)
    #[arg(long)]
    pub keep_outside_boxes: bool,

    /// Write ASCII PLY (default: binary little-endian)
    #[arg(long)]
    pub ascii: bool,
}

impl RefineArgs {
    /// The resolved configuration: defaults < --config < --set < flags, validated.
    pub fn config(&self) -> Result<PipelineConfig> {
        let mut config = self.config.load()?;
        config.apply_refine_overrides(&RefineOverrides {
            steps: self.steps,
            eps_m: self.eps_m,
            min_points: self.min_points,
            keep_outside_boxes: self.keep_outside_boxes.then_some(true),
        })?;
        Ok(config)
    }

    /// The pipeline's options for `refine_file`.
    pub fn options(&self) -> Result<RefineOptions> {
        Ok(RefineOptions {
            cloud: self.cloud.clone(),
            boxes: self.boxes.clone(),
            out: self.out.clone(),
            config: self.config()?,
            ascii: self.ascii,
            write_resolved_config: true,
        })
    }
}

const EVAL_LONG_ABOUT: &str = "\
Score labelled point clouds against ground truth, as the paper's tables do: per class IoU, \
precision, recall and F1, mIoU (all 7 classes), BIoU (the 6 body classes), AP and F1.

Reads: one or more predicted clouds (--pred, PLY) and the ground-truth cloud (--gt, PLY). \
Points are paired by their origin (the `camera` and `pixel` properties; without them, by \
vertex index), so both clouds must come from the same frame. Ground-truth points labelled \
255 (unknown) are not scored; predicted unknown points count as background. Writes: the \
report to stdout, or to --out FILE.

With --merge, reads report JSON files (written with --format json, e.g. one per shard of a \
data set) and sums their confusion matrices into one report.

Metrics are printed as percentages (markdown) or fractions 0..1 (JSON).";

const EVAL_EXAMPLES: &str = "\
Examples:
  # One prediction, markdown table on stdout:
  bodyseg eval --pred refined.ply --gt truth.ply
  # Compare configurations (the first is the reference of the change rows), JSON report:
  bodyseg eval --pred Reference=input.ply --pred M-R-N=refined.ply --gt truth.ply \\
      --format json --out report.json
  # Sum the reports of several shards:
  bodyseg eval --merge shard0.json shard1.json --format md";

/// `bodyseg eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Predicted cloud (PLY); repeat as NAME=PATH to compare several configurations
    /// (a value holding '=' is NAME=PATH: write ./a=b.ply for such a file name)
    #[arg(
        long = "pred",
        value_name = "[NAME=]PRED.ply",
        required_unless_present = "merge"
    )]
    pub pred: Vec<String>,

    /// Ground-truth cloud (PLY) with the true label of each point
    #[arg(long, value_name = "GT.ply", required_unless_present = "merge")]
    pub gt: Option<PathBuf>,

    /// Row name of a single --pred given without NAME= [default: prediction]
    #[arg(long, value_name = "NAME")]
    pub name: Option<String>,

    /// Merge these report JSON files (from --format json) instead of scoring clouds
    #[arg(
        long,
        value_name = "REPORT.json",
        num_args = 1..,
        conflicts_with_all = ["pred", "gt", "name"]
    )]
    pub merge: Vec<PathBuf>,

    /// Report format: md (the paper's tables, percentages) or json (matrices and metrics,
    /// fractions; mergeable with --merge)
    #[arg(long, value_enum, default_value_t = Format::Md)]
    pub format: Format,

    /// Write the report to this file (replaced only on success) instead of stdout
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// `--format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Markdown tables.
    Md,
    /// JSON.
    Json,
}

impl From<Format> for ReportFormat {
    fn from(f: Format) -> ReportFormat {
        match f {
            Format::Md => ReportFormat::Markdown,
            Format::Json => ReportFormat::Json,
        }
    }
}

impl EvalArgs {
    /// The pipeline's options for `eval_files` (not used with --merge).
    pub fn options(&self) -> Result<EvalOptions> {
        let Some(gt) = self.gt.clone() else {
            bail!("--gt is required to score clouds");
        };
        let parsed: Vec<(Option<String>, PathBuf)> =
            self.pred.iter().map(|p| split_named(p)).collect();
        let unnamed = parsed.iter().filter(|(n, _)| n.is_none()).count();
        if parsed.len() > 1 && unnamed > 0 {
            bail!("several --pred given: name each as --pred NAME=PATH");
        }
        if self.name.is_some() && unnamed == 0 {
            bail!("--name names a single --pred given without NAME=; drop one of the two");
        }
        let predictions = parsed
            .into_iter()
            .map(|(name, path)| NamedPrediction {
                name: name
                    .or_else(|| self.name.clone())
                    .unwrap_or_else(|| DEFAULT_PREDICTION_NAME.to_string()),
                path,
            })
            .collect();
        Ok(EvalOptions { predictions, gt })
    }
}

/// `NAME=PATH` → (Some(NAME), PATH); a value with no '=', or whose part before the first
/// '=' is empty or holds a path separator, is a plain path.
fn split_named(value: &str) -> (Option<String>, PathBuf) {
    match value.split_once('=') {
        Some((name, path)) if !name.is_empty() && !name.contains(['/', '\\']) => {
            (Some(name.to_string()), PathBuf::from(path))
        }
        _ => (None, PathBuf::from(value)),
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

/// `bodyseg rig ...`.
#[derive(Debug, Subcommand)]
pub enum RigCommand {
    /// Assemble a rig.toml from other tools' calibration files, one camera per input
    /// (iai_kinect2, Azure Kinect, ROS camera_info, OpenCV; world poses from OpenPTrack)
    #[command(long_about = RIG_IMPORT_LONG_ABOUT, after_help = RIG_IMPORT_EXAMPLES)]
    Import(RigImportArgs),
    /// Print a short summary of a rig.toml: sensor sizes and intrinsics, baseline, depth
    /// shift, world position of each camera
    #[command(after_help = RIG_SHOW_EXAMPLES)]
    Show(RigShowArgs),
}

const RIG_IMPORT_LONG_ABOUT: &str = "\
Assemble a rig.toml (shared/FORMATS.md) from calibration files of other tools: one INPUT \
per camera, cameras in the order given (the rig order: camera index i of a point is the \
i-th INPUT). --from gives the format: once for every INPUT, or once per INPUT in the same \
order. What each format reads:

--from iai_kinect2: INPUT is a kinect2_calibration folder (calib_color.yaml, calib_ir.yaml, \
calib_pose.yaml, calib_depth.yaml). calib_pose maps the IR (depth) sensor into the colour \
sensor (metres) and becomes color_from_depth; depthShift (millimetres) becomes \
depth_shift_mm; a folder without calib_depth.yaml gets depth shift 0, as kinect2_bridge \
does (a note says so); depth_scale is 1000; image sizes are the Kinect v2 ones (512x424 \
depth, 1920x1080 colour) unless the files give image_width/image_height.

--from azure_kinect: INPUT is the device's factory calibration JSON (k4arecorder's \
calibration.json, k4a_device_get_raw_calibration), mapped as the Azure Kinect SDK maps \
it: both sensors with their rational distortion (k1..k6, p1, p2) and the colour sensor's \
pose. The intrinsics are for the full images the calibration is stored for (depth \
1024x1024, colour 4096x3072) unless --depth-mode and --color-resolution name the mode \
of the recording (e.g. NFOV_UNBINNED: 640x576, 1080P: 1920x1080). depth_scale 1000, no \
shift.

--from ros: INPUT is DEPTH.yaml,COLOR.yaml: the ROS camera_info files of the depth and \
the colour sensor (plumb_bob or rational_polynomial; a file without distortion_model is \
plumb_bob, as in ROS). camera_info holds no pose between the sensors: color_from_depth \
is the identity (a note says so). A single file (no comma) is a depth stream registered \
to that sensor (depth_registered): both sensors get its intrinsics.

--from opencv: as ros, with OpenCV FileStorage YAML files of one sensor each \
(camera_matrix or cameraMatrix, distortion_coefficients or distortionCoefficients with \
4, 5 or 8 values, image_width, image_height), e.g. from cv::FileStorage or `bodyseg \
calibrate intrinsics`. XML files need bodyseg built with --features opencv.

--from openptrack: an OpenPTrack network: INPUTs as for ros (its sensors' camera_info \
files), and --poses is required.

World poses: none of these formats holds one. --poses reads OpenPTrack's \
camera_poses.yaml (opt_calibration's output): each camera's pose is that of the sensor \
of the same name (name the cameras after OpenPTrack's sensors with --name). OpenPTrack \
calibrates the colour sensors, so world_from_depth = pose · color_from_depth. Without \
--poses every world_from_depth is the identity; set the real poses with `bodyseg \
calibrate world` or by editing the written file; a note says so unless \
--world-from-depth-identity is given.

Camera names are the folder names (iai_kinect2) or file stems, or --name (once per INPUT, \
same order); they must be distinct. Notes (defaults taken) are printed as `note:` lines. \
Writes --out atomically: nothing is written when an input cannot be read; errors name \
the file and the key.";

const RIG_IMPORT_EXAMPLES: &str = "\
Examples:
  # Three Kinect v2 cameras, named after their serial-number folders:
  bodyseg rig import --from iai_kinect2 calib/011054343347 calib/021401644747 \\
      calib/196605135147 --out rig.toml
  # The same, named after OpenPTrack's sensors and placed with its camera_poses.yaml:
  bodyseg rig import --from iai_kinect2 calib/011054343347 calib/021401644747 \\
      calib/196605135147 --name kinect01 --name kinect02 --name kinect03 \\
      --poses opt_calibration/conf/camera_poses.yaml --out rig.toml
  # An Azure Kinect recorded in NFOV unbinned depth and 1080p colour:
  bodyseg rig import --from azure_kinect calibration.json --depth-mode NFOV_UNBINNED \\
      --color-resolution 1080P --out rig.toml
  # A Kinect v2 and a ROS camera (depth and colour camera_info), two formats:
  bodyseg rig import --from iai_kinect2 --from ros calib/011054343347 \\
      ros/depth.yaml,ros/rgb.yaml --name left --name right --out rig.toml
  # An OpenPTrack network of ROS cameras (camera_info files named after its sensors):
  bodyseg rig import --from openptrack cam01_depth.yaml,cam01_rgb.yaml \\
      cam02_depth.yaml,cam02_rgb.yaml --name cam01 --name cam02 \\
      --poses opt_calibration/conf/camera_poses.yaml --out rig.toml
  # Check what was imported:
  bodyseg rig show rig.toml";

/// `bodyseg rig import`.
#[derive(Debug, Args)]
pub struct RigImportArgs {
    /// Format of the inputs: once for all, or once per INPUT in the same order
    #[arg(long, value_enum, value_name = "FORMAT", required = true)]
    pub from: Vec<ImportFormat>,

    /// One camera each: a folder (iai_kinect2), a JSON file (azure_kinect), or
    /// DEPTH,COLOR files (ros, opencv; one file: depth registered to that sensor)
    #[arg(value_name = "INPUT", required = true, num_args = 1..)]
    pub inputs: Vec<String>,

    /// Camera name: once per INPUT, in the same order [default: folder names, file stems]
    #[arg(long = "name", value_name = "NAME")]
    pub names: Vec<String>,

    /// OpenPTrack camera_poses.yaml: each camera's world pose, by camera name
    #[arg(long, value_name = "camera_poses.yaml")]
    pub poses: Option<PathBuf>,

    /// Azure Kinect depth mode of the recording (intrinsics for its images)
    /// [default: the stored 1024x1024 image]
    #[arg(long, value_name = "MODE", value_parser = parse_depth_mode)]
    pub depth_mode: Option<AzureDepthMode>,

    /// Azure Kinect colour resolution of the recording: 720P, 1080P, 1440P, 1536P, 2160P
    /// or 3072P [default: the stored image, 3072P on a retail device]
    #[arg(long, value_name = "RESOLUTION", value_parser = parse_color_resolution)]
    pub color_resolution: Option<AzureColorResolution>,

    /// Accept identity world poses (world_from_depth) without --poses, without the note
    /// saying so; the rig is the same either way
    #[arg(long)]
    pub world_from_depth_identity: bool,

    /// Where to write the rig (TOML); an existing file is replaced only on success
    #[arg(long, value_name = "RIG.toml")]
    pub out: PathBuf,
}

fn parse_depth_mode(s: &str) -> Result<AzureDepthMode, String> {
    AzureDepthMode::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = AzureDepthMode::ALL.iter().map(|m| m.name()).collect();
        format!("{s:?} is not a depth mode: {}", names.join(", "))
    })
}

fn parse_color_resolution(s: &str) -> Result<AzureColorResolution, String> {
    AzureColorResolution::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = AzureColorResolution::ALL.iter().map(|m| m.name()).collect();
        format!("{s:?} is not a colour resolution: {}", names.join(", "))
    })
}

/// `--from`: the calibration formats `rig import` reads, as in [`RigFormat`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ImportFormat {
    /// iai_kinect2 folders: calib_color.yaml, calib_ir.yaml, calib_pose.yaml,
    /// calib_depth.yaml
    #[value(name = "iai_kinect2")]
    IaiKinect2,
    /// Azure Kinect factory calibration JSON
    #[value(name = "azure_kinect")]
    AzureKinect,
    /// ROS camera_info YAML, DEPTH,COLOR
    #[value(name = "ros")]
    Ros,
    /// OpenCV FileStorage intrinsics, DEPTH,COLOR
    #[value(name = "opencv")]
    OpenCv,
    /// An OpenPTrack network: each sensor's ROS camera_info YAML (DEPTH,COLOR, as its
    /// drivers store them), placed by opt_calibration's camera_poses.yaml (--poses, required)
    #[value(name = "openptrack")]
    OpenPTrack,
}

impl From<ImportFormat> for RigFormat {
    fn from(f: ImportFormat) -> RigFormat {
        match f {
            ImportFormat::IaiKinect2 => RigFormat::IaiKinect2,
            ImportFormat::AzureKinect => RigFormat::AzureKinect,
            ImportFormat::Ros => RigFormat::Ros,
            ImportFormat::OpenCv => RigFormat::OpenCv,
            // OpenPTrack's intrinsics are ROS camera_info files; its own part, the world
            // poses, is --poses (checked in `options`).
            ImportFormat::OpenPTrack => RigFormat::Ros,
        }
    }
}

impl RigImportArgs {
    /// The pipeline's options for `import_rig`: each INPUT with its format (`DEPTH,COLOR`
    /// split for one-sensor formats).
    pub fn options(&self) -> Result<RigImportOptions> {
        if self.from.contains(&ImportFormat::OpenPTrack) && self.poses.is_none() {
            bail!(
                "--from openptrack needs --poses camera_poses.yaml (opt_calibration's output, \
                 e.g. opt_calibration/conf/camera_poses.yaml)"
            );
        }
        let formats: Vec<RigFormat> = match self.from.as_slice() {
            [one] => vec![(*one).into(); self.inputs.len()],
            many if many.len() == self.inputs.len() => many.iter().map(|&f| f.into()).collect(),
            many => bail!(
                "{} --from for {} INPUTs: give one --from for all, or one per INPUT in the \
                 same order",
                many.len(),
                self.inputs.len()
            ),
        };
        let inputs = self
            .inputs
            .iter()
            .zip(formats)
            .map(|(input, format)| {
                let (path, color) = match input.split_once(',') {
                    Some((depth, color)) if format.is_one_sensor() => {
                        (PathBuf::from(depth), Some(PathBuf::from(color)))
                    }
                    _ => (PathBuf::from(input), None),
                };
                RigInput {
                    format,
                    path,
                    color,
                }
            })
            .collect::<Vec<_>>();
        let has_azure = inputs.iter().any(|i| i.format == RigFormat::AzureKinect);
        if !has_azure && (self.depth_mode.is_some() || self.color_resolution.is_some()) {
            bail!("--depth-mode and --color-resolution apply to --from azure_kinect only");
        }
        Ok(RigImportOptions {
            inputs,
            names: self.names.clone(),
            poses: self.poses.clone(),
            azure_mode: AzureKinectMode {
                depth: self.depth_mode,
                color: self.color_resolution,
            },
            world_from_depth_identity: self.world_from_depth_identity,
            out: self.out.clone(),
        })
    }
}

const RIG_SHOW_EXAMPLES: &str = "\
Examples:
  bodyseg rig show rig.toml
  bodyseg rig show recording/rig.toml";

/// `bodyseg rig show`.
#[derive(Debug, Args)]
pub struct RigShowArgs {
    /// The rig to show (rig.toml, shared/FORMATS.md)
    #[arg(value_name = "RIG.toml")]
    pub rig: PathBuf,
}

/// `bodyseg calibrate`.
#[derive(Debug, Subcommand)]
pub enum CalibrateCommand {
    /// One sensor's intrinsics (focal lengths, principal point, k1 k2 p1 p2 k3) from a
    /// folder of chessboard views
    #[command(long_about = CALIBRATE_INTRINSICS_LONG_ABOUT, after_help = CALIBRATE_EXAMPLES)]
    Intrinsics(CalibrateIntrinsicsArgs),
    /// One RGB-D camera's colour-from-depth from IR and colour views of the same board
    /// poses: writes a one-camera rig.toml
    #[command(long_about = CALIBRATE_STEREO_LONG_ABOUT, after_help = CALIBRATE_EXAMPLES)]
    Stereo(CalibrateStereoArgs),
    /// Every camera's world pose from simultaneous views of a board lying on the floor
    /// (the board's frame is the world, z up): writes the rig.toml
    #[command(long_about = CALIBRATE_WORLD_LONG_ABOUT, after_help = CALIBRATE_EXAMPLES)]
    World(CalibrateWorldArgs),
}

const CALIBRATE_LONG_ABOUT: &str = "\
Calibrate RGB-D cameras from images of a printed chessboard, with OpenCV (corners with \
sub-pixel refinement, calibrateCamera, stereoCalibrate, solvePnP). Three steps lead from \
board images to a rig.toml: `intrinsics` per sensor, `stereo` per camera (colour-from-depth), \
`world` once for the rig (every camera placed on a board lying on the floor). README.md \
\"Calibrating your cameras\" walks through them.

The commands need a bodyseg built with the `opencv` feature (cargo build --release \
--features opencv, with libopencv-dev, clang and libclang-dev: scripts/setup_opencv.sh); \
without it they say so and exit with status 1.";

const CALIBRATE_INTRINSICS_LONG_ABOUT: &str = "\
Calibrate one sensor (a colour camera, or a depth camera's IR sensor) from a folder of PNG \
or JPEG views of a chessboard, all of the same size: the board's inner corners are found \
and refined to sub-pixel accuracy, then OpenCV's calibrateCamera fits fx, fy, cx, cy and \
the distortion k1 k2 p1 p2 k3. Images where the board is not found are reported and \
skipped; at least 3 must show it (15-20 views, the board tilted in every direction and \
reaching the image corners, give good results).

Prints the RMS reprojection error of each image and of all: below 0.3 px is good; an image \
far above the others is likely blurred or misdetected, remove it and rerun.

--out ending in .toml writes the fields of a rig.toml sensor table (width, height, fx, fy, \
cx, cy, distortion) with the errors as comments; .yaml, .yml or .xml writes OpenCV \
FileStorage (cameraMatrix, distortionCoefficients, image_width, image_height, as \
iai_kinect2's calib_*.yaml).";

const CALIBRATE_STEREO_LONG_ABOUT: &str = "\
Calibrate one RGB-D camera's colour-from-depth (the rigid transform from the depth (IR) \
sensor's frame into the colour sensor's) from views of a chessboard taken by both sensors \
at the same instants: an IR image and a colour image of the same file name (stem) form a \
pair. The intrinsics come from --ir-intrinsics / --color-intrinsics (files written by \
`calibrate intrinsics`, or OpenCV FileStorage YAML/XML such as iai_kinect2's calib_ir.yaml), \
else they are calibrated from the same views first. OpenCV's stereoCalibrate then fits the \
transform and refines both intrinsics with it (a board pose shared by both sensors fixes \
their relative scale: millimetres better along the viewing direction); --fix-intrinsics \
keeps them as they are.

Writes a rig.toml with this one camera (depth scale 1000, world pose identity): the input \
of `calibrate world`. The board must have one even and one odd count of inner corners \
(9x6) so that both sensors number its corners alike.";

const CALIBRATE_WORLD_LONG_ABOUT: &str = "\
Place every camera in one world frame: lay a chessboard flat on the floor where all cameras \
see it and save, per camera, its IR and/or colour view as FLOOR/<camera name>/ir.png and \
FLOOR/<camera name>/color.png (or .jpg). The board defines the world: the origin is its \
inner corner (0, 0) (next to a black corner square), x runs along the rows of the first \
inner-corner count, z points up, y = z cross x. Seen from above, x turned 90 degrees \
counter-clockwise is y. Each camera's world_from_depth is fitted to all its views (solvePnP, \
then IR and colour corners together through the camera's colour-from-depth); its \
intrinsics and colour-from-depth are kept from the --rig files.

A larger board (e.g. 0.1 m squares) is easier to see from 3 m than a hand-held one. The \
board must have one even and one odd count of inner corners (9x6).";

const CALIBRATE_EXAMPLES: &str = "\
Examples:
  # on the views of `bodyseg synth --chessboard --out views`:
  bodyseg calibrate intrinsics --images views/cam0/ir --board 9x6 --square-m 0.04 --out cam0_ir.toml
  bodyseg calibrate intrinsics --images views/cam0/color --board 9x6 --square-m 0.04 --out cam0_color.yaml
  bodyseg calibrate stereo --ir views/cam0/ir --color views/cam0/color --board 9x6 --square-m 0.04 \\
      --ir-intrinsics cam0_ir.toml --color-intrinsics cam0_color.yaml --name cam0 --out cam0.toml
  bodyseg calibrate world --rig cam0.toml --rig cam1.toml --rig cam2.toml --floor views/floor \\
      --board 9x6 --square-m 0.1 --out rig.toml";

/// The board flags shared by the calibrate commands.
#[derive(Debug, Args)]
pub struct BoardArgs {
    /// Inner corners of the chessboard per row x per column (a board of 10x7 squares is 9x6)
    #[arg(long, value_name = "COLSxROWS", value_parser = parse_board)]
    pub board: [u32; 2],

    /// Side of one square of the board, metres (measure the print)
    #[arg(long, value_name = "M")]
    pub square_m: f64,
}

fn parse_board(text: &str) -> std::result::Result<[u32; 2], String> {
    Board::parse_inner_corners(text).map_err(|e| e.to_string())
}

impl BoardArgs {
    fn board(&self) -> Result<Board> {
        Ok(Board::new(self.board, self.square_m)?)
    }
}

/// `bodyseg calibrate intrinsics`.
#[derive(Debug, Args)]
pub struct CalibrateIntrinsicsArgs {
    /// Folder of the sensor's chessboard views (PNG or JPEG, all the same size)
    #[arg(long, value_name = "DIR")]
    pub images: PathBuf,

    #[command(flatten)]
    pub board: BoardArgs,

    /// Intrinsics file to write: .toml, or OpenCV FileStorage .yaml, .yml or .xml
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

impl CalibrateIntrinsicsArgs {
    /// The pipeline's options.
    pub fn options(&self) -> Result<IntrinsicsCalibOptions> {
        Ok(IntrinsicsCalibOptions {
            images: self.images.clone(),
            board: self.board.board()?,
            out: self.out.clone(),
        })
    }
}

/// `bodyseg calibrate stereo`.
#[derive(Debug, Args)]
pub struct CalibrateStereoArgs {
    /// Folder of the IR (depth sensor) views
    #[arg(long, value_name = "DIR")]
    pub ir: PathBuf,

    /// Folder of the colour views; each pairs with the IR view of the same file stem
    #[arg(long, value_name = "DIR")]
    pub color: PathBuf,

    #[command(flatten)]
    pub board: BoardArgs,

    /// IR intrinsics (.toml from `calibrate intrinsics`, or OpenCV .yaml/.yml/.xml)
    /// [default: calibrated from the IR views]
    #[arg(long, value_name = "FILE")]
    pub ir_intrinsics: Option<PathBuf>,

    /// Colour intrinsics [default: calibrated from the colour views]
    #[arg(long, value_name = "FILE")]
    pub color_intrinsics: Option<PathBuf>,

    /// Keep the intrinsics as given (or as calibrated from each folder) instead of refining
    /// them together with colour-from-depth
    #[arg(long)]
    pub fix_intrinsics: bool,

    /// Camera name in the rig [default: the folder holding the IR folder]
    #[arg(long, value_name = "NAME")]
    pub name: Option<String>,

    /// The one-camera rig.toml to write
    #[arg(long, value_name = "RIG.toml")]
    pub out: PathBuf,
}

impl CalibrateStereoArgs {
    /// The pipeline's options.
    pub fn options(&self) -> Result<StereoCalibOptions> {
        Ok(StereoCalibOptions {
            ir: self.ir.clone(),
            color: self.color.clone(),
            board: self.board.board()?,
            ir_intrinsics: self.ir_intrinsics.clone(),
            color_intrinsics: self.color_intrinsics.clone(),
            fix_intrinsics: self.fix_intrinsics,
            name: self.name.clone(),
            out: self.out.clone(),
        })
    }
}

/// `bodyseg calibrate world`.
#[derive(Debug, Args)]
pub struct CalibrateWorldArgs {
    /// Rig file(s) with the cameras to place (from `calibrate stereo` or `rig import`);
    /// repeat for several, the rig order is the order given
    #[arg(long = "rig", value_name = "RIG.toml", required = true)]
    pub rigs: Vec<PathBuf>,

    /// Folder of the floor views: <camera name>/ir.png and/or <camera name>/color.png
    #[arg(long, value_name = "DIR")]
    pub floor: PathBuf,

    #[command(flatten)]
    pub board: BoardArgs,

    /// The rig.toml to write
    #[arg(long, value_name = "RIG.toml")]
    pub out: PathBuf,
}

impl CalibrateWorldArgs {
    /// The pipeline's options.
    pub fn options(&self) -> Result<WorldCalibOptions> {
        Ok(WorldCalibOptions {
            rigs: self.rigs.clone(),
            floor: self.floor.clone(),
            board: self.board.board()?,
            out: self.out.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// `bodyseg BASE EXTRA` as clap parses it (a test's fixed words, then the case's).
    fn try_parse(base: &[&str], extra: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(["bodyseg"].iter().chain(base).chain(extra))
    }

    /// The command `bodyseg BASE EXTRA` parses into; panics when clap refuses the line.
    fn parsed(base: &[&str], extra: &[&str]) -> Command {
        try_parse(base, extra).expect("valid command line").command
    }

    /// The configuration `bodyseg refine --cloud c.ply --boxes b.json --out o.ply EXTRA`
    /// resolves to.
    fn refine_config(extra: &[&str]) -> Result<PipelineConfig> {
        let files = [
            "refine", "--cloud", "c.ply", "--boxes", "b.json", "--out", "o.ply",
        ];
        let Command::Refine(r) = parsed(&files, extra) else {
            panic!("parsed as refine");
        };
        r.config()
    }

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn project_mode_flag_overrides_the_config() {
        let parse = |extra: &[&str]| {
            let Command::Project(p) = parsed(
                &[
                    "project",
                    "--recording",
                    "rec",
                    "--frame",
                    "000012",
                    "--out",
                    "o.ply",
                ],
                extra,
            ) else {
                panic!("parsed as project");
            };
            p.options().expect("valid options")
        };
        assert_eq!(parse(&[]).config.project.mode, ProjectMode::Dsa);
        let o = parse(&["--mode", "naive", "--ascii"]);
        assert_eq!(o.config.project.mode, ProjectMode::Naive);
        assert!(o.ascii);
        assert_eq!(o.frame, "000012");
        assert!(
            try_parse(
                &[
                    "project",
                    "--recording",
                    "r",
                    "--frame",
                    "f",
                    "--mode",
                    "x",
                    "--out",
                    "o"
                ],
                &[]
            )
            .is_err()
        );
    }

    #[test]
    fn boxes_takes_a_cloud_or_a_recording_frame() {
        let parse = |args: &[&str]| try_parse(&["boxes", "--out", "b.json"], args);
        let Ok(Cli {
            command: Command::Boxes(b),
            ..
        }) = parse(&["--cloud", "c.pcd", "--mode", "geometry"])
        else {
            panic!("parsed as boxes");
        };
        let o = b.options().expect("valid");
        assert_eq!(o.config.boxes.mode, bodyseg_pipeline::BoxMode::Geometry);
        assert_eq!(o.input, bodyseg_pipeline::BoxesInput::Cloud("c.pcd".into()));
        assert!(parse(&["--recording", "rec", "--frame", "000001"]).is_ok());
        // An input is required; --recording needs --frame; not both inputs.
        assert!(parse(&[]).is_err());
        assert!(parse(&["--recording", "rec"]).is_err());
        assert!(parse(&["--cloud", "c.ply", "--recording", "rec", "--frame", "1"]).is_err());
    }

    #[test]
    fn named_predictions_split_at_the_first_equals_sign() {
        assert_eq!(
            split_named("M-R-N=out/a.ply"),
            (Some("M-R-N".into()), "out/a.ply".into())
        );
        assert_eq!(split_named("out/a.ply"), (None, "out/a.ply".into()));
        assert_eq!(split_named("./a=b.ply"), (None, "./a=b.ply".into()));
        assert_eq!(split_named("=b.ply"), (None, "=b.ply".into()));
    }

    #[test]
    fn flags_override_the_defaults() {
        let flags = ["--steps", "m,n", "--eps-m", "0.03", "--min-points", "5"];
        let c = refine_config(&flags).expect("valid config");
        assert_eq!(c.refine.eps_m, 0.03);
        assert_eq!(c.refine.min_points, 5);
        assert_eq!(c.refine.steps.to_string(), "M-N");
        assert!(!c.refine.keep_outside_boxes);
    }

    #[test]
    fn config_files_layer_set_beats_them_and_flags_beat_set() {
        let dir = tempfile::tempdir().expect("temp dir");
        let a = dir.path().join("a.toml");
        let b = dir.path().join("b.toml");
        std::fs::write(&a, "[refine]\neps_m = 0.02\nmin_points = 7\n").expect("write");
        std::fs::write(&b, "[refine]\neps_m = 0.04\n").expect("write");
        let (a, b) = (a.display().to_string(), b.display().to_string());
        let c = refine_config(&["--config", &a, "--config", &b]).expect("valid");
        assert_eq!(
            (c.refine.eps_m, c.refine.min_points),
            (0.04, 7),
            "later file wins"
        );
        let c = refine_config(&["--config", &a, "--config", &b, "--set", "refine.eps_m=0.06"])
            .expect("valid");
        assert_eq!(c.refine.eps_m, 0.06, "--set beats the files");
        let c = refine_config(&[
            "--set",
            "refine.eps_m=0.06",
            "--eps-m",
            "0.03",
            "--set",
            "refine.min_points=5",
        ])
        .expect("valid");
        assert_eq!(
            (c.refine.eps_m, c.refine.min_points),
            (0.03, 5),
            "flags beat --set"
        );
        let e = format!(
            "{:#}",
            refine_config(&["--set", "refine.min_pts=5"]).expect_err("unknown")
        );
        assert!(e.contains("unknown key `refine.min_pts`"), "{e}");

        // Every command that reads the configuration takes them.
        let Command::Run(r) = parsed(
            &[
                "run",
                "--recording",
                "r",
                "--out",
                "o",
                "--config",
                &a,
                "--set",
                "project.mode=naive",
                "--mode",
                "dsa",
                "--set",
                "boxes.mode=geometry",
            ],
            &[],
        ) else {
            panic!("parsed as run");
        };
        let o = r.options().expect("valid");
        assert_eq!(
            o.config.project.mode,
            ProjectMode::Dsa,
            "--mode beats --set"
        );
        assert_eq!(o.config.boxes.mode, bodyseg_pipeline::BoxMode::Geometry);
        assert_eq!(o.config.refine.min_points, 7);
        for command in [
            &["parse", "--recording", "r", "--frame", "f", "--out", "o"][..],
            &["project", "--recording", "r", "--frame", "f", "--out", "o"],
            &["boxes", "--cloud", "c.ply", "--out", "o"],
            &[
                "convert",
                "--input",
                "i",
                "--format",
                "recording",
                "--out",
                "o",
            ],
        ] {
            let settings = ["--config", &a, "--set", "parsing.threads=3"];
            assert!(try_parse(command, &settings).is_ok(), "{command:?}");
        }
    }

    #[test]
    fn negative_radius_parses_and_is_rejected_naming_the_flag() {
        // clap takes the negative number as the flag's value.
        let e = format!(
            "{:#}",
            refine_config(&["--eps-m", "-1"]).expect_err("invalid")
        );
        assert_eq!(e, "--eps-m: refine.eps_m must be in (0, 5] metres, got -1");
    }

    #[test]
    fn rig_import_takes_folders_and_names_in_order() {
        let Command::Rig(RigCommand::Import(r)) = parsed(
            &[
                "rig",
                "import",
                "--from",
                "iai_kinect2",
                "a",
                "b",
                "--name",
                "left",
                "--name",
                "right",
                "--out",
                "rig.toml",
            ],
            &[],
        ) else {
            panic!("parsed as rig import");
        };
        let o = r.options().expect("valid options");
        let formats: Vec<RigFormat> = o.inputs.iter().map(|i| i.format).collect();
        assert_eq!(formats, [RigFormat::IaiKinect2; 2]);
        let paths: Vec<&PathBuf> = o.inputs.iter().map(|i| &i.path).collect();
        assert_eq!(paths, [&PathBuf::from("a"), &PathBuf::from("b")]);
        assert_eq!(o.names, ["left", "right"]);
        assert!(!o.world_from_depth_identity);
        // A folder is required, and so is a known format.
        assert!(
            try_parse(
                &["rig", "import", "--from", "iai_kinect2", "--out", "r"],
                &[]
            )
            .is_err()
        );
        assert!(try_parse(&["rig", "import", "--from", "x", "a", "--out", "r"], &[]).is_err());
    }

    #[test]
    fn rig_import_pairs_formats_with_inputs() {
        let parse = |args: &[&str]| {
            let Command::Rig(RigCommand::Import(r)) =
                parsed(&["rig", "import", "--out", "rig.toml"], args)
            else {
                panic!("parsed as rig import");
            };
            r.options()
        };
        let o = parse(&[
            "--from",
            "iai_kinect2",
            "--from",
            "ros",
            "--from",
            "azure_kinect",
            "k/0113",
            "d.yaml,c.yaml",
            "k4a.json",
            "--poses",
            "camera_poses.yaml",
            "--depth-mode",
            "nfov_unbinned",
            "--color-resolution",
            "1080P",
        ])
        .expect("valid");
        assert_eq!(
            o.inputs,
            [
                RigInput {
                    format: RigFormat::IaiKinect2,
                    path: "k/0113".into(),
                    color: None
                },
                RigInput {
                    format: RigFormat::Ros,
                    path: "d.yaml".into(),
                    color: Some("c.yaml".into())
                },
                RigInput {
                    format: RigFormat::AzureKinect,
                    path: "k4a.json".into(),
                    color: None
                },
            ]
        );
        assert_eq!(o.poses, Some(PathBuf::from("camera_poses.yaml")));
        assert_eq!(o.azure_mode.depth, Some(AzureDepthMode::NfovUnbinned));
        assert_eq!(o.azure_mode.color, Some(AzureColorResolution::R1080p));
        // One-sensor formats take a single file too; a comma only splits for them.
        let o = parse(&["--from", "opencv", "rgbd.yaml"]).expect("valid");
        assert_eq!(o.inputs[0].color, None);
        let o = parse(&["--from", "iai_kinect2", "a,b"]).expect("valid");
        assert_eq!(o.inputs[0].path, PathBuf::from("a,b"));
        let e = parse(&["--from", "ros", "--from", "ros", "a", "b", "c"]).expect_err("2 for 3");
        assert!(e.to_string().starts_with("2 --from for 3 INPUTs"), "{e}");
        let e = parse(&["--from", "ros", "a", "--depth-mode", "WFOV_UNBINNED"])
            .expect_err("Azure option without Azure input");
        assert!(e.to_string().contains("azure_kinect only"), "{e}");
        let cli = try_parse(
            &[
                "rig",
                "import",
                "--from",
                "azure_kinect",
                "a.json",
                "--depth-mode",
                "NFOV",
                "--out",
                "r",
            ],
            &[],
        );
        let err = cli.expect_err("unknown mode").to_string();
        assert!(err.contains("NFOV_UNBINNED"), "{err}");
    }

    #[test]
    fn eval_names_predictions() {
        let parse = |args: &[&str]| {
            let Command::Eval(e) = parsed(&["eval", "--gt", "g.ply"], args) else {
                panic!("parsed as eval");
            };
            e.options()
        };
        let o = parse(&["--pred", "p.ply"]).expect("valid");
        assert_eq!(o.predictions[0].name, "prediction");
        let o = parse(&["--pred", "p.ply", "--name", "M-R-N"]).expect("valid");
        assert_eq!(o.predictions[0].name, "M-R-N");
        let o = parse(&["--pred", "R=a.ply", "--pred", "M=b.ply"]).expect("valid");
        assert_eq!(o.predictions[1].name, "M");
        assert!(parse(&["--pred", "a.ply", "--pred", "M=b.ply"]).is_err());
        assert!(try_parse(&["eval", "--merge", "a.json", "--gt", "g"], &[]).is_err());
        assert!(try_parse(&["eval", "--merge", "a.json", "b.json"], &[]).is_ok());
        assert!(try_parse(&["eval", "--pred", "a.ply"], &[]).is_err());
    }
}

const RUN_LONG_ABOUT: &str = "\
Run every frame of a recording (shared/FORMATS.md) through the whole pipeline: 2D labels \
(the recording's parsing/ images, or the ONNX model on the colour images) -> DSA-aware \
projection -> person boxes -> clustering refinement -> outputs -> evaluation against the \
recording's ground truth (depth_labels/) when it has one.

Writes into OUT: clouds/<frame>.ply (refined, refine.steps), boxes/<frame>.json, \
labels/<camera>/<frame>.png (refined labels drawn back into each colour image; class ids, \
255 = no point), with --write-stages stages/<frame>/projected.ply and one cloud per \
configuration (M, N, M-N, M-R-N), figures/<frame>.png (input, clusters, M, N, M-N, M-R-N, \
truth, from one viewpoint), frames/<frame>.json (per-frame record), report.md and \
report.json (the paper's table: Reference, M, N, M-N, M-R-N), config.resolved.toml and \
run.json (counts, failures, times).

Frames run in parallel, one frame in memory per worker. Every file is written atomically \
and a frame's record last: a second run into the same OUT skips the frames that are \
complete, so an interrupted run is finished by running it again. A frame that fails (a \
corrupt image, say) is reported and skipped; the others are written.

Exit status: 0 when every frame was written, 3 when some frames failed (listed in \
report.md and run.json), 1 on an error that stops the run, 2 for a bad command line.";

const RUN_EXAMPLES: &str = "\
Examples:
  bodyseg synth --preset handover --frames 20 --out rec && bodyseg run --recording rec --out run1
  bodyseg run --recording rec --out run1 --parser model --write-stages --figure 000004 --figure 000010
  bodyseg run --recording rec --out run_naive --mode naive --limit 5
  bodyseg run --recording rec --out run_geo --config configs/benchmarks/improved.toml --set boxes.mode=geometry
  bodyseg run --recording rec --out run1 --shard 1/4   # a quarter of the frames";

/// `--parser`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ParserArg {
    /// The recording's parsing/ images when it has them, else the model
    Auto,
    /// The ONNX model on the colour images
    Model,
    /// The recording's parsing/ images (recorded predictions)
    Recorded,
}

/// Options shared by `run` and `convert`: configuration and the frame loop.
#[derive(Debug, Args)]
pub struct BatchArgs {
    #[command(flatten)]
    pub config: ConfigArgs,

    /// Projection: naive or dsa [default: project.mode of the configuration, dsa]
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,

    /// Refinement steps of the written clouds, e.g. M-R-N, m,n or reference [default:
    /// refine.steps, M-R-N]
    #[arg(long, value_name = "STEPS")]
    pub steps: Option<Steps>,

    /// Where 2D labels come from
    #[arg(long, value_enum, default_value = "auto")]
    pub parser: ParserArg,

    /// SCHP-contract ONNX model for --parser model (sidecar: same path with .json);
    /// selects parsing.segmenter = "onnx" [default: parsing.segmenter, "blazepose"]
    #[arg(long, value_name = "FILE.onnx")]
    pub model: Option<PathBuf>,

    /// Do only part of the frames: K/N takes every frame whose position in the sorted
    /// frame list modulo N is K (0 <= K < N), e.g. a Slurm array task id and the array size
    #[arg(long, value_name = "K/N")]
    pub shard: Option<bodyseg_pipeline::Shard>,

    /// Redo frames that are already complete in OUT
    #[arg(long)]
    pub force: bool,

    /// Also write the projected cloud and one cloud per configuration (stages/)
    #[arg(long)]
    pub write_stages: bool,

    /// Also log every frame processed into a Rerun recording (open it with `rerun
    /// FILE.rrd`): cameras, images, 2D labels, clouds, person boxes, scores. Needs a build
    /// with `--features rerun`; convert: one recording only
    #[arg(long, value_name = "FILE.rrd")]
    pub rerun: Option<PathBuf>,

    /// With --rerun: also log the refinement's clusters (`world/clusters`, one colour per
    /// cluster; a third copy of each cloud, so off by default)
    #[arg(long, requires = "rerun")]
    pub rerun_clusters: bool,
}

impl BatchArgs {
    /// The resolved configuration: defaults < --config < --set < flags, validated.
    pub fn config(&self) -> Result<PipelineConfig> {
        let mut config = self.config.load()?;
        config.apply_project_mode(self.mode.map(ProjectMode::from));
        config.apply_refine_overrides(&RefineOverrides {
            steps: self.steps,
            ..RefineOverrides::default()
        })?;
        if let Some(model) = &self.model {
            config.parsing.model = model.display().to_string();
            config.parsing.segmenter = bodyseg_pipeline::SegmenterKind::Onnx;
        }
        Ok(config)
    }

    /// `--parser`.
    pub fn parser(&self) -> ParserChoice {
        match self.parser {
            ParserArg::Auto => ParserChoice::Auto,
            ParserArg::Model => ParserChoice::Model,
            ParserArg::Recorded => ParserChoice::Recorded,
        }
    }
}

/// `bodyseg run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Recording folder: rig.toml, per camera depth/ and parsing/ or color/, optional
    /// ground truth depth_labels/
    #[arg(long, value_name = "REC")]
    pub recording: PathBuf,

    /// Output folder (created; complete frames in it are skipped)
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,

    #[command(flatten)]
    pub batch: BatchArgs,

    /// Run only this frame (file stem; repeatable) [default: every frame]
    #[arg(long = "frame", value_name = "STEM")]
    pub frames: Vec<String>,

    /// Run only the first N frames (after --frame)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub limit: Option<u32>,

    /// Draw a figure for this frame (repeatable); `none` for no figure [default: the
    /// middle frame]
    #[arg(long = "figure", value_name = "STEM")]
    pub figures: Vec<String>,

    /// Do not draw the refined labels back into the colour images (labels/)
    #[arg(long)]
    pub no_label_images: bool,
}

impl RunArgs {
    /// The pipeline's options (the frame list is completed by `limit`).
    pub fn options(&self) -> Result<RunOptions> {
        let figures = if self.figures.iter().any(|f| f == "none") {
            if self.figures.len() > 1 {
                bail!("--figure none cannot be combined with frames");
            }
            FigureChoice::Off
        } else if self.figures.is_empty() {
            FigureChoice::Middle
        } else {
            FigureChoice::Frames(self.figures.clone())
        };
        Ok(RunOptions {
            recording: self.recording.clone(),
            config: self.batch.config()?,
            out: self.out.clone(),
            parser: self.batch.parser(),
            frames: (!self.frames.is_empty()).then(|| self.frames.clone()),
            limit: self.limit.map(|n| n as usize),
            shard: self.batch.shard.unwrap_or_default(),
            write_stages: self.batch.write_stages,
            figures,
            label_images: !self.no_label_images,
            redo: self.batch.force,
            rerun: self.batch.rerun.clone(),
            rerun_clusters: self.batch.rerun_clusters,
        })
    }
}

const CONVERT_LONG_ABOUT: &str = "\
Convert a whole dataset into labelled point clouds, resumably and in shards.

--format recording: INPUT is one recording or a folder of recordings (each a folder with \
rig.toml). Every frame goes through the pipeline as in `bodyseg run` (without figures and \
label images) into OUT/<recording>/: clouds/, boxes/, frames/, and per recording \
report.md / report.json when it has ground truth.

--format 3dpeople: INPUT is a 3DPeople dataset (rgb/<subject>/<sequence>/cameraNN/*.jpg, \
depth_mat/..., segmentation_body/...). Every view becomes OUT/clouds/<view>.ply: the depth \
back-projected (camera frame turned z-up), each point labelled by the body-part \
segmentation (14 parts mapped to the 7 classes) and coloured by the RGB image.

Resumable: a frame whose outputs exist and are complete is skipped, so a stopped \
conversion is finished by running it again. One bad frame is reported and skipped. With \
--shard K/N many processes (machines) split the frames deterministically; each writes \
report.shard-K-of-N.json, which `bodyseg eval --merge` sums (see scripts/slurm/).

Exit status: 0 when every frame was converted, 3 when some failed (listed in \
report*.md and run*.json), 1 on an error that stops the conversion.";

const CONVERT_EXAMPLES: &str = "\
Examples:
  bodyseg convert --input recs/ --format recording --out converted
  bodyseg convert --input recs/ --format recording --out converted --shard 3/8
  bodyseg eval --merge converted/*/report.shard-*.json --format md
  bodyseg convert --input 3DPeople/ --format 3dpeople --out 3dpeople_clouds";

/// `--format` of `bodyseg convert`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DatasetFormat {
    /// bodyseg recordings (shared/FORMATS.md): one, or a folder of them
    Recording,
    /// The 3DPeople dataset layout
    #[value(name = "3dpeople")]
    ThreeDPeople,
}

/// `bodyseg convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The dataset folder
    #[arg(long, value_name = "DATASET")]
    pub input: PathBuf,

    /// The dataset's layout
    #[arg(long, value_enum)]
    pub format: DatasetFormat,

    /// Output folder (created; complete frames in it are skipped)
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,

    #[command(flatten)]
    pub batch: BatchArgs,

    /// 3dpeople: image size and pinhole intrinsics of the aligned images, pixels, as
    /// W,H,FX,FY,CX,CY [default: 640,480,700,700,320,240]
    #[arg(long, value_name = "W,H,FX,FY,CX,CY", value_parser = parse_intrinsics)]
    pub intrinsics: Option<[f64; 6]>,

    /// 3dpeople: metres per depth.mat unit (0.1 if the depth is in decimetres) [default: 1]
    #[arg(long, value_name = "METRES")]
    pub depth_scale_m: Option<f64>,
}

/// `W,H,FX,FY,CX,CY`.
fn parse_intrinsics(s: &str) -> Result<[f64; 6], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected six numbers W,H,FX,FY,CX,CY, got {s:?}"))?;
    let v: [f64; 6] = v
        .try_into()
        .map_err(|_| format!("expected six numbers W,H,FX,FY,CX,CY, got {s:?}"))?;
    for (i, name) in [(0, "W"), (1, "H")] {
        if v[i] < 1.0 || v[i].fract() != 0.0 || v[i] > f64::from(u32::MAX) {
            return Err(format!(
                "{name} must be a whole number of pixels >= 1, got {}",
                v[i]
            ));
        }
    }
    Ok(v)
}

impl ConvertArgs {
    /// The pipeline's options.
    pub fn options(&self) -> Result<ConvertOptions> {
        Ok(ConvertOptions {
            input: self.input.clone(),
            format: match self.format {
                DatasetFormat::Recording => ConvertFormat::Recording,
                DatasetFormat::ThreeDPeople => ConvertFormat::ThreeDPeople,
            },
            config: self.batch.config()?,
            out: self.out.clone(),
            parser: self.batch.parser(),
            shard: self.batch.shard.unwrap_or_default(),
            write_stages: self.batch.write_stages,
            redo: self.batch.force,
            rerun: self.batch.rerun.clone(),
            rerun_clusters: self.batch.rerun_clusters,
            camera_3dpeople: {
                let mut camera = match self.intrinsics {
                    Some([w, h, fx, fy, cx, cy]) => {
                        ThreeDPeopleCamera::pinhole(w as u32, h as u32, fx, fy, cx, cy)
                    }
                    None => ThreeDPeopleCamera::default(),
                };
                if let Some(scale) = self.depth_scale_m {
                    camera.depth_scale_m = scale;
                }
                camera
            },
        })
    }
}
