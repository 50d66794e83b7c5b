//! The project's `rig.toml` (FORMATS.md "rig.toml"): reader and writer.
//!
//! The reader walks the TOML tree by hand so that every error names the camera and the
//! field (`camera cam0: depth.fx must be a number, got string: rig.toml`). Unknown keys are
//! ignored (readers are tolerant); integers are accepted where a float is expected;
//! `distortion` holds 5 values (Brown-Conrady) or 8 (the rational model), any other count
//! is an error naming the camera and the table. The writer writes the 5 or 8 values the
//! camera's model has, always writes rotations as 3×3 matrices, with floats printed to
//! round-trip exactly. A leading byte order mark is ignored.

use std::path::Path;

use serde::Serialize;
use toml::{Table, Value};

use crate::{CalibError, DEFAULT_DEPTH_SCALE, Distortion, Intrinsics, Pose, RgbdCamera, Rig};

/// Reads and validates one sensor's intrinsics TOML (see [`parse_intrinsics_toml`]).
pub fn read_intrinsics_toml(path: &Path) -> Result<Intrinsics, CalibError> {
    let text = crate::files::read_text(path)?;
    parse_intrinsics_toml(&text, path)
}

/// Parses one sensor's intrinsics: the keys of a rig.toml `[camera.depth]` table (`width`,
/// `height`, `fx`, `fy`, `cx`, `cy`, `distortion`) at the top level; other keys are
/// ignored. `path` is only used in error messages.
pub fn parse_intrinsics_toml(text: &str, path: &Path) -> Result<Intrinsics, CalibError> {
    let root = parse_table(text, path)?;
    let located = |e: CalibError| match e {
        CalibError::CameraField {
            field,
            reason,
            path,
            ..
        } => CalibError::BadValue {
            key: field,
            reason,
            path,
        },
        CalibError::Invalid { field, reason } => CalibError::BadValue {
            key: field,
            reason,
            path: path.to_path_buf(),
        },
        other => other,
    };
    let intrinsics = read_intrinsics(&root, "", "", path).map_err(located)?;
    intrinsics.validate().map_err(located)?;
    Ok(intrinsics)
}

/// The text of one sensor's intrinsics TOML, `comment` (lines without `#`) first.
pub fn intrinsics_to_toml_string(
    intrinsics: &Intrinsics,
    comment: &str,
) -> Result<String, CalibError> {
    intrinsics.validate()?;
    let body = toml::to_string(&IntrinsicsOut::from(intrinsics))
        .map_err(|e| CalibError::invalid("intrinsics", e.to_string()))?;
    let header: String = comment.lines().map(|l| format!("# {l}\n")).collect();
    Ok(format!("{header}{body}"))
}

/// Writes one sensor's intrinsics TOML atomically (temporary file, then rename).
pub fn write_intrinsics_toml(
    intrinsics: &Intrinsics,
    comment: &str,
    path: &Path,
) -> Result<(), CalibError> {
    crate::files::write_atomic(path, &intrinsics_to_toml_string(intrinsics, comment)?)
}

fn parse_table(text: &str, path: &Path) -> Result<Table, CalibError> {
    // Spans below count bytes of the text without the byte order mark.
    let text = crate::files::without_bom(text);
    text.parse()
        .map_err(|e: toml::de::Error| CalibError::Syntax {
            line: e.span().map_or(0, |span| {
                let before = &text.as_bytes()[..span.start.min(text.len())];
                before.iter().filter(|&&b| b == b'\n').count() + 1
            }),
            reason: e.message().to_string(),
            path: path.to_path_buf(),
        })
}

/// Reads and validates a `rig.toml`.
pub fn read_rig_toml(path: &Path) -> Result<Rig, CalibError> {
    let text = crate::files::read_text(path)?;
    parse_rig_toml(&text, path)
}

/// Parses and validates the text of a `rig.toml`; `path` is only used in error messages.
pub fn parse_rig_toml(text: &str, path: &Path) -> Result<Rig, CalibError> {
    let root = parse_table(text, path)?;
    let cameras = match root.get("camera") {
        Some(Value::Array(items)) if !items.is_empty() => items,
        Some(Value::Array(_)) | None => {
            return Err(CalibError::MissingKey {
                key: "[[camera]] (a rig needs at least one camera)".into(),
                path: path.to_path_buf(),
            });
        }
        Some(other) => {
            return Err(CalibError::BadValue {
                key: "camera".into(),
                reason: format!(
                    "must be an array of tables ([[camera]]), got {}",
                    other.type_str()
                ),
                path: path.to_path_buf(),
            });
        }
    };
    let mut rig = Rig::default();
    for (i, item) in cameras.iter().enumerate() {
        let unnamed = format!("#{i}");
        let Value::Table(table) = item else {
            return Err(field_error(&unnamed, "", "must be a table", path));
        };
        let cam = read_camera(table, &unnamed, path)?;
        rig.cameras.push(cam);
    }
    rig.validate().map_err(|e| match e {
        CalibError::Invalid { field, reason } => CalibError::BadValue {
            key: field,
            reason,
            path: path.to_path_buf(),
        },
        other => other,
    })?;
    Ok(rig)
}

fn field_error(camera: &str, field: &str, reason: impl Into<String>, path: &Path) -> CalibError {
    CalibError::CameraField {
        camera: camera.to_string(),
        field: field.to_string(),
        reason: reason.into(),
        path: path.to_path_buf(),
    }
}

/// Where a field sits, for error messages.
struct Ctx<'a> {
    camera: &'a str,
    table: &'a str,
    path: &'a Path,
}

impl Ctx<'_> {
    fn field(&self, key: &str) -> String {
        if self.table.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.table)
        }
    }

    fn err(&self, key: &str, reason: impl Into<String>) -> CalibError {
        field_error(self.camera, &self.field(key), reason, self.path)
    }

    fn get<'t>(&self, t: &'t Table, key: &str) -> Result<&'t Value, CalibError> {
        t.get(key).ok_or_else(|| self.err(key, "is missing"))
    }

    fn number(&self, key: &str, v: &Value) -> Result<f64, CalibError> {
        match v {
            Value::Float(f) => Ok(*f),
            // Integers are exact in f64 up to 2^53, far beyond any calibration value.
            Value::Integer(i) => Ok(*i as f64),
            other => Err(self.err(key, format!("must be a number, got {}", other.type_str()))),
        }
    }

    fn f64(&self, t: &Table, key: &str) -> Result<f64, CalibError> {
        self.number(key, self.get(t, key)?)
    }

    fn f64_or(&self, t: &Table, key: &str, default: f64) -> Result<f64, CalibError> {
        t.get(key).map_or(Ok(default), |v| self.number(key, v))
    }

    fn u32(&self, t: &Table, key: &str) -> Result<u32, CalibError> {
        match self.get(t, key)? {
            Value::Integer(i) => u32::try_from(*i)
                .map_err(|_| self.err(key, format!("must be a pixel count, got {i}"))),
            other => Err(self.err(key, format!("must be an integer, got {}", other.type_str()))),
        }
    }

    fn array<const N: usize>(&self, key: &str, v: &Value) -> Result<[f64; N], CalibError> {
        let Value::Array(items) = v else {
            return Err(self.err(
                key,
                format!("must be an array of {N} numbers, got {}", v.type_str()),
            ));
        };
        if items.len() != N {
            return Err(self.err(key, format!("must have {N} values, got {}", items.len())));
        }
        let mut out = [0.0; N];
        for (o, item) in out.iter_mut().zip(items) {
            *o = self.number(key, item)?;
        }
        Ok(out)
    }

    /// `distortion`: 5 numbers (Brown-Conrady) or 8 (rational), OpenCV's order.
    fn distortion(&self, v: &Value) -> Result<Distortion, CalibError> {
        const KEY: &str = "distortion";
        const WANT: &str =
            "5 numbers (k1 k2 p1 p2 k3) or 8 (rational model: k1 k2 p1 p2 k3 k4 k5 k6)";
        let Value::Array(items) = v else {
            return Err(self.err(
                KEY,
                format!("must be an array of {WANT}, got {}", v.type_str()),
            ));
        };
        let values = items
            .iter()
            .map(|item| self.number(KEY, item))
            .collect::<Result<Vec<f64>, _>>()?;
        match values.len() {
            5 | 8 => Distortion::from_opencv(&values)
                .ok_or_else(|| self.err(KEY, format!("must have {WANT}"))),
            n => Err(self.err(KEY, format!("must have {WANT}, got {n} values"))),
        }
    }

    fn table<'t>(&self, t: &'t Table, key: &str) -> Result<&'t Table, CalibError> {
        match self.get(t, key)? {
            Value::Table(inner) => Ok(inner),
            other => Err(self.err(key, format!("must be a table, got {}", other.type_str()))),
        }
    }
}

fn read_camera(t: &Table, unnamed: &str, path: &Path) -> Result<RgbdCamera, CalibError> {
    let name = match t.get("name") {
        Some(Value::String(s)) if !s.is_empty() => s.clone(),
        Some(Value::String(_)) => {
            return Err(field_error(unnamed, "name", "must not be empty", path));
        }
        Some(other) => {
            return Err(field_error(
                unnamed,
                "name",
                format!("must be a string, got {}", other.type_str()),
                path,
            ));
        }
        None => return Err(field_error(unnamed, "name", "is missing", path)),
    };
    let top = Ctx {
        camera: &name,
        table: "",
        path,
    };
    let depth = read_intrinsics(top.table(t, "depth")?, &name, "depth", path)?;
    let color = read_intrinsics(top.table(t, "color")?, &name, "color", path)?;
    let pose = |key: &str| read_pose(top.table(t, key)?, &name, key, path);
    let color_from_depth = pose("color_from_depth")?;
    let world_from_depth = pose("world_from_depth")?;
    let cam = RgbdCamera {
        depth_scale: top.f64_or(t, "depth_scale", DEFAULT_DEPTH_SCALE)?,
        depth_shift_mm: top.f64_or(t, "depth_shift_mm", 0.0)?,
        name: name.clone(),
        depth,
        color,
        color_from_depth,
        world_from_depth,
    };
    cam.validate().map_err(|e| match e {
        CalibError::Invalid { field, reason } => field_error(&name, &field, reason, path),
        other => other,
    })?;
    Ok(cam)
}

fn read_intrinsics(
    t: &Table,
    camera: &str,
    table: &str,
    path: &Path,
) -> Result<Intrinsics, CalibError> {
    let c = Ctx {
        camera,
        table,
        path,
    };
    let distortion = c.distortion(c.get(t, "distortion")?)?;
    Ok(Intrinsics {
        width: c.u32(t, "width")?,
        height: c.u32(t, "height")?,
        fx: c.f64(t, "fx")?,
        fy: c.f64(t, "fy")?,
        cx: c.f64(t, "cx")?,
        cy: c.f64(t, "cy")?,
        distortion,
    })
}

fn read_pose(t: &Table, camera: &str, table: &str, path: &Path) -> Result<Pose, CalibError> {
    let c = Ctx {
        camera,
        table,
        path,
    };
    let translation_m = c.array::<3>("translation_m", c.get(t, "translation_m")?)?;
    let located = |e: CalibError| match e {
        CalibError::Invalid { field, reason } => c.err(&field, reason),
        other => other,
    };
    match (t.get("rotation"), t.get("quaternion_wxyz")) {
        (Some(rotation), None) => {
            let Value::Array(rows) = rotation else {
                return Err(c.err(
                    "rotation",
                    format!("must be 3 rows of 3 numbers, got {}", rotation.type_str()),
                ));
            };
            if rows.len() != 3 {
                return Err(c.err("rotation", format!("must have 3 rows, got {}", rows.len())));
            }
            let mut r = [[0.0; 3]; 3];
            for (out, row) in r.iter_mut().zip(rows) {
                *out = c.array::<3>("rotation", row)?;
            }
            Pose::from_rotation_translation(r, translation_m).map_err(located)
        }
        (None, Some(q)) => {
            let q = c.array::<4>("quaternion_wxyz", q)?;
            Pose::from_quaternion_wxyz(q, translation_m).map_err(located)
        }
        (Some(_), Some(_)) => {
            Err(c.err("rotation", "and quaternion_wxyz are both given; give one"))
        }
        (None, None) => Err(c.err("rotation", "is missing (give rotation or quaternion_wxyz)")),
    }
}

#[derive(Serialize)]
struct RigOut<'a> {
    camera: Vec<CameraOut<'a>>,
}

#[derive(Serialize)]
struct CameraOut<'a> {
    name: &'a str,
    depth_scale: f64,
    depth_shift_mm: f64,
    depth: IntrinsicsOut,
    color: IntrinsicsOut,
    color_from_depth: PoseOut,
    world_from_depth: PoseOut,
}

#[derive(Serialize)]
struct IntrinsicsOut {
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    /// 5 or 8 values, as the model needs.
    distortion: Vec<f64>,
}

impl From<&Intrinsics> for IntrinsicsOut {
    fn from(i: &Intrinsics) -> Self {
        IntrinsicsOut {
            width: i.width,
            height: i.height,
            fx: i.fx,
            fy: i.fy,
            cx: i.cx,
            cy: i.cy,
            distortion: i.distortion.coefficients().to_vec(),
        }
    }
}

#[derive(Serialize)]
struct PoseOut {
    rotation: [[f64; 3]; 3],
    translation_m: [f64; 3],
}

impl From<&Pose> for PoseOut {
    fn from(p: &Pose) -> Self {
        PoseOut {
            rotation: p.rotation(),
            translation_m: p.translation_m(),
        }
    }
}

/// The text of a `rig.toml` for a rig (validated first, so what is written can be read).
pub fn rig_to_toml_string(rig: &Rig) -> Result<String, CalibError> {
    rig.validate()?;
    let out = RigOut {
        camera: rig
            .cameras
            .iter()
            .map(|c| CameraOut {
                name: &c.name,
                depth_scale: c.depth_scale,
                depth_shift_mm: c.depth_shift_mm,
                depth: (&c.depth).into(),
                color: (&c.color).into(),
                color_from_depth: (&c.color_from_depth).into(),
                world_from_depth: (&c.world_from_depth).into(),
            })
            .collect(),
    };
    let body = toml::to_string(&out).map_err(|e| CalibError::invalid("rig", e.to_string()))?;
    Ok(format!(
        "# bodyseg rig: see FORMATS.md \"rig.toml\". Frames: OpenCV optical (x right, y down,\n\
         # z forward) per sensor; world z up; metres; transforms map b into a (a_from_b).\n\n{body}"
    ))
}

/// Writes a `rig.toml`: to a temporary file beside `path`, then renamed over it, so a
/// failure never leaves a half-written rig.
pub fn write_rig_toml(rig: &Rig, path: &Path) -> Result<(), CalibError> {
    crate::files::write_atomic(path, &rig_to_toml_string(rig)?)
}
