//! Azure Kinect factory calibration JSON (`k4arecorder`'s attachment, `k4a_device_get_raw_calibration`):
//! reader and writer.
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
//! - Cameras are found by `Location`: `..._CameraLocationD0` is the depth sensor,
//!   `..._CameraLocationPV0` the colour sensor; others (IMU-less extras) are ignored.
//! - `ModelParameters` are normalised by the sensor size (`SensorWidth`, `SensorHeight`,
//!   the full native resolution: 1024×1024 depth, 4096×3072 colour). The intrinsics are
//!   returned at that resolution; a capture mode that bins or crops (NFOV 640×576, colour
//!   1920×1080) needs its own scaling, which this reader does not do.
//! - The Azure Kinect SDK's pixel convention puts pixel *corners* at integers (centre of
//!   the first pixel at 0.5), OpenCV's and bodyseg's put pixel *centres* at integers (see
//!   the crate conventions). So, as the SDK does when it converts to OpenCV:
//!   `fx = fx_n · W`, `fy = fy_n · H`, `cx = cx_n · W − 0.5`, `cy = cy_n · H − 0.5`.
//!   The writer inverts this.
//! - k4, k5, k6 are the denominator of OpenCV's rational model; bodyseg's 5-coefficient
//!   Brown-Conrady (k1 k2 p1 p2 k3) drops them. So does the centre of distortion
//!   (codx, cody), which k4a's Brown-Conrady model requires to be 0. When any of them is
//!   non-zero the reader still succeeds and says so in
//!   [`AzureKinectCalibration::warnings`]. Note the stored order: p2 before p1.
//! - `Rt` maps the depth frame (the device's reference) into each camera: the colour
//!   camera's `Rt` is `color_from_depth` (translation in metres); the depth camera's is the
//!   identity in factory files, and is honoured if it is not
//!   (`color_from_depth = colour.Rt · depth.Rt⁻¹`).
//! - `world_from_depth` is the identity, `depth_scale` 1000 (millimetres), no shift.

use std::path::Path;

use serde_json::{Value, json};

use crate::files::{read_text, write_atomic};
use crate::{CalibError, DEFAULT_DEPTH_SCALE, Intrinsics, Pose, RgbdCamera};

/// `Location` of the depth camera.
pub const AZURE_DEPTH_LOCATION: &str = "CALIBRATION_CameraLocationD0";
/// `Location` of the colour (photo-video) camera.
pub const AZURE_COLOR_LOCATION: &str = "CALIBRATION_CameraLocationPV0";
/// `ModelType` of the lens model this reader understands.
const BROWN_CONRADY: &str = "CALIBRATION_LensDistortionModelBrownConrady";
/// Number of `ModelParameters` of the Brown-Conrady model.
const MODEL_PARAMETER_COUNT: usize = 14;

/// A camera read from an Azure Kinect calibration, with what the conversion dropped.
#[derive(Debug, Clone, PartialEq)]
pub struct AzureKinectCalibration {
    /// The camera (intrinsics at the sensors' native resolution).
    pub camera: RgbdCamera,
    /// One line per non-zero coefficient that bodyseg's model drops (k4..k6, codx, cody),
    /// naming the key, the value and the file. Real devices store non-zero k4..k6, so
    /// callers should log these.
    pub warnings: Vec<String>,
}

/// Reads an Azure Kinect calibration JSON into a camera called `name`.
pub fn read_azure_kinect_json(
    path: &Path,
    name: &str,
) -> Result<AzureKinectCalibration, CalibError> {
    parse_azure_kinect_json(&read_text(path)?, name, path)
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

/// One camera entry: intrinsics and its `Rt` (camera_from_depth-reference).
fn read_camera(
    doc: &Doc,
    cam: &Value,
    key: &str,
    warnings: &mut Vec<String>,
) -> Result<(Intrinsics, Pose), CalibError> {
    let width = doc.size(cam, key, "SensorWidth")?;
    let height = doc.size(cam, key, "SensorHeight")?;
    let intr_key = format!("{key}.Intrinsics");
    let intr = doc.get(cam, key, "Intrinsics")?;
    if let Some(model) = intr.get("ModelType")
        && model.as_str() != Some(BROWN_CONRADY)
    {
        return Err(doc.bad(
            &format!("{intr_key}.ModelType"),
            format!("{model} is not supported: bodyseg reads only {BROWN_CONRADY:?}"),
        ));
    }
    let params_key = format!("{intr_key}.ModelParameters");
    let p = doc.numbers(
        doc.get(intr, &intr_key, "ModelParameters")?,
        &params_key,
        MODEL_PARAMETER_COUNT,
    )?;
    let (w, h) = (f64::from(width), f64::from(height));
    let intrinsics = Intrinsics {
        width,
        height,
        fx: p[2] * w,
        fy: p[3] * h,
        // Corner-at-integer (k4a) → centre-at-integer (OpenCV, bodyseg): see module doc.
        cx: p[0] * w - 0.5,
        cy: p[1] * h - 0.5,
        // Stored as k1 k2 k3 k4 k5 k6 codx cody p2 p1; ours is k1 k2 p1 p2 k3.
        distortion: [p[4], p[5], p[13], p[12], p[6]],
    };
    intrinsics
        .validate()
        .map_err(|e| doc.bad(&params_key, e.to_string()))?;
    for (i, label) in [(7, "k4"), (8, "k5"), (9, "k6"), (10, "codx"), (11, "cody")] {
        if p[i] != 0.0 {
            warnings.push(format!(
                "{params_key}: {label} = {} dropped (bodyseg's model is 5-coefficient Brown-Conrady): {}",
                p[i],
                doc.path.display()
            ));
        }
    }
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

/// Parses the text of an Azure Kinect calibration JSON into a camera called `name`;
/// `path` is used in error messages, which name the key
/// (`CalibrationInformation.Cameras[1].Intrinsics.ModelParameters`).
pub fn parse_azure_kinect_json(
    text: &str,
    name: &str,
    path: &Path,
) -> Result<AzureKinectCalibration, CalibError> {
    let doc = Doc { path };
    let root: Value = serde_json::from_str(text).map_err(|e| CalibError::Syntax {
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
    let mut warnings = Vec::new();
    let (di, depth_cam) = find(AZURE_DEPTH_LOCATION)?;
    let (ci, color_cam) = find(AZURE_COLOR_LOCATION)?;
    let (depth, depth_from_ref) =
        read_camera(&doc, depth_cam, &format!("{cams_key}[{di}]"), &mut warnings)?;
    let (color, color_from_ref) =
        read_camera(&doc, color_cam, &format!("{cams_key}[{ci}]"), &mut warnings)?;
    let color_from_depth = if depth_from_ref == Pose::identity() {
        color_from_ref
    } else {
        color_from_ref.compose(&depth_from_ref.inverse())
    };
    Ok(AzureKinectCalibration {
        camera: RgbdCamera {
            name: name.to_string(),
            depth,
            color,
            color_from_depth,
            world_from_depth: Pose::identity(),
            depth_scale: DEFAULT_DEPTH_SCALE,
            depth_shift_mm: 0.0,
        },
        warnings,
    })
}

fn camera_json(intr: &Intrinsics, location: &str, purpose: &str, rt: &Pose) -> Value {
    let (w, h) = (f64::from(intr.width), f64::from(intr.height));
    let d = intr.distortion;
    let r = rt.rotation();
    json!({
        "Intrinsics": {
            "ModelParameterCount": MODEL_PARAMETER_COUNT,
            "ModelParameters": [
                (intr.cx + 0.5) / w, (intr.cy + 0.5) / h, intr.fx / w, intr.fy / h,
                d[0], d[1], d[4], 0.0, 0.0, 0.0, 0.0, 0.0, d[3], d[2],
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

/// The text of an Azure Kinect calibration JSON for a camera (k4..k6, codx, cody = 0).
///
/// The format holds neither `world_from_depth` (dropped) nor a depth scale or shift:
/// `depth_scale` must be 1000 and `depth_shift_mm` 0, else the error names the field.
/// Intrinsics go through the normalisation of the module doc, so a round trip gives
/// them back within a few ulps (≤ 1e-9 px), not bit for bit; the rest is exact.
pub fn azure_kinect_json_to_string(camera: &RgbdCamera) -> Result<String, CalibError> {
    camera.validate()?;
    if camera.depth_scale != DEFAULT_DEPTH_SCALE {
        return Err(CalibError::invalid(
            "depth_scale",
            format!(
                "must be {DEFAULT_DEPTH_SCALE} (Azure Kinect depth is in millimetres), got {}",
                camera.depth_scale
            ),
        ));
    }
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
