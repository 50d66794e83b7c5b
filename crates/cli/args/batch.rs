//! What `run` and `convert` share (configuration, projection mode, the frame loop), and
//! their arguments; `--config`/`--set` and `--mode` of every command.

use anyhow::{Result, bail};
use bodyseg_pipeline::{
    ConvertFormat, ConvertOptions, FigureChoice, ParserChoice, PipelineConfig, ProjectMode,
    RefineOverrides, RunOptions, ThreeDPeopleCamera,
};
use bodyseg_refine::Steps;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

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

    /// [`ConfigArgs::load`], then `--mode` over `project.mode` when given.
    pub fn load_with_mode(&self, mode: Option<Mode>) -> Result<PipelineConfig> {
        let mut config = self.load()?;
        config.apply_project_mode(mode.map(ProjectMode::from));
        Ok(config)
    }
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

pub(super) const RUN_LONG_ABOUT: &str = "\
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

pub(super) const RUN_EXAMPLES: &str = "\
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
        let mut config = self.config.load_with_mode(self.mode)?;
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

pub(super) const CONVERT_LONG_ABOUT: &str = "\
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

pub(super) const CONVERT_EXAMPLES: &str = "\
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
