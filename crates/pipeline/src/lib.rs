//! bodyseg-pipeline: the commands behind the `bodyseg` binary, as plain functions, and the
//! stage types that carry one frame of a recording through them.
//!
//! Place in the pipeline: the only crate (with the binary and the study crate, lab) that
//! sees every stage. It loads the [`PipelineConfig`], reads the inputs with bodyseg-io,
//! calls the stages in order and writes the outputs.
//!
//! # Commands
//! Each takes an options struct and returns a summary with per-stage timings ([`Stage`])
//! for the binary to print; no command-line parsing here (that is `crates/cli`).
//!
//! ```text
//! synth_recording: scene + seed → a synthetic recording with ground truth (RecordingWriter)
//! parse_file:      recording frame (colour images) → Segmenter → label PNGs + previews
//! project_file:    recording frame (depth + parsing PNGs) → labelled world-frame PLY
//! boxes_file:      cloud PLY/PCD (any frame: its floor found) or recording frame → bodyseg_people::find_boxes → boxes JSON (+ preview)
//! refine_file:     cloud PLY + boxes JSON → bodyseg_refine::refine → refined PLY
//! eval_files:      predicted PLY(s) + ground-truth PLY → Report;  merge_reports: reports → Report
//! run_recording:   a recording, every frame through every stage → clouds, boxes, label images, report
//! convert_dataset: recordings or 3DPeople, resumable and sharded → clouds (+ reports)
//! import_ros2:     a ROS 2 bag (MCAP) → bodyseg_ros2 (scan, plan, decode) → a recording
//! import_cloud:    organised clouds (PCD, PLY) → a one-camera recording (grid-fitted intrinsics, floor-given world frame)
//! view_run:        a recording + a finished run's files → a Rerun recording (.rrd; feature `rerun`,
//!                  as `--rerun` on run_recording / convert_dataset)
//! import_rig, read_rig, describe_rig: calibration files (iai_kinect2, Azure Kinect, ROS, OpenCV;
//!                  OpenPTrack poses) ⇄ rig.toml
//! calibrate_*:     chessboard images → intrinsics, colour-from-depth, world poses (feature `opencv`)
//! ```
//!
//! # Stage types
//! `bodyseg run` streams a recording through them, one frame per worker
//! ([`FrameProcessor`]):
//!
//! ```text
//! Recording ─ Frame::read → Frame (images) ─ parse_frame (Segmenter) → ParsedFrame (label maps)
//!   → LabeledCloud (bodyseg-project) → PersonBoxes (bodyseg-people) → RefinedCloud
//!   (bodyseg-refine) → Report (bodyseg-eval)
//! ```
//!
//! [`Recording`] is the recording layout (FORMATS.md "Recording"): its rig, its frames
//! and the path and reader of every [`Layer`]; [`RecordingWriter`] writes one.
//!
//! # Conventions
//! - Errors are [`anyhow::Error`]s whose chain (`{:#}`) reads as one line naming the file,
//!   and the vertex, box or configuration field at fault.
//! - Every file is written atomically (bodyseg-io's `write_atomic`): a failed command
//!   leaves no output file behind and an existing one untouched.
//! - Configuration precedence: built-in defaults ([`PipelineConfig::default`], equal to
//!   `configs/default.toml`) < configuration files < `--set` < command-line flags.
//! - Units are those of the stages: metres, radians; times are wall-clock.

mod allocator;
mod batch;
mod boxes;
mod calibrate;
mod config;
mod convert;
mod eval;
mod figure;
mod floor;
mod frame;
mod import_cloud;
mod import_ros2;
mod layers;
mod model;
mod outputs;
mod parse;
mod processor;
mod project;
mod recording;
mod refine;
pub mod regions;
mod report;
mod rig;
mod run;
mod sanity;
mod stage;
mod synth;
mod threedpeople;
mod view;
mod viewer;

pub use allocator::keep_freed_memory;
pub use batch::{
    BatchOutcome, BatchProgress, FrameFailure, FrameRecord, FrameScores, FrameWriter, InputFile,
    OutputFile, Shard,
};
pub use bodyseg_calib::{AzureColorResolution, AzureDepthMode, AzureKinectMode, Board};
pub use bodyseg_parsing::SegmenterKind;
pub use bodyseg_people::{BoxMode, Floor, FloorHint, Up};
pub use bodyseg_project::ProjectMode;
pub use boxes::{BoxesInput, BoxesOptions, BoxesSummary, boxes_file, top_view};
pub use calibrate::{
    CalibrateSummary, IntrinsicsCalibOptions, StereoCalibOptions, ViewReport, WorldCalibOptions,
    calibrate_intrinsics, calibrate_stereo, calibrate_world,
};
pub use config::{BackProjectConfig, PipelineConfig, RefineOverrides};
pub use convert::{ConvertFormat, ConvertOptions, ConvertSummary, convert_dataset};
pub use eval::{
    DEFAULT_PREDICTION_NAME, EvalOptions, EvalSummary, NamedPrediction, ReportFormat, eval_files,
    merge_reports, render_report,
};
pub use frame::{Frame, FrameNeeds, ParsedFrame, parse_frame};
pub use import_cloud::{
    GridFit, ImportCloudOptions, ImportCloudSummary, MAX_GRID_RMS_PX, import_cloud,
};
pub use import_ros2::{Ros2ImportOptions, Ros2ImportSummary, import_ros2};
pub use model::{FoundBy, ParserChoice, describe_parser_files};
pub use outputs::{check_output_file, check_output_folder, write_text};
pub use parse::{ParseOptions, ParseSource, ParseSummary, parse_file};
pub use processor::FrameProcessor;
pub use project::{ProjectOptions, ProjectSummary, project_file};
pub use recording::{FrameList, Layer, Recording, RecordingWriter, Sensor};
pub use refine::{RefineOptions, RefineSummary, refine_file};
pub use report::RunSummary;
pub use rig::{
    RigFormat, RigImportOptions, RigImportSummary, RigInput, describe_rig, import_rig, read_rig,
};
pub use run::{FigureChoice, RunOptions, run_recording};
pub use stage::Stage;
pub use synth::{SceneSource, SynthOptions, SynthSummary, synth_recording};
pub use threedpeople::{
    ThreeDPeopleCamera, ThreeDPeopleView, list_3dpeople_views, read_3dpeople_view,
};
pub use view::{ViewOptions, ViewSummary, view_run};
