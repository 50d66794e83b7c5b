//! Azure Kinect factory calibration JSON (`k4arecorder`'s attachment, `k4a_device_get_raw_calibration`):
//! reader and writer, mapped exactly as the Azure Kinect Sensor SDK maps it.
//!
//! ```json
//! {"CalibrationInformation": {"Cameras": [
//!   {"Location": "CALIBRATION_CameraLocationD0", "SensorWidth": 1024, "SensorHeight": 1024,
//!    "Intrinsics": {"ModelType": "CALIBRATION_LensDistortionModelBrownConrady",
//!                   "ModelParameterCount": 14, "ModelParameters": [cx, cy, fx, fy, k1, k2, k3,
//!                   k4, k5, k6, codx, cody, p2, p1]},
//!    "Rt": {"Rotation": [9 values, row-major], "Translation": [x, y, z]}},
//!   {"Location": "CALIBRATION_CameraLocationPV0", ...}]}}
//! ```
//!
//! Sources (Azure-Kinect-Sensor-SDK, `src/calibration/calibration.c`,
//! `src/transformation/mode_specific_calibration.c`, `intrinsic_transformation.c`,
//! `include/k4a/k4atypes.h` for `k4a_calibration_intrinsic_parameters_t`):
//! - Cameras are found by `Location`: `..._CameraLocationD0` is the depth sensor,
//!   `..._CameraLocationPV0` the colour sensor; others are ignored. A UTF-8 byte order
//!   mark before the JSON is ignored.
//! - `ModelParameters` hold `cx cy fx fy k1 k2 k3 k4 k5 k6 codx cody p2 p1` (and the
//!   metric radius, when 15), the first four normalised by the image size with pixel
//!   *corners* at integers. The SDK's `CALIBRATION_LensDistortionModelBrownConrady`
//!   projects with `d = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)`,
//!   `x_d = x d + (r² + 2x²) p2 + 2 x y p1`, `y_d = y d + (r² + 2y²) p1 + 2 x y p2`
//!   around the centre of distortion (codx, cody): that is OpenCV's rational model, so
//!   the reader returns [`Distortion::Rational`]`([k1, k2, p1, p2, k3, k4, k5, k6])`.
//!   codx and cody are 0 in every factory file (the SDK's own OpenCV export writes 0,
//!   "always zero for BrownConrady"); a file where they are not is refused, since the
//!   model cannot hold them. `CALIBRATION_LensDistortionModelRational6KT` (the SDK:
//!   "deprecated, only supported early internal devices") has other tangential terms
//!   (`x y p1` without the factor 2) and a centre of distortion: refused too.
//! - Pixel units, as the SDK's `transformation_get_mode_specific_camera_calibration`:
//!   for an image `W × H` binned from the sensor and cropped at `(ox, oy)`,
//!   `fx = fx_n · Wb`, `cx = cx_n · Wb − ox − 0.5` (the 0.5 moves integers from pixel
//!   corners to pixel centres, OpenCV's and bodyseg's convention), likewise y. Without a
//!   capture mode ([`AzureKinectMode`] fields `None`) the intrinsics are those of the
//!   full stored image (`SensorWidth × SensorHeight`, no binning or crop); with one, the
//!   SDK's table of that mode is used, so the intrinsics fit the images a recording in
//!   that mode holds (NFOV unbinned depth is 640×576, 1080p colour 1920×1080). A colour
//!   calibration stored for a 16:9 image (older devices) is first brought to the 4:3
//!   sensor as the SDK does.
//! - The metric radius (the SDK does not project points farther from the axis) is not
//!   kept: bodyseg's models have no such limit.
//! - `Rt` maps the depth frame (the device's reference) into each camera: the colour
//!   camera's `Rt` is `color_from_depth` (translation in metres); the depth camera's is the
//!   identity in factory files, and is honoured if it is not
//!   (`color_from_depth = colour.Rt · depth.Rt⁻¹`).
//! - `world_from_depth` is the identity, `depth_scale` 1000 (millimetres), no shift.

use std::path::Path;

use serde_json::{Value, json};

use crate::files::{read_text, without_bom, write_atomic};
use crate::{
    CalibError, DEFAULT_DEPTH_SCALE, Distortion, ImportedCamera, Intrinsics, Pose, RgbdCamera,
};

/// `Location` of the depth camera.
pub const AZURE_DEPTH_LOCATION: &str = "CALIBRATION_CameraLocationD0";
/// `Location` of the colour (photo-video) camera.
pub const AZURE_COLOR_LOCATION: &str = "CALIBRATION_CameraLocationPV0";
/// `ModelType` of the lens model this reader understands.
const BROWN_CONRADY: &str = "CALIBRATION_LensDistortionModelBrownConrady";
/// `ModelType` of the deprecated model of early devices, refused.
const RATIONAL_6KT: &str = "CALIBRATION_LensDistortionModelRational6KT";
/// Number of `ModelParameters` the model needs (a 15th, the metric radius, is ignored).
const MODEL_PARAMETER_COUNT: usize = 14;

/// Depth camera mode (`k4a_depth_mode_t`): which image of the depth sensor the
/// intrinsics describe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AzureDepthMode {
    /// `NFOV_2X2BINNED`: 320×288.
    Nfov2x2Binned,
    /// `NFOV_UNBINNED`: 640×576.
    NfovUnbinned,
    /// `WFOV_2X2BINNED`: 512×512.
    Wfov2x2Binned,
    /// `WFOV_UNBINNED`: 1024×1024.
    WfovUnbinned,
    /// `PASSIVE_IR`: 1024×1024.
    PassiveIr,
}

/// Colour camera resolution (`k4a_color_resolution_t`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AzureColorResolution {
    /// `720P`: 1280×720.
    R720p,
    /// `1080P`: 1920×1080.
    R1080p,
    /// `1440P`: 2560×1440.
    R1440p,
    /// `1536P`: 2048×1536.
    R1536p,
    /// `2160P`: 3840×2160.
    R2160p,
    /// `3072P`: 4096×3072.
    R3072p,
}

/// The SDK's `k4a_camera_calibration_mode_info_t`: the image the sensor is binned to, the
/// crop offset in it and the output size, pixels.
#[derive(Debug, Clone, Copy)]
struct ModeInfo {
    binned: [u32; 2],
    crop: [i32; 2],
    output: [u32; 2],
}

const fn mode(binned: [u32; 2], crop: [i32; 2], output: [u32; 2]) -> ModeInfo {
    ModeInfo {
        binned,
        crop,
        output,
    }
}

impl AzureDepthMode {
    /// Every mode, in the SDK's order.
    pub const ALL: [AzureDepthMode; 5] = [
        AzureDepthMode::Nfov2x2Binned,
        AzureDepthMode::NfovUnbinned,
        AzureDepthMode::Wfov2x2Binned,
        AzureDepthMode::WfovUnbinned,
        AzureDepthMode::PassiveIr,
    ];

    /// The SDK's name without `K4A_DEPTH_MODE_` (`NFOV_UNBINNED`).
    pub fn name(self) -> &'static str {
        match self {
            AzureDepthMode::Nfov2x2Binned => "NFOV_2X2BINNED",
            AzureDepthMode::NfovUnbinned => "NFOV_UNBINNED",
            AzureDepthMode::Wfov2x2Binned => "WFOV_2X2BINNED",
            AzureDepthMode::WfovUnbinned => "WFOV_UNBINNED",
            AzureDepthMode::PassiveIr => "PASSIVE_IR",
        }
    }

    /// The mode of a name as [`AzureDepthMode::name`] gives it, case-insensitive.
    pub fn from_name(name: &str) -> Option<Self> {
        named(&Self::ALL, Self::name, name)
    }

    /// `transformation_get_mode_specific_depth_camera_calibration`'s table.
    fn info(self) -> ModeInfo {
        match self {
            AzureDepthMode::Nfov2x2Binned => mode([512, 512], [96, 90], [320, 288]),
            AzureDepthMode::NfovUnbinned => mode([1024, 1024], [192, 180], [640, 576]),
            AzureDepthMode::Wfov2x2Binned => mode([512, 512], [0, 0], [512, 512]),
            AzureDepthMode::WfovUnbinned | AzureDepthMode::PassiveIr => {
                mode([1024, 1024], [0, 0], [1024, 1024])
            }
        }
    }
}

impl AzureColorResolution {
    /// Every resolution, in the SDK's order.
    pub const ALL: [AzureColorResolution; 6] = [
        AzureColorResolution::R720p,
        AzureColorResolution::R1080p,
        AzureColorResolution::R1440p,
        AzureColorResolution::R1536p,
        AzureColorResolution::R2160p,
        AzureColorResolution::R3072p,
    ];

    /// The SDK's name without `K4A_COLOR_RESOLUTION_` (`1080P`).
    pub fn name(self) -> &'static str {
        match self {
            AzureColorResolution::R720p => "720P",
            AzureColorResolution::R1080p => "1080P",
            AzureColorResolution::R1440p => "1440P",
            AzureColorResolution::R1536p => "1536P",
            AzureColorResolution::R2160p => "2160P",
            AzureColorResolution::R3072p => "3072P",
        }
    }

    /// The resolution of a name as [`AzureColorResolution::name`] gives it,
    /// case-insensitive.
    pub fn from_name(name: &str) -> Option<Self> {
        named(&Self::ALL, Self::name, name)
    }

    /// `transformation_get_mode_specific_color_camera_calibration`'s table (for a 4:3
    /// calibration).
    fn info(self) -> ModeInfo {
        match self {
            AzureColorResolution::R720p => mode([1280, 960], [0, 120], [1280, 720]),
            AzureColorResolution::R1080p => mode([1920, 1440], [0, 180], [1920, 1080]),
            AzureColorResolution::R1440p => mode([2560, 1920], [0, 240], [2560, 1440]),
            AzureColorResolution::R1536p => mode([2048, 1536], [0, 0], [2048, 1536]),
            AzureColorResolution::R2160p => mode([3840, 2880], [0, 360], [3840, 2160]),
            AzureColorResolution::R3072p => mode([4096, 3072], [0, 0], [4096, 3072]),
        }
    }
}

/// The value of `all` whose `name` is `wanted`, case-insensitive.
fn named<T: Copy>(all: &[T], name: fn(T) -> &'static str, wanted: &str) -> Option<T> {
    all.iter()
        .copied()
        .find(|&m| name(m).eq_ignore_ascii_case(wanted))
}

/// The capture mode whose images the intrinsics are for; `None`: the full image the
/// calibration is stored for (`SensorWidth × SensorHeight`, no binning, no crop).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AzureKinectMode {
    /// Depth mode of the recording, or `None`.
    pub depth: Option<AzureDepthMode>,
    /// Colour resolution of the recording, or `None`.
    pub color: Option<AzureColorResolution>,
}

/// Reads an Azure Kinect calibration JSON into a camera called `name`, with intrinsics
/// for the images of `mode` (see the module documentation).
pub fn read_azure_kinect_json(
    path: &Path,
    name: &str,
    mode: AzureKinectMode,
) -> Result<ImportedCamera, CalibError> {
    parse_azure_kinect_json(&read_text(path)?, name, path, mode)
}

struct Doc<'p> {
    path: &'p Path,
}

impl Doc<'_> {
    fn bad(&self, key: &str, reason: impl Into<String>) -> CalibError {
        CalibError::BadValue {
            key: key.to_string(),
            reason: reason.into(),
            path: self.path.to_path_buf(),
        }
    }

    fn get<'v>(&self, v: &'v Value, parent: &str, key: &str) -> Result<&'v Value, CalibError> {
        v.get(key).ok_or_else(|| CalibError::MissingKey {
            key: format!("{parent}.{key}"),
            path: self.path.to_path_buf(),
        })
    }

    fn numbers(&self, v: &Value, key: &str, min_len: usize) -> Result<Vec<f64>, CalibError> {
        let Value::Array(items) = v else {
            return Err(self.bad(key, "must be an array of numbers"));
        };
        if items.len() < min_len {
            return Err(self.bad(key, format!("needs {min_len} values, got {}", items.len())));
        }
        items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                item.as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.bad(key, format!("[{i}] = {item} is not a finite number")))
            })
            .collect()
    }

    fn size(&self, v: &Value, parent: &str, key: &str) -> Result<u32, CalibError> {
        let item = self.get(v, parent, key)?;
        item.as_u64()
            .filter(|&n| n > 0)
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| {
                self.bad(
                    &format!("{parent}.{key}"),
                    format!("must be a positive pixel count, got {item}"),
                )
            })
    }
}

/// Which sensor a camera entry is, for the pixel conversion.
#[derive(Clone, Copy)]
enum AzureSensor {
    Depth(Option<AzureDepthMode>),
    Color(Option<AzureColorResolution>),
}

/// The normalised pinhole `[cx, cy, fx, fy]` (corner-at-integer) in pixels of the
/// mode's image, and its size, as the SDK converts them.
fn to_pixels(
    doc: &Doc,
    key: &str,
    sensor: AzureSensor,
    stored: [u32; 2],
    n: [f64; 4],
) -> Result<([f64; 4], [u32; 2]), CalibError> {
    let [w, h] = stored;
    let info = match sensor {
        AzureSensor::Depth(None) | AzureSensor::Color(None) => mode(stored, [0, 0], stored),
        AzureSensor::Depth(Some(m)) => {
            if stored != [1024, 1024] {
                return Err(doc.bad(
                    &format!("{key}.SensorWidth"),
                    format!(
                        "depth mode {} needs the 1024x1024 depth calibration of a real \
                         device, the file says {w}x{h}",
                        m.name()
                    ),
                ));
            }
            m.info()
        }
        AzureSensor::Color(Some(r)) => r.info(),
    };
    let mut n = n;
    if let AzureSensor::Color(Some(r)) = sensor {
        // A calibration stored for a 16:9 image is brought to the 4:3 sensor, still
        // normalised, as the SDK does (its mode {4096x2304 binned, crop (0, -384),
        // 4096x3072 out}); integer arithmetic as the SDK's.
        if w * 9 / 16 == h {
            let legacy = mode([4096, 2304], [0, -384], [4096, 3072]);
            let [bw, bh] = legacy.binned.map(f64::from);
            let [ow, oh] = legacy.output.map(f64::from);
            let [ox, oy] = legacy.crop.map(f64::from);
            n = [
                (n[0] * bw - ox) / ow,
                (n[1] * bh - oy) / oh,
                n[2] * bw / ow,
                n[3] * bh / oh,
            ];
        } else if w * 3 / 4 != h {
            return Err(doc.bad(
                &format!("{key}.SensorWidth"),
                format!(
                    "colour resolution {} needs a 4:3 or 16:9 colour calibration, the file \
                     says {w}x{h}",
                    r.name()
                ),
            ));
        }
    }
    let [bw, bh] = info.binned.map(f64::from);
    let [ox, oy] = info.crop.map(f64::from);
    Ok((
        [
            n[0] * bw - ox - 0.5,
            n[1] * bh - oy - 0.5,
            n[2] * bw,
            n[3] * bh,
        ],
        info.output,
    ))
}

/// One camera entry: intrinsics and its `Rt` (camera_from_depth-reference).
fn read_camera(
    doc: &Doc,
    cam: &Value,
    key: &str,
    sensor: AzureSensor,
) -> Result<(Intrinsics, Pose), CalibError> {
    let width = doc.size(cam, key, "SensorWidth")?;
    let height = doc.size(cam, key, "SensorHeight")?;
    let intr_key = format!("{key}.Intrinsics");
    let intr = doc.get(cam, key, "Intrinsics")?;
    let model_key = format!("{intr_key}.ModelType");
    match doc.get(intr, &intr_key, "ModelType")?.as_str() {
        Some(BROWN_CONRADY) => {}
        Some(RATIONAL_6KT) => {
            return Err(doc.bad(
                &model_key,
                format!(
                    "{RATIONAL_6KT:?} is the SDK's deprecated model of early internal devices \
                     (tangential terms without OpenCV's factor 2, a centre of distortion): \
                     bodyseg reads only {BROWN_CONRADY:?}, the model of every retail device"
                ),
            ));
        }
        _ => {
            return Err(doc.bad(
                &model_key,
                format!(
                    "{} is not supported: bodyseg reads only {BROWN_CONRADY:?}",
                    intr["ModelType"]
                ),
            ));
        }
    }
    let params_key = format!("{intr_key}.ModelParameters");
    let p = doc.numbers(
        doc.get(intr, &intr_key, "ModelParameters")?,
        &params_key,
        MODEL_PARAMETER_COUNT,
    )?;
    for (i, label) in [(10, "codx"), (11, "cody")] {
        if p[i] != 0.0 {
            return Err(doc.bad(
                &params_key,
                format!(
                    "[{i}] ({label}, centre of distortion) = {} is not 0: OpenCV's rational \
                     model, which bodyseg uses, has its centre of distortion on the axis",
                    p[i]
                ),
            ));
        }
    }
    let ([cx, cy, fx, fy], [w, h]) =
        to_pixels(doc, key, sensor, [width, height], [p[0], p[1], p[2], p[3]])?;
    let intrinsics = Intrinsics {
        width: w,
        height: h,
        fx,
        fy,
        cx,
        cy,
        // Stored k1 k2 k3 k4 k5 k6 codx cody p2 p1; OpenCV's k1 k2 p1 p2 k3 k4 k5 k6.
        distortion: Distortion::Rational([p[4], p[5], p[13], p[12], p[6], p[7], p[8], p[9]]),
    };
    intrinsics
        .validate()
        .map_err(|e| doc.bad(&params_key, e.to_string()))?;
    let rt_key = format!("{key}.Rt");
    let rt = doc.get(cam, key, "Rt")?;
    let r_key = format!("{rt_key}.Rotation");
    let r = doc.numbers(doc.get(rt, &rt_key, "Rotation")?, &r_key, 9)?;
    let t_key = format!("{rt_key}.Translation");
    let t = doc.numbers(doc.get(rt, &rt_key, "Translation")?, &t_key, 3)?;
    let pose = Pose::from_rotation_translation(
        [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]],
        [t[0], t[1], t[2]],
    )
    .map_err(|e| doc.bad(&r_key, e.to_string()))?;
    Ok((intrinsics, pose))
}

/// Parses the text of an Azure Kinect calibration JSON into a camera called `name`, with
/// intrinsics for the images of `mode`; `path` is used in error messages, which name the
/// key (`CalibrationInformation.Cameras[1].Intrinsics.ModelParameters`).
pub fn parse_azure_kinect_json(
    text: &str,
    name: &str,
    path: &Path,
    mode: AzureKinectMode,
) -> Result<ImportedCamera, CalibError> {
    let doc = Doc { path };
    let root: Value = serde_json::from_str(without_bom(text)).map_err(|e| CalibError::Syntax {
        line: e.line(),
        reason: e.to_string(),
        path: path.to_path_buf(),
    })?;
    let info = doc.get(&root, "", "CalibrationInformation")?;
    let cams_key = "CalibrationInformation.Cameras";
    let Value::Array(cams) = doc.get(info, "CalibrationInformation", "Cameras")? else {
        return Err(doc.bad(cams_key, "must be an array"));
    };
    let find = |location: &str| -> Result<(usize, &Value), CalibError> {
        cams.iter()
            .enumerate()
            .find(|(_, c)| c.get("Location").and_then(Value::as_str) == Some(location))
            .ok_or_else(|| CalibError::MissingKey {
                key: format!("{cams_key}[Location = {location}]"),
                path: path.to_path_buf(),
            })
    };
    let (di, depth_cam) = find(AZURE_DEPTH_LOCATION)?;
    let (ci, color_cam) = find(AZURE_COLOR_LOCATION)?;
    let (depth, depth_from_ref) = read_camera(
        &doc,
        depth_cam,
        &format!("{cams_key}[{di}]"),
        AzureSensor::Depth(mode.depth),
    )?;
    let (color, color_from_ref) = read_camera(
        &doc,
        color_cam,
        &format!("{cams_key}[{ci}]"),
        AzureSensor::Color(mode.color),
    )?;
    let color_from_depth = if depth_from_ref == Pose::identity() {
        color_from_ref
    } else {
        color_from_ref.compose(&depth_from_ref.inverse())
    };
    Ok(ImportedCamera {
        camera: RgbdCamera {
            name: name.to_string(),
            depth,
            color,
            color_from_depth,
            world_from_depth: Pose::identity(),
            depth_scale: DEFAULT_DEPTH_SCALE,
            depth_shift_mm: 0.0,
        },
        notes: Vec::new(),
    })
}

fn camera_json(intr: &Intrinsics, location: &str, purpose: &str, rt: &Pose) -> Value {
    let (w, h) = (f64::from(intr.width), f64::from(intr.height));
    let [k1, k2, p1, p2, k3, k4, k5, k6] = intr.distortion.rational_coefficients();
    let r = rt.rotation();
    json!({
        "Intrinsics": {
            "ModelParameterCount": MODEL_PARAMETER_COUNT,
            "ModelParameters": [
                (intr.cx + 0.5) / w, (intr.cy + 0.5) / h, intr.fx / w, intr.fy / h,
                k1, k2, k3, k4, k5, k6, 0.0, 0.0, p2, p1,
            ],
            "ModelType": BROWN_CONRADY,
        },
        "Location": location,
        "Purpose": purpose,
        "Rt": {
            "Rotation": r.iter().flatten().copied().collect::<Vec<f64>>(),
            "Translation": rt.translation_m(),
        },
        "SensorHeight": intr.height,
        "SensorWidth": intr.width,
    })
}

/// The text of an Azure Kinect calibration JSON for a camera: `SensorWidth ×
/// SensorHeight` is each sensor's image size (a device's own file holds 1024×1024 and
/// 4096×3072), the distortion its rational coefficients (k4..k6 = 0 for Brown-Conrady),
/// codx = cody = 0.
///
/// The format holds neither `world_from_depth` (dropped) nor a depth scale or shift:
/// `depth_scale` must be 1000 and `depth_shift_mm` 0, else the error names the field.
/// Intrinsics go through the normalisation of the module doc, so a round trip gives
/// them back within a few ulps (≤ 1e-9 px), not bit for bit; the rest is exact.
pub fn azure_kinect_json_to_string(camera: &RgbdCamera) -> Result<String, CalibError> {
    camera.validate_millimetre_depth("(Azure Kinect depth is in millimetres)")?;
    if camera.depth_shift_mm != 0.0 {
        return Err(CalibError::invalid(
            "depth_shift_mm",
            format!(
                "must be 0 (the Azure Kinect format has no depth shift), got {}",
                camera.depth_shift_mm
            ),
        ));
    }
    let root = json!({
        "CalibrationInformation": {
            "Cameras": [
                camera_json(&camera.depth, AZURE_DEPTH_LOCATION, "CALIBRATION_CameraPurposeDepth", &Pose::identity()),
                camera_json(&camera.color, AZURE_COLOR_LOCATION, "CALIBRATION_CameraPurposePhotoVideo", &camera.color_from_depth),
            ],
            "FileVersion": {"Major": 1, "Minor": 2},
        }
    });
    serde_json::to_string_pretty(&root)
        .map_err(|e| CalibError::invalid("camera", format!("cannot be written as JSON: {e}")))
}

/// Writes an Azure Kinect calibration JSON (through a temporary file and a rename).
pub fn write_azure_kinect_json(path: &Path, camera: &RgbdCamera) -> Result<(), CalibError> {
    write_atomic(path, &azure_kinect_json_to_string(camera)?)
}
