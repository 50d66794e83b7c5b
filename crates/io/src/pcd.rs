//! PCL's point cloud files (`.pcd`, format version 0.7; 0.6 and 0.5 headers read too):
//! `ascii`, `binary` and `binary_compressed` (LZF) data, organised or not.

use crate::limits::{MAX_DECLARED_BYTES, MAX_DECLARED_POINTS};
use crate::{CloudFile, CloudGrid, FileLabels, IoError};
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use std::path::Path;

/// Most bytes LZF can produce from one byte of input: a back reference of the longest
/// length (264 bytes) takes three bytes, `264 / 3 = 88`. A `binary_compressed` block that
/// declares a larger uncompressed size is corrupt, and is refused before any allocation.
const LZF_MAX_EXPANSION: usize = 88;

/// Reads a point cloud from a PCD file; see [`parse_pcd`].
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read, otherwise as [`parse_pcd`].
pub fn read_pcd(path: &Path) -> Result<LabeledCloud, IoError> {
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    parse_pcd(&bytes, path)
}

/// One `FIELDS` entry: its name, storage and place in a point record.
#[derive(Clone, Debug)]
struct Field {
    name: String,
    size: usize,
    kind: u8,
    count: usize,
    /// Byte offset of the field in a binary point record.
    offset: usize,
    /// Index of its first value in an ASCII line.
    column: usize,
}

/// What the header declares.
struct Header {
    fields: Vec<Field>,
    points: usize,
    /// `WIDTH` and `HEIGHT` (1 when absent).
    width: u64,
    height: u64,
    /// Bytes per point in binary data: the sum of `SIZE × COUNT`.
    stride: usize,
    /// Values per point in ASCII data: the sum of `COUNT`.
    columns: usize,
    /// Bytes of binary point data, `stride × points` (at most [`MAX_DECLARED_BYTES`]).
    data_bytes: usize,
    data: String,
    /// Byte offset of the data (after the `DATA` line).
    data_start: usize,
    /// Lines in the header (for ASCII line numbers).
    lines: usize,
}

/// Parses a point cloud from the bytes of a PCD file whose labels, if any, must be
/// bodyseg's class ids: [`parse_pcd_file`], then
/// [`CloudFile::into_class_labels`](crate::CloudFile::into_class_labels). A cloud without
/// a `label` field reads with every label unknown.
///
/// # Errors
/// As [`parse_pcd_file`]; [`IoError::ForeignLabels`] for a label outside 0..=6 and 255.
pub fn parse_pcd(bytes: &[u8], path_for_errors: &Path) -> Result<LabeledCloud, IoError> {
    parse_pcd_file(bytes, path_for_errors)?.into_class_labels("point", path_for_errors)
}

/// Parses a point cloud from the bytes of a PCD file; `path_for_errors` only names the
/// file in error messages.
///
/// Accepted: `DATA ascii`, `binary` and `binary_compressed` (PCL's LZF with the
/// column-major layout); organised (`HEIGHT > 1`) and unorganised clouds; fields of any
/// `SIZE`/`TYPE` PCL writes (`F` 4 or 8, `I` and `U` 1, 2, 4 or 8) and `COUNT`s, padding
/// fields (`_`) included. Read into a [`CloudFile`]:
///
/// | field | required | stored as |
/// |---|---|---|
/// | `x`, `y`, `z` | yes | [`LabeledCloud::positions_m`] (metres, the file's frame) |
/// | `rgb` or `rgba` | no | [`LabeledCloud::colors`]: the packed `0x00RRGGBB` bits, whether stored as `F` (PCL's float-packed rgb) or `U` |
/// | `label` | no | [`LabeledCloud::labels`] when every value is a class id 0..=6 or 255 (unknown): [`FileLabels::Classes`]; absent: all unknown, [`FileLabels::Absent`]; any other value (PCL's segment ids): all unknown, [`FileLabels::Foreign`] |
///
/// Points with a NaN or infinite coordinate (PCL's invalid points of organised clouds)
/// are skipped. A point's origin is camera 0 and its index in the file (row-major in an
/// organised cloud, so the pixel), NaN points counted. An organised cloud's
/// [`CloudFile::grid`] holds `WIDTH`, `HEIGHT` and every point's colour, NaN points
/// included.
///
/// # Errors
/// [`IoError::PcdHeader`] for a header line that is not understood or a missing one
/// (`FIELDS`, `SIZE`, `TYPE`, `WIDTH`, `POINTS`, `DATA`), a missing `x`, `y` or `z`
/// field; [`IoError::PcdDataKind`] for an unknown `DATA` kind;
/// [`IoError::PcdPointCount`] when `WIDTH × HEIGHT ≠ POINTS`; [`IoError::PcdHeader`]
/// also when the declared points exceed [`MAX_DECLARED_POINTS`] or their data
/// [`MAX_DECLARED_BYTES`] (checked before anything is allocated); [`IoError::PcdTruncated`]
/// when the data holds fewer points than declared or compressed data is corrupt (its
/// declared sizes are checked against the file's length and LZF's largest expansion
/// before the output is allocated);
/// [`IoError::BadValue`] for an ASCII token that is not a number, or a finite coordinate
/// beyond `f32`'s range.
pub fn parse_pcd_file(bytes: &[u8], path_for_errors: &Path) -> Result<CloudFile, IoError> {
    let path = path_for_errors;
    let header = parse_header(bytes, path)?;
    let find = |name: &str| header.fields.iter().find(|f| f.name == name);
    let need = |name: &str| {
        find(name).ok_or_else(|| IoError::PcdHeader {
            line: header.lines,
            reason: format!("no '{name}' field in FIELDS (x, y and z are required)"),
            path: path.to_path_buf(),
        })
    };
    let (fx, fy, fz) = (need("x")?, need("y")?, need("z")?);
    let frgb = find("rgb").or_else(|| find("rgba"));
    let flabel = find("label");
    let n = header.points;
    let data = &bytes[header.data_start..];
    let mut cloud = LabeledCloud {
        colors: frgb.map(|_| Vec::new()),
        ..Default::default()
    };
    // An organised cloud keeps every cell's colour (NaN points included).
    let organised = match (u32::try_from(header.width), u32::try_from(header.height)) {
        (Ok(w), Ok(h)) if h > 1 => Some((w, h)),
        _ => None,
    };
    let mut grid_colors: Option<Vec<[u8; 3]>> = organised.and(frgb).map(|_| Vec::new());
    let mut foreign: Option<(usize, String)> = None;
    let mut push = |index: usize,
                    xyz: [f64; 3],
                    rgb: Option<u32>,
                    label: Option<f64>|
     -> Result<(), IoError> {
        let rgb = rgb.map(|c| [(c >> 16) as u8, (c >> 8) as u8, c as u8]);
        if let (Some(all), Some(c)) = (grid_colors.as_mut(), rgb) {
            all.push(c);
        }
        if !xyz.iter().all(|v| v.is_finite()) {
            return Ok(());
        }
        // A finite coordinate beyond f32's range (an `F 8`, `I 8` or `U 8` field, or ASCII
        // text) would become infinite in the cloud: an error, not a point at infinity.
        let xyz_f32 = xyz.map(|v| v as f32);
        if let Some(k) = xyz_f32.iter().position(|v| !v.is_finite()) {
            return Err(IoError::BadValue {
                element: "point".into(),
                index,
                property: ["x", "y", "z"][k].into(),
                value: xyz[k].to_string(),
                expected: "a coordinate within f32's range (±3.4e38)",
                path: path.to_path_buf(),
            });
        }
        let label = match label {
            None => Label::UNKNOWN,
            Some(v) => (v.fract() == 0.0 && (0.0..=255.0).contains(&v))
                .then(|| Label::from_id(v as u8))
                .flatten()
                .unwrap_or_else(|| {
                    foreign.get_or_insert_with(|| (index, v.to_string()));
                    Label::UNKNOWN
                }),
        };
        cloud.positions_m.push(xyz_f32);
        cloud.labels.push(label);
        cloud.origins.push(PointOrigin {
            camera: 0,
            pixel: index as u32,
        });
        if let (Some(colors), Some(c)) = (cloud.colors.as_mut(), rgb) {
            colors.push(c);
        }
        Ok(())
    };
    match header.data.as_str() {
        "ascii" => {
            let text = String::from_utf8_lossy(data);
            let columns = header.columns;
            let mut index = 0;
            for (k, line) in text.lines().enumerate() {
                if index == n {
                    break;
                }
                let tokens: Vec<&str> = line.split_ascii_whitespace().collect();
                if tokens.is_empty() {
                    continue;
                }
                if tokens.len() < columns {
                    return Err(IoError::PcdTruncated {
                        reason: format!(
                            "line {}: point {index} has {} values, FIELDS/COUNT declare {columns}",
                            header.lines + k + 1,
                            tokens.len()
                        ),
                        path: path.to_path_buf(),
                    });
                }
                let value = |f: &Field| -> Result<f64, IoError> {
                    let t = tokens[f.column];
                    t.parse::<f64>().map_err(|_| IoError::BadValue {
                        element: "point".into(),
                        index,
                        property: f.name.clone(),
                        value: t.to_string(),
                        expected: "a number",
                        path: path.to_path_buf(),
                    })
                };
                let xyz = [value(fx)?, value(fy)?, value(fz)?];
                let rgb =
                    match frgb {
                        Some(f) => Some(ascii_rgb(tokens[f.column], f).ok_or_else(|| {
                            IoError::BadValue {
                                element: "point".into(),
                                index,
                                property: f.name.clone(),
                                value: tokens[f.column].to_string(),
                                expected: "a packed rgb number",
                                path: path.to_path_buf(),
                            }
                        })?),
                        None => None,
                    };
                let label = flabel.map(value).transpose()?;
                push(index, xyz, rgb, label)?;
                index += 1;
            }
            if index < n {
                return Err(IoError::PcdTruncated {
                    reason: format!("header declares {n} points, ASCII data holds {index}"),
                    path: path.to_path_buf(),
                });
            }
        }
        "binary" => {
            let (stride, want) = (header.stride, header.data_bytes);
            if data.len() < want {
                return Err(IoError::PcdTruncated {
                    reason: format!(
                        "header declares {n} points of {stride} bytes ({want} bytes), data holds {} bytes ({} points)",
                        data.len(),
                        data.len() / stride.max(1)
                    ),
                    path: path.to_path_buf(),
                });
            }
            for (index, record) in data[..want].chunks_exact(stride.max(1)).enumerate() {
                let at = |f: &Field| &record[f.offset..f.offset + f.size];
                let xyz = [
                    scalar(at(fx), fx.kind),
                    scalar(at(fy), fy.kind),
                    scalar(at(fz), fz.kind),
                ];
                let rgb = frgb.map(|f| packed(at(f)));
                let label = flabel.map(|f| scalar(at(f), f.kind));
                push(index, xyz, rgb, label)?;
            }
        }
        "binary_compressed" => {
            let raw = decompress_columns(data, &header, path)?;
            // Column-major: field k's values for all points, one after the other. No
            // overflow: the columns add up to `data_bytes`, checked in the header.
            let mut starts = Vec::with_capacity(header.fields.len());
            let mut at = 0;
            for f in &header.fields {
                starts.push(at);
                at += f.size * f.count * n;
            }
            let column = |f: &Field| {
                let k = header
                    .fields
                    .iter()
                    .position(|g| std::ptr::eq(g, f))
                    .unwrap_or(0);
                (starts[k], f.size * f.count)
            };
            let (cx, cy, cz) = (column(fx), column(fy), column(fz));
            let crgb = frgb.map(column);
            let clabel = flabel.map(column);
            let get = |(start, step): (usize, usize), i: usize, size: usize| {
                &raw[start + i * step..start + i * step + size]
            };
            for index in 0..n {
                let xyz = [
                    scalar(get(cx, index, fx.size), fx.kind),
                    scalar(get(cy, index, fy.size), fy.kind),
                    scalar(get(cz, index, fz.size), fz.kind),
                ];
                let rgb = crgb.zip(frgb).map(|(c, f)| packed(get(c, index, f.size)));
                let label = clabel
                    .zip(flabel)
                    .map(|(c, f)| scalar(get(c, index, f.size), f.kind));
                push(index, xyz, rgb, label)?;
            }
        }
        other => {
            return Err(IoError::PcdDataKind {
                kind: other.to_string(),
                path: path.to_path_buf(),
            });
        }
    }
    let labels = match (flabel, foreign) {
        (None, _) => FileLabels::Absent,
        (Some(_), None) => FileLabels::Classes,
        (Some(_), Some((index, value))) => {
            // Not our ids: none of them is a class (a segment id 3 is no upper arm).
            cloud.labels.fill(Label::UNKNOWN);
            FileLabels::Foreign { index, value }
        }
    };
    let grid = organised.map(|(width, height)| CloudGrid {
        width,
        height,
        colors: grid_colors,
    });
    Ok(CloudFile {
        cloud,
        labels,
        grid,
    })
}

/// An ASCII `rgb`/`rgba` token: PCL writes float-packed colours as floats (whose bits
/// are the colour) and `U` ones as integers.
fn ascii_rgb(token: &str, f: &Field) -> Option<u32> {
    if f.kind == b'F' {
        let v: f32 = token.parse().ok()?;
        Some(v.to_bits() & 0x00FF_FFFF)
    } else {
        let v: f64 = token.parse().ok()?;
        (v >= 0.0 && v.fract() == 0.0).then_some((v as u64 & 0x00FF_FFFF) as u32)
    }
}

/// The low 24 bits of a 4-byte packed colour (little-endian, as PCL writes).
fn packed(b: &[u8]) -> u32 {
    match b {
        [b0, b1, b2, ..] => u32::from_le_bytes([*b0, *b1, *b2, 0]),
        _ => 0,
    }
}

/// A little-endian scalar of `TYPE` `kind` and the slice's size, as f64.
fn scalar(b: &[u8], kind: u8) -> f64 {
    let mut buf = [0u8; 8];
    buf[..b.len()].copy_from_slice(b);
    match (kind, b.len()) {
        (b'F', 4) => f64::from(f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
        (b'F', _) => f64::from_le_bytes(buf),
        (b'I', 1) => f64::from(buf[0] as i8),
        (b'I', 2) => f64::from(i16::from_le_bytes([buf[0], buf[1]])),
        (b'I', 4) => f64::from(i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
        (b'I', _) => i64::from_le_bytes(buf) as f64,
        (_, _) => u64::from_le_bytes(buf) as f64,
    }
}

/// Decompresses `binary_compressed` data: `u32` compressed size, `u32` uncompressed
/// size, then LZF.
fn decompress_columns(data: &[u8], header: &Header, path: &Path) -> Result<Vec<u8>, IoError> {
    let truncated = |reason: String| IoError::PcdTruncated {
        reason,
        path: path.to_path_buf(),
    };
    let want = header.data_bytes;
    let (Some(c), Some(u)) = (data.get(0..4), data.get(4..8)) else {
        return Err(truncated(format!(
            "binary_compressed data needs an 8-byte size prefix, file holds {} bytes",
            data.len()
        )));
    };
    let compressed = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize;
    let uncompressed = u32::from_le_bytes([u[0], u[1], u[2], u[3]]) as usize;
    if uncompressed != want {
        return Err(truncated(format!(
            "header declares {} points ({want} bytes), compressed block holds {uncompressed} bytes",
            header.points
        )));
    }
    let Some(block) = data.get(8..).and_then(|rest| rest.get(..compressed)) else {
        return Err(truncated(format!(
            "compressed block of {compressed} bytes, file holds {}",
            data.len().saturating_sub(8)
        )));
    };
    if uncompressed > compressed.saturating_mul(LZF_MAX_EXPANSION) {
        return Err(truncated(format!(
            "compressed block of {compressed} bytes cannot hold {uncompressed} bytes (LZF expands at most {LZF_MAX_EXPANSION}x)"
        )));
    }
    let out = lzf_decompress(block, uncompressed)
        .map_err(|e| truncated(format!("corrupt LZF block: {e}")))?;
    if out.len() != uncompressed {
        return Err(truncated(format!(
            "LZF block decompresses to {} bytes, header says {uncompressed}",
            out.len()
        )));
    }
    Ok(out)
}

/// LZF decompression (liblzf's format, as PCL uses): control byte < 32 = literal run of
/// `ctrl + 1` bytes; otherwise a back reference of length `(ctrl >> 5) + 2` (7 = one
/// more length byte follows) at distance `((ctrl & 31) << 8) + next + 1`.
pub(crate) fn lzf_decompress(input: &[u8], capacity: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(capacity);
    let mut ip = 0;
    while ip < input.len() {
        let ctrl = usize::from(input[ip]);
        ip += 1;
        if ctrl < 32 {
            let len = ctrl + 1;
            let Some(run) = input.get(ip..ip + len) else {
                return Err(format!(
                    "literal run of {len} bytes past the end at byte {ip}"
                ));
            };
            out.extend_from_slice(run);
            ip += len;
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                let Some(&more) = input.get(ip) else {
                    return Err("back reference length past the end".into());
                };
                len += usize::from(more);
                ip += 1;
            }
            len += 2;
            let Some(&low) = input.get(ip) else {
                return Err("back reference offset past the end".into());
            };
            ip += 1;
            let distance = ((ctrl & 31) << 8) + usize::from(low) + 1;
            let Some(start) = out.len().checked_sub(distance) else {
                return Err(format!(
                    "back reference {distance} bytes before the start of the output"
                ));
            };
            for k in 0..len {
                let b = out[start + k];
                out.push(b);
            }
        }
        if out.len() > capacity {
            return Err(format!("output exceeds the declared {capacity} bytes"));
        }
    }
    Ok(out)
}

/// Reads the header lines up to and including `DATA`.
fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
    let bad = |line: usize, reason: String| IoError::PcdHeader {
        line,
        reason,
        path: path.to_path_buf(),
    };
    let mut names: Option<Vec<String>> = None;
    let mut sizes: Option<Vec<usize>> = None;
    let mut types: Option<Vec<u8>> = None;
    let mut counts: Option<Vec<usize>> = None;
    let (mut width, mut height, mut points) = (None, None, None);
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        if pos >= bytes.len() {
            return Err(bad(
                line_no + 1,
                "no DATA line (not a PCD file, or a truncated header)".into(),
            ));
        }
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| pos + k);
        let line = String::from_utf8_lossy(&bytes[pos..end]);
        pos = (end + 1).min(bytes.len());
        line_no += 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut words = line.split_ascii_whitespace();
        let key = words.next().unwrap_or_default().to_ascii_uppercase();
        let rest: Vec<&str> = words.collect();
        let numbers = |what: &str| -> Result<Vec<usize>, IoError> {
            rest.iter()
                .map(|w| {
                    w.parse::<usize>()
                        .map_err(|_| bad(line_no, format!("{what}: '{w}' is not a whole number")))
                })
                .collect()
        };
        let one = |what: &str| -> Result<u64, IoError> {
            match rest[..] {
                [w] => w
                    .parse::<u64>()
                    .map_err(|_| bad(line_no, format!("{what}: '{w}' is not a whole number"))),
                _ => Err(bad(line_no, format!("{what} takes one number"))),
            }
        };
        match key.as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => names = Some(rest.iter().map(|s| s.to_string()).collect()),
            "SIZE" => {
                let v = numbers("SIZE")?;
                if let Some(s) = v.iter().find(|&&s| ![1, 2, 4, 8].contains(&s)) {
                    return Err(bad(line_no, format!("SIZE {s} is not 1, 2, 4 or 8")));
                }
                sizes = Some(v);
            }
            "TYPE" => {
                let mut v = Vec::new();
                for w in &rest {
                    match *w {
                        "F" | "I" | "U" => v.push(w.as_bytes()[0]),
                        other => {
                            return Err(bad(line_no, format!("TYPE '{other}' is not F, I or U")));
                        }
                    }
                }
                types = Some(v);
            }
            "COUNT" => counts = Some(numbers("COUNT")?),
            "WIDTH" => width = Some(one("WIDTH")?),
            "HEIGHT" => height = Some(one("HEIGHT")?),
            "POINTS" => points = Some(one("POINTS")?),
            "DATA" => {
                let kind = rest.first().copied().unwrap_or_default().to_string();
                let Some(names) = names else {
                    return Err(bad(line_no, "no FIELDS line before DATA".into()));
                };
                let (Some(sizes), Some(types)) = (sizes, types) else {
                    return Err(bad(line_no, "no SIZE or TYPE line before DATA".into()));
                };
                let counts = counts.unwrap_or_else(|| vec![1; names.len()]);
                if sizes.len() != names.len()
                    || types.len() != names.len()
                    || counts.len() != names.len()
                {
                    return Err(bad(
                        line_no,
                        format!(
                            "FIELDS has {} entries but SIZE {}, TYPE {}, COUNT {}",
                            names.len(),
                            sizes.len(),
                            types.len(),
                            counts.len()
                        ),
                    ));
                }
                let Some(width) = width else {
                    return Err(bad(line_no, "no WIDTH line before DATA".into()));
                };
                let height = height.unwrap_or(1);
                let product = width.saturating_mul(height);
                let points = points.unwrap_or(product);
                if product != points {
                    return Err(IoError::PcdPointCount {
                        width,
                        height,
                        product,
                        points,
                        path: path.to_path_buf(),
                    });
                }
                let mut fields = Vec::with_capacity(names.len());
                let (mut offset, mut column) = (0usize, 0usize);
                for (k, name) in names.into_iter().enumerate() {
                    if counts[k] == 0 {
                        return Err(bad(line_no, format!("field '{name}' has COUNT 0")));
                    }
                    // A COUNT so large that one point's size overflows: no real file.
                    let (Some(next_offset), Some(next_column)) = (
                        sizes[k]
                            .checked_mul(counts[k])
                            .and_then(|bytes| offset.checked_add(bytes)),
                        column.checked_add(counts[k]),
                    ) else {
                        return Err(bad(
                            line_no,
                            format!(
                                "field '{name}' has COUNT {}: a point would exceed {} bytes",
                                counts[k],
                                usize::MAX
                            ),
                        ));
                    };
                    fields.push(Field {
                        name,
                        size: sizes[k],
                        kind: types[k],
                        count: counts[k],
                        offset,
                        column,
                    });
                    (offset, column) = (next_offset, next_column);
                }
                if !matches!(kind.as_str(), "ascii" | "binary" | "binary_compressed") {
                    return Err(IoError::PcdDataKind {
                        kind,
                        path: path.to_path_buf(),
                    });
                }
                if points > MAX_DECLARED_POINTS {
                    return Err(bad(
                        line_no,
                        format!(
                            "POINTS {points} is more than bodyseg reads ({MAX_DECLARED_POINTS})"
                        ),
                    ));
                }
                let data_bytes = u64::try_from(offset)
                    .ok()
                    .and_then(|stride| stride.checked_mul(points))
                    .filter(|&bytes| bytes <= MAX_DECLARED_BYTES)
                    .and_then(|bytes| usize::try_from(bytes).ok())
                    .ok_or_else(|| {
                        bad(
                            line_no,
                            format!(
                                "{points} points of {offset} bytes are more data than bodyseg reads ({MAX_DECLARED_BYTES} bytes)"
                            ),
                        )
                    })?;
                let points = usize::try_from(points)
                    .map_err(|_| bad(line_no, format!("POINTS {points} is too large")))?;
                return Ok(Header {
                    fields,
                    points,
                    width,
                    height,
                    stride: offset,
                    columns: column,
                    data_bytes,
                    data: kind,
                    data_start: pos,
                    lines: line_no,
                });
            }
            other => {
                return Err(bad(line_no, format!("unknown header key '{other}'")));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lzf_literals_and_overlapping_back_references() {
        // "abc" literal, then a reference of length 6 at distance 3: "abcabcabc".
        let data = [2, b'a', b'b', b'c', (4 << 5), 2];
        assert_eq!(
            lzf_decompress(&data, 100).expect("valid"),
            b"abcabcabc".to_vec()
        );
        assert!(lzf_decompress(&[5, b'a'], 100).is_err());
        assert!(lzf_decompress(&[(1 << 5), 9], 100).is_err());
    }
}
