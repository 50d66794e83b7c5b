//! Command-line arguments (clap derive) and their translation into bodyseg-pipeline's
//! option structs. No work happens here.

use anyhow::{Result, bail};
use bodyseg_pipeline::{
    DEFAULT_PREDICTION_NAME, EvalOptions, NamedPrediction, ParseOptions, ParseSource,
    PipelineConfig, ProjectOptions, RefineOptions, RefineOverrides, ReportFormat, SceneSource,
    SynthOptions,
};
use bodyseg_refine::Steps;
use bodyseg_synth::ChessboardConfig;
use clap::{ArgAction, Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

mod batch;
mod calib;
mod floor;
mod import;
#[cfg(test)]
mod tests;
pub use batch::*;
use batch::{CONVERT_EXAMPLES, CONVERT_LONG_ABOUT, RUN_EXAMPLES, RUN_LONG_ABOUT};
use calib::CALIBRATE_LONG_ABOUT;
pub use calib::*;
pub use floor::*;
pub use import::*;

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

const PARSE_LONG_ABOUT: &str = "\
Run 2D human parsing on every camera of one frame: each colour image is mapped into the \
network's square input (SCHP's affine pre-processing: aspect kept, centred, black padding), \
all views go through the ONNX model in one batch, and the logits are warped back to the \
image, where each pixel takes the most probable class (shared/ALGORITHM.md §2).

Model: --model FILE.onnx with its sidecar FILE.json (input_size, channel_order, mean, std, \
class_names, output_stride, align_corners), or parsing.model of the configuration; default \
BlazePose (parsing.segmenter = blazepose, models/blazepose_full.onnx) on the people \
found from depth, with body parts from BodyPix (parsing.body_parts = bodypix, \
models/bodypix_mobilenet_v1_075_quant.onnx; landmarks: BlazePose's alone); parsing.segmenter = onnx without a model runs the bundled \
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

impl ProjectArgs {
    /// The resolved configuration: defaults < --config < --set < --mode, validated.
    pub fn config(&self) -> Result<PipelineConfig> {
        self.config.load_with_mode(self.mode)
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
