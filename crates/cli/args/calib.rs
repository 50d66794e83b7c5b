//! `bodyseg rig ...` and `bodyseg calibrate ...`.

use anyhow::{Result, bail};
use bodyseg_pipeline::{
    AzureColorResolution, AzureDepthMode, AzureKinectMode, Board, IntrinsicsCalibOptions,
    RigFormat, RigImportOptions, RigInput, StereoCalibOptions, WorldCalibOptions,
};
use clap::{Args, Subcommand, ValueEnum};
use std::path::PathBuf;

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

pub(super) const CALIBRATE_LONG_ABOUT: &str = "\
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
