//! bodyseg-pipeline: the commands behind the `bodyseg` binary, as plain functions.
//!
//! Place in the pipeline: the only crate (with the binary) that sees every stage. It
//! loads the [`PipelineConfig`], reads the inputs with bodyseg-io, calls the stages in
//! order and writes the outputs:
//!
//! ```text
//! parse_file:    recording frame (rig.toml, colour images) → bodyseg_parsing::Segmenter → label PNGs + previews
//! project_file:  recording frame (rig.toml, depth + parsing PNGs) → bodyseg_project::project_frame → labelled PLY
//! boxes_file:    cloud PLY/PCD or recording frame → bodyseg_people::find_boxes → boxes JSON (+ preview PNG)
//! refine_file:   cloud PLY + boxes JSON → bodyseg_refine::refine → refined PLY (+ resolved config)
//! eval_files:    predicted PLY(s) + ground-truth PLY → bodyseg_eval::match_clouds → Report
//! merge_reports: report JSON files → Report::merge → Report
//! import_rig:    calibration files (iai_kinect2, Azure Kinect, ROS, OpenCV; OpenPTrack poses) → bodyseg_calib::Rig → rig.toml
//! describe_rig:  rig.toml → human-readable summary
//! calibrate_*:   chessboard images → intrinsics, colour-from-depth, world poses → rig.toml (feature `opencv`)
//! ```
//!
//! No command-line parsing here (that is `crates/cli`): each command takes an options
//! struct and returns a summary with per-stage timings ([`Stage`]) for the binary to print.
//!
//! # Conventions
//! - Errors are [`anyhow::Error`]s whose chain (`{:#}`) reads as one line naming the file,
//!   and the vertex, box or configuration field at fault.
//! - Every file is written atomically (bodyseg-io's `write_atomic`): a failed command
//!   leaves no output file behind and an existing one untouched.
//! - Configuration precedence: built-in defaults ([`PipelineConfig::default`], equal to
//!   `configs/default.toml`) < configuration file < command-line flags.
//! - Units are those of the stages: metres, radians; times are wall-clock.

mod allocator;
mod batch;
mod boxes;
mod boxes_study;
mod calibrate;
mod config;
mod convert;
mod eval;
mod figure;
mod frame_files;
mod fs;
mod parse;
mod project;
mod projection_study;
mod refine;
mod rig;
mod run;
mod stage;
mod synth;
mod threedpeople;

pub use allocator::keep_freed_memory;
pub use batch::{
    BatchFrame, BatchOutcome, BatchProgress, FrameFailure, FrameRecord, FrameWriter, InputFile,
    OutputFile, Shard, complete_record, record_path, run_batch,
};
pub use bodyseg_calib::{AzureColorResolution, AzureDepthMode, AzureKinectMode, Board};
pub use bodyseg_people::{BoxMode, BoxesConfig};
pub use bodyseg_project::ProjectMode;
pub use boxes::{
    BoxesInput, BoxesOptions, BoxesSummary, boxes_file, boxes_path, read_cloud, top_view,
};
pub use boxes_study::{
    BoxStats, FrameMatch, MATCH_IOU, box_stats, describe_box, match_boxes, study_frame,
};
pub use calibrate::{
    CALIBRATE_AVAILABLE, CalibrateSummary, IntrinsicsCalibOptions, StereoCalibOptions, ViewReport,
    WorldCalibOptions, calibrate_intrinsics, calibrate_stereo, calibrate_world,
};
pub use config::{BackProjectConfig, PipelineConfig, RefineOverrides};
pub use convert::{
    ConvertFormat, ConvertOptions, ConvertSummary, convert_dataset, list_recordings,
};
pub use eval::{
    DEFAULT_PREDICTION_NAME, EvalOptions, EvalSummary, NamedPrediction, ReportFormat, eval_files,
    merge_reports, render_report,
};
pub use figure::{FigurePanel, LabelView, PanelView, figure_image, panel_view};
pub use fs::write_text;
pub use parse::{
    BUNDLED_MODEL, LOCAL_RUNTIME_LIBRARY, ParseOptions, ParseSource, ParseSummary,
    RUNTIME_LIBRARY_ENV, color_path, load_segmenter, palette_preview, parse_file, resolve_model,
    resolve_runtime_library,
};
pub use project::{ProjectOptions, ProjectSummary, depth_path, parsing_path, project_file};
pub use projection_study::{ProjectionStats, camera_images, parsing_images, projection_stats};
pub use refine::{RefineOptions, RefineSummary, refine_file, resolved_config_path};
pub use rig::{
    RigFormat, RigImportOptions, RigImportSummary, RigInput, describe_rig, import_rig, read_rig,
};
pub use run::{
    ABLATION, FigureChoice, FrameInputs, FrameProcessor, ParserChoice, RunOptions, RunSummary,
    list_frames, run_recording,
};
pub use stage::Stage;
pub use synth::{
    SceneSource, SynthOptions, SynthSummary, load_scene, synth_chessboard, synth_recording,
    write_frame,
};
pub use threedpeople::{
    MAX_PALETTE_TOLERANCE, THREEDPEOPLE_PALETTE, ThreeDPeopleCamera, ThreeDPeopleView,
    list_3dpeople_views, read_3dpeople_view,
};
