//! A reader for the subset of OpenCV's FileStorage YAML (`%YAML:1.0`) that calibration
//! tools write: top-level `key: scalar` and `key: !!opencv-matrix` blocks with `rows`,
//! `cols`, `dt` and a `data: [ ... ]` list that may span lines.
//!
//! This dialect is not standard YAML (the `%YAML:1.0` directive, the `!!opencv-matrix`
//! tag), so it is parsed by hand. Other top-level blocks (nested maps, sequences) are
//! skipped; keys are looked up when a reader asks for them, so errors name the file and
//! the key.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::{CalibError, Distortion, Intrinsics};

/// One top-level entry.
#[derive(Debug, Clone, PartialEq)]
enum Entry {
    /// `key: value` (quotes removed).
    Scalar(String),
    /// `key: !!opencv-matrix`.
    Matrix {
        rows: String,
        cols: String,
        /// The raw items of `data`, unparsed.
        data: Vec<String>,
    },
    /// Anything else (nested maps, sequences): kept only so that its key is known.
    Other,
}

/// A parsed FileStorage document.
#[derive(Debug, Clone)]
pub(crate) struct FileStorage {
    entries: BTreeMap<String, (usize, Entry)>,
    path: PathBuf,
}

fn syntax(line: usize, reason: impl Into<String>, path: &Path) -> CalibError {
    CalibError::Syntax {
        line,
        reason: reason.into(),
        path: path.to_path_buf(),
    }
}

/// Splits `key: rest` (the key may be quoted); `None` when the line has no colon.
fn split_key(line: &str) -> Option<(&str, &str)> {
    let (key, rest) = line.split_once(':')?;
    Some((key.trim().trim_matches('"'), rest.trim()))
}

fn strip_comment(line: &str) -> &str {
    // FileStorage never writes '#' inside values it emits for calibration data.
    line.split_once('#').map_or(line, |(before, _)| before)
}

impl FileStorage {
    /// Reads and parses a file.
    pub(crate) fn read(path: &Path) -> Result<Self, CalibError> {
        Self::parse(&crate::files::read_text(path)?, path)
    }

    /// Parses the text of a file (a leading byte order mark is ignored); `path` is used
    /// in error messages only.
    pub(crate) fn parse(text: &str, path: &Path) -> Result<Self, CalibError> {
        let text = crate::files::without_bom(text);
        let lines: Vec<&str> = text.lines().map(strip_comment).collect();
        let first = lines.iter().position(|l| !l.trim().is_empty());
        match first.map(|i| lines[i].trim()) {
            Some(header) if header.starts_with("%YAML") => {}
            _ => {
                return Err(syntax(
                    first.map_or(1, |i| i + 1),
                    "not an OpenCV FileStorage file (no %YAML:1.0 header)",
                    path,
                ));
            }
        }
        let mut entries = BTreeMap::new();
        let mut i = first.map_or(0, |f| f + 1);
        while i < lines.len() {
            let line = lines[i];
            let line_no = i + 1;
            i += 1;
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed == "---" || trimmed == "..." {
                continue;
            }
            if line.starts_with([' ', '\t']) {
                return Err(syntax(line_no, "indented line outside a block", path));
            }
            let Some((key, rest)) = split_key(trimmed) else {
                return Err(syntax(
                    line_no,
                    format!("expected `key: value`, got {trimmed:?}"),
                    path,
                ));
            };
            // The block: the following indented (or empty) lines.
            let start = i;
            while i < lines.len()
                && (lines[i].trim().is_empty() || lines[i].starts_with([' ', '\t']))
            {
                i += 1;
            }
            let block = &lines[start..i];
            let entry = if rest.starts_with("!!opencv-matrix") {
                parse_matrix(key, block, start + 1, path)?
            } else if rest.is_empty() || rest.starts_with(['[', '{', '!']) {
                Entry::Other
            } else {
                Entry::Scalar(rest.trim_matches('"').to_string())
            };
            entries.insert(key.to_string(), (line_no, entry));
        }
        Ok(FileStorage {
            entries,
            path: path.to_path_buf(),
        })
    }

    fn missing(&self, key: &str) -> CalibError {
        CalibError::MissingKey {
            key: key.to_string(),
            path: self.path.clone(),
        }
    }

    fn bad(&self, key: &str, reason: impl Into<String>) -> CalibError {
        CalibError::BadValue {
            key: key.to_string(),
            reason: reason.into(),
            path: self.path.clone(),
        }
    }

    /// True when the document has this top-level key.
    pub(crate) fn has(&self, key: &str) -> bool {
        self.entries.contains_key(key)
    }

    /// A scalar as a finite number.
    pub(crate) fn number(&self, key: &str) -> Result<f64, CalibError> {
        match self.entries.get(key) {
            None => Err(self.missing(key)),
            Some((_, Entry::Scalar(s))) => parse_number(s)
                .ok_or_else(|| self.bad(key, format!("{s:?} is not a finite number"))),
            Some((_, _)) => Err(self.bad(key, "must be a single number")),
        }
    }

    /// A vector: a matrix with one row or one column (or empty), of any length; its
    /// values in order, all finite.
    pub(crate) fn vector(&self, key: &str) -> Result<Vec<f64>, CalibError> {
        let (rows, cols) = self.shape(key)?;
        if rows > 1 && cols > 1 {
            return Err(self.bad(
                key,
                format!("must be a 1xN or Nx1 vector, the file says {rows}x{cols}"),
            ));
        }
        self.matrix(key, rows, cols)
    }

    /// `rows × cols` of a matrix entry.
    fn shape(&self, key: &str) -> Result<(usize, usize), CalibError> {
        let Some((_, entry)) = self.entries.get(key) else {
            return Err(self.missing(key));
        };
        let Entry::Matrix { rows, cols, .. } = entry else {
            return Err(self.bad(key, "must be an !!opencv-matrix"));
        };
        let dim = |name: &str, s: &str| {
            s.parse::<usize>()
                .map_err(|_| self.bad(key, format!("{name} {s:?} is not a count")))
        };
        Ok((dim("rows", rows)?, dim("cols", cols)?))
    }

    /// A matrix that must be `rows × cols`; its values row-major, all finite.
    pub(crate) fn matrix(
        &self,
        key: &str,
        rows: usize,
        cols: usize,
    ) -> Result<Vec<f64>, CalibError> {
        let Some((_, entry)) = self.entries.get(key) else {
            return Err(self.missing(key));
        };
        let Entry::Matrix {
            rows: r,
            cols: c,
            data,
        } = entry
        else {
            return Err(self.bad(key, "must be an !!opencv-matrix"));
        };
        let dim = |name: &str, s: &str| {
            s.parse::<usize>()
                .map_err(|_| self.bad(key, format!("{name} {s:?} is not a count")))
        };
        let (got_rows, got_cols) = (dim("rows", r)?, dim("cols", c)?);
        if (got_rows, got_cols) != (rows, cols) {
            return Err(self.bad(
                key,
                format!("must be a {rows}x{cols} matrix, the file says {got_rows}x{got_cols}"),
            ));
        }
        if data.len() != rows * cols {
            return Err(self.bad(
                key,
                format!(
                    "a {rows}x{cols} matrix needs {} values, data has {}",
                    rows * cols,
                    data.len()
                ),
            ));
        }
        data.iter()
            .enumerate()
            .map(|(k, s)| {
                parse_number(s).ok_or_else(|| {
                    self.bad(key, format!("data[{k}] = {s:?} is not a finite number"))
                })
            })
            .collect()
    }
}

/// Reads one sensor's intrinsics from an OpenCV FileStorage YAML file (`%YAML:1.0`), in
/// pure Rust: `cameraMatrix` or `camera_matrix` (3×3, no skew), `distortionCoefficients`
/// or `distortion_coefficients` (a 1×N or N×1 vector read as OpenCV reads it: 4, 5 or 8
/// values, see [`Distortion::from_opencv`]), and the image size from `image_width` and
/// `image_height`, or `default_size` when the file has neither (iai_kinect2's files).
/// Errors name the file and the key. XML files need OpenCV itself (feature `opencv`:
/// `read_opencv_intrinsics`).
pub fn read_opencv_yaml_intrinsics(
    path: &Path,
    default_size: Option<[u32; 2]>,
) -> Result<Intrinsics, CalibError> {
    intrinsics_of(&FileStorage::read(path)?, path, default_size)
}

/// [`read_opencv_yaml_intrinsics`] on the text of a file; `path` is used in error
/// messages only.
pub fn parse_opencv_yaml_intrinsics(
    text: &str,
    path: &Path,
    default_size: Option<[u32; 2]>,
) -> Result<Intrinsics, CalibError> {
    intrinsics_of(&FileStorage::parse(text, path)?, path, default_size)
}

/// The intrinsics in a parsed FileStorage document (see [`read_opencv_yaml_intrinsics`]).
fn intrinsics_of(
    fs: &FileStorage,
    path: &Path,
    default_size: Option<[u32; 2]>,
) -> Result<Intrinsics, CalibError> {
    let either = |a: &'static str, b: &'static str| -> Result<&'static str, CalibError> {
        match (fs.has(a), fs.has(b)) {
            (true, _) => Ok(a),
            (false, true) => Ok(b),
            (false, false) => Err(CalibError::MissingKey {
                key: format!("{a} or {b}"),
                path: path.to_path_buf(),
            }),
        }
    };
    let k_key = either("cameraMatrix", "camera_matrix")?;
    let k = fs.matrix(k_key, 3, 3)?;
    if k[1] != 0.0 || [k[3], k[6], k[7], k[8]] != [0.0, 0.0, 0.0, 1.0] {
        return Err(fs.bad(
            k_key,
            format!("must be [fx 0 cx; 0 fy cy; 0 0 1] (bodyseg's pinhole has no skew), got {k:?}"),
        ));
    }
    let d_key = either("distortionCoefficients", "distortion_coefficients")?;
    let d = fs.vector(d_key)?;
    let distortion = Distortion::from_opencv(&d)
        .ok_or_else(|| fs.bad(d_key, Distortion::unsupported_count(d.len())))?;
    let size = |key: &str| -> Result<Option<u32>, CalibError> {
        if !fs.has(key) {
            return Ok(None);
        }
        let v = fs.number(key)?;
        if v.fract() != 0.0 || !(1.0..=f64::from(u32::MAX)).contains(&v) {
            return Err(fs.bad(key, format!("must be a positive pixel count, got {v}")));
        }
        Ok(Some(v as u32))
    };
    // With a default each key falls back on its own (iai_kinect2 writes neither);
    // without one both are needed.
    let dim = |key: &str, i: usize| -> Result<u32, CalibError> {
        match (size(key)?, default_size) {
            (Some(v), _) => Ok(v),
            (None, Some(default)) => Ok(default[i]),
            (None, None) => Err(fs.missing(key)),
        }
    };
    let (width, height) = (dim("image_width", 0)?, dim("image_height", 1)?);
    let intrinsics =
        Intrinsics::pinhole(width, height, k[0], k[4], k[2], k[5]).with_distortion(distortion);
    intrinsics
        .validate()
        .map_err(|e| e.intrinsics_in_file(k_key, d_key, path))?;
    Ok(intrinsics)
}

/// Parses a finite number as FileStorage prints it (`1.`, `-5.2e-02`, `.5`).
fn parse_number(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

fn parse_matrix(
    key: &str,
    block: &[&str],
    first_line: usize,
    path: &Path,
) -> Result<Entry, CalibError> {
    let mut rows = None;
    let mut cols = None;
    let mut data = None;
    let mut j = 0;
    while j < block.len() {
        let line_no = first_line + j;
        let line = block[j].trim();
        j += 1;
        if line.is_empty() {
            continue;
        }
        let Some((sub, rest)) = split_key(line) else {
            return Err(syntax(
                line_no,
                format!("{key}: expected `name: value`, got {line:?}"),
                path,
            ));
        };
        match sub {
            "rows" => rows = Some(rest.to_string()),
            "cols" => cols = Some(rest.to_string()),
            "dt" => {}
            "data" => {
                let Some(after) = rest.strip_prefix('[') else {
                    return Err(syntax(
                        line_no,
                        format!("{key}: data must start with '['"),
                        path,
                    ));
                };
                let mut text = after.to_string();
                while !text.contains(']') {
                    let Some(next) = block.get(j) else {
                        return Err(syntax(
                            line_no,
                            format!("{key}: data has no closing ']'"),
                            path,
                        ));
                    };
                    text.push(',');
                    text.push_str(next);
                    j += 1;
                }
                let inside = text.split(']').next().unwrap_or_default();
                data = Some(
                    inside
                        .split(',')
                        .map(str::trim)
                        .filter(|s| !s.is_empty())
                        .map(str::to_string)
                        .collect::<Vec<_>>(),
                );
            }
            _ => {}
        }
    }
    let missing = |name: &str| {
        syntax(
            first_line.saturating_sub(1),
            format!("{key}: matrix has no {name}"),
            path,
        )
    };
    Ok(Entry::Matrix {
        rows: rows.ok_or_else(|| missing("rows"))?,
        cols: cols.ok_or_else(|| missing("cols"))?,
        data: data.ok_or_else(|| missing("data"))?,
    })
}

/// A number as OpenCV's FileStorage prints a double: integers as `1.`, `-2.`, `0.`,
/// everything else as `%.16e` (`1.0599465578241038e+03`). 17 significant digits always
/// parse back to the same `f64`, so writing then reading is bit-exact.
pub(crate) fn format_number(v: f64) -> String {
    if v == v.trunc() && v.abs() < 1e15 {
        let sign = if v.is_sign_negative() { "-" } else { "" };
        return format!("{sign}{}.", v.abs() as u64);
    }
    let text = format!("{v:.16e}");
    let (mantissa, exp) = text.split_once('e').unwrap_or((&text, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let sign = if exp < 0 { '-' } else { '+' };
    format!("{mantissa}e{sign}{:02}", exp.abs())
}

/// A top-level `key: !!opencv-matrix` block, data wrapped like OpenCV wraps it (lines of
/// at most about 70 characters, continuation lines indented by 7 spaces).
pub(crate) fn format_matrix(key: &str, rows: usize, cols: usize, data: &[f64]) -> String {
    let mut out =
        format!("{key}: !!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ ");
    let mut line_len = 12;
    for (i, &v) in data.iter().enumerate() {
        let mut item = format_number(v);
        item.push_str(if i + 1 == data.len() { " ]" } else { "," });
        if line_len + item.len() > 70 && line_len > 12 {
            out.push_str("\n       ");
            line_len = 7;
        } else if i > 0 {
            out.push(' ');
            line_len += 1;
        }
        line_len += item.len();
        out.push_str(&item);
    }
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = "%YAML:1.0\n---\nshift: -1.5e+01\nname: \"kinect\"\n\
        m: !!opencv-matrix\n   rows: 2\n   cols: 2\n   dt: d\n   data: [ 1., -2.5e-01,\n       3.,\n       4. ]\n\
        nested:\n   a: 1\nv: !!opencv-matrix\n   rows: 1\n   cols: 3\n   dt: d\n   data: [ 1., x, 3. ]\n";

    fn sample() -> FileStorage {
        FileStorage::parse(SAMPLE, Path::new("s.yaml")).expect("valid sample")
    }

    #[test]
    fn reads_scalars_and_multi_line_matrices() {
        let fs = sample();
        assert_eq!(fs.number("shift").expect("number"), -15.0);
        assert_eq!(
            fs.matrix("m", 2, 2).expect("2x2"),
            vec![1.0, -0.25, 3.0, 4.0]
        );
        assert!(fs.has("nested"));
        assert!(!fs.has("a"), "keys of nested blocks are not top-level");
    }

    #[test]
    fn errors_name_key_and_file() {
        let fs = sample();
        let msg = fs.matrix("m", 3, 3).expect_err("wrong shape").to_string();
        assert!(
            msg.starts_with("m: must be a 3x3 matrix") && msg.ends_with("s.yaml"),
            "{msg}"
        );
        let msg = fs.matrix("v", 1, 3).expect_err("non-numeric").to_string();
        assert!(
            msg.contains("data[1] = \"x\"") && msg.ends_with("s.yaml"),
            "{msg}"
        );
        let msg = fs.number("name").expect_err("string").to_string();
        assert!(
            msg.starts_with("name: \"kinect\" is not a finite number"),
            "{msg}"
        );
        let msg = fs.number("absent").expect_err("missing").to_string();
        assert_eq!(msg, "missing key absent: s.yaml");
    }

    #[test]
    fn rejects_files_without_header_or_with_unclosed_data() {
        let err = FileStorage::parse("a: 1\n", Path::new("x.yaml")).expect_err("no header");
        assert!(err.to_string().contains("%YAML:1.0"), "{err}");
        let text =
            "%YAML:1.0\nm: !!opencv-matrix\n   rows: 1\n   cols: 2\n   dt: d\n   data: [ 1., 2.\n";
        let err = FileStorage::parse(text, Path::new("x.yaml")).expect_err("unclosed");
        assert!(err.to_string().contains("no closing ']'"), "{err}");
    }

    #[test]
    // The literals are written as OpenCV prints them.
    #[allow(clippy::excessive_precision)]
    fn written_numbers_and_matrices_read_back_bit_exact() {
        assert_eq!(format_number(1059.9465578241038), "1.0599465578241038e+03");
        assert_eq!(
            format_number(-5.2052476112081990e-02),
            "-5.2052476112081990e-02"
        );
        assert_eq!(format_number(1.0), "1.");
        assert_eq!(format_number(0.0), "0.");
        assert_eq!(format_number(-3.0), "-3.");
        let data = [
            1.0599465578241038e+03,
            0.0,
            1e-300,
            -2.5,
            0.1,
            1.0 / 3.0,
            7.0,
            8.5,
            -0.0,
        ];
        let text = format!("%YAML:1.0\n{}", format_matrix("m", 3, 3, &data));
        let fs = FileStorage::parse(&text, Path::new("w.yaml")).expect("own output parses");
        let back = fs.matrix("m", 3, 3).expect("3x3");
        for (a, b) in back.iter().zip(&data) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} vs {b}");
        }
    }

    #[test]
    fn count_mismatch_is_reported() {
        let text = "%YAML:1.0\nm: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 1., 2. ]\n";
        let fs = FileStorage::parse(text, Path::new("x.yaml")).expect("syntax is fine");
        let msg = fs
            .matrix("m", 3, 1)
            .expect_err("2 values for 3x1")
            .to_string();
        assert_eq!(msg, "m: a 3x1 matrix needs 3 values, data has 2: x.yaml");
    }
}
