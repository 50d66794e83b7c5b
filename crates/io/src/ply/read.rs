//! PLY reader: header, then a fixed-stride decode of the vertex block (binary) or one
//! line per entry (ASCII). Other elements are walked past, never decoded.

use super::ascii::{AsciiLines, range_grid_ascii, skip_ascii, vertices_ascii};
use super::binary::binary;
use super::header::{Encoding, parse_header};
use super::plan::{LABEL, PIXEL, Plan, RangeGrid, is_range_grid};
use crate::{CloudFile, CloudGrid, FileLabels, IoError};
use bodyseg_core::{Label, LabeledCloud};
use std::path::Path;

/// Reads a labelled point cloud from a PLY file (ASCII or binary, either byte order).
///
/// The whole file is read into memory, then parsed by [`parse_ply`], which documents
/// what is accepted.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read, otherwise as [`parse_ply`].
pub fn read_ply(path: &Path) -> Result<LabeledCloud, IoError> {
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    parse_ply(&bytes, path)
}

/// Reads a PLY file as it is ([`parse_ply_file`]): labels of any kind or none.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read, otherwise as [`parse_ply_file`].
pub fn read_ply_file(path: &Path) -> Result<CloudFile, IoError> {
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    parse_ply_file(&bytes, path)
}

/// Parses a labelled point cloud from the bytes of a PLY file whose vertices must carry
/// bodyseg's class ids: [`parse_ply_file`], refusing a file without `label` or with a
/// label that is no class id.
///
/// # Errors
/// As [`parse_ply_file`]; [`IoError::MissingProperty`] when `label` is not declared;
/// [`IoError::ForeignLabels`] for a label outside 0..=6 and 255 (naming the vertex).
pub fn parse_ply(bytes: &[u8], path_for_errors: &Path) -> Result<LabeledCloud, IoError> {
    let file = parse_ply_file(bytes, path_for_errors)?;
    if file.labels == FileLabels::Absent {
        return Err(IoError::MissingProperty {
            element: "vertex".into(),
            property: "label".into(),
            path: path_for_errors.to_path_buf(),
        });
    }
    file.into_class_labels("vertex", path_for_errors)
}

/// Parses a point cloud from the bytes of a PLY file; `path_for_errors` only names the
/// file in error messages.
///
/// Accepted: formats `ascii`, `binary_little_endian`, `binary_big_endian`; every PLY
/// scalar type under either spelling (`uchar`/`uint8`, `float`/`float32`, ...); any
/// number of other elements (such as `face`) with scalar or list properties, before or
/// after the vertex element; `comment` and `obj_info` lines. Of the `vertex` element:
///
/// | property | required | stored as | accepted values |
/// |---|---|---|---|
/// | `x`, `y`, `z` | yes | [`LabeledCloud::positions_m`] (`f32`, metres) | finite in `f32` |
/// | `label` | no | [`LabeledCloud::labels`]; [`FileLabels::Classes`] | 0..=6, or 255 = unknown; absent: all unknown, [`FileLabels::Absent`]; any other value (another tool's ids): all unknown, [`FileLabels::Foreign`] |
/// | `red`, `green`, `blue` | no (all three or ignored) | [`LabeledCloud::colors`] (none when a comment says `red green blue = class palette`, as bodyseg writes by default) | integer types 0..=255; float types 0..=1, scaled by 255 and rounded |
/// | `camera` | no (absent: 0) | [`PointOrigin::camera`] | 0..=255 |
/// | `pixel` | no (absent: the vertex index, or its grid cell) | [`PointOrigin::pixel`] | 0..=2³²−1 |
///
/// Integer-valued properties may be stored in any type, floats included, as long as the
/// value is a whole number in range. Other vertex properties are ignored.
///
/// An organised cloud as PCL writes it (`obj_info num_cols W`, `obj_info num_rows H`,
/// only the valid points as vertices and an element `range_grid` of `W × H` lists that
/// hold each cell's vertex, if any) reads with [`CloudFile::grid`] set and each vertex's
/// pixel its cell (unless a `pixel` property says otherwise); so does one with
/// `num_cols`/`num_rows` and exactly `W × H` vertices in row-major order.
///
/// ASCII data is read one entry per line (blank lines skipped); every entry line must end
/// with a newline, since a file cut inside its last number would otherwise read as a
/// different, valid number. Data after the last declared element is ignored.
///
/// # Errors
/// [`IoError::NotPly`], [`IoError::UnterminatedHeader`], [`IoError::UnsupportedFormat`],
/// [`IoError::BadHeader`] for the header; [`IoError::MissingElement`] and
/// [`IoError::MissingProperty`] when `vertex`, `x`, `y` or `z` is not declared;
/// [`IoError::Truncated`] when any element has fewer entries than declared;
/// [`IoError::BadValue`] for a value outside the table above (naming the vertex);
/// [`IoError::BadAsciiLine`] for an ASCII line with too few or too many values.
pub fn parse_ply_file(bytes: &[u8], path_for_errors: &Path) -> Result<CloudFile, IoError> {
    let path = path_for_errors;
    let header = parse_header(bytes, path)?;
    let vi = header
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| IoError::MissingElement {
            element: "vertex".into(),
            path: path.to_path_buf(),
        })?;
    let plan = Plan::new(&header.elements[vi], path)?;
    let data = &bytes[header.data_offset..];
    let (before, rest) = header.elements.split_at(vi);
    let (vertex, after) = (&rest[0], &rest[1..]);
    let organised = matches!(header.grid, (Some(w), Some(h)) if w > 0 && h > 0);
    let (mut vertices, range_grid) = match header.encoding {
        Encoding::Ascii => {
            let mut lines = AsciiLines {
                data,
                pos: 0,
                line_no: header.lines,
            };
            for e in before {
                skip_ascii(&mut lines, e, path)?;
            }
            let vertices = vertices_ascii(&mut lines, vertex, &plan, path)?;
            let mut range_grid = None;
            for e in after {
                if organised && is_range_grid(e) {
                    range_grid = Some(range_grid_ascii(&mut lines, e, path)?);
                } else {
                    skip_ascii(&mut lines, e, path)?;
                }
            }
            (vertices, range_grid)
        }
        Encoding::BinaryLittleEndian => {
            binary::<false>(data, before, vertex, after, &plan, organised, path)?
        }
        Encoding::BinaryBigEndian => {
            binary::<true>(data, before, vertex, after, &plan, organised, path)?
        }
    };
    // bodyseg's own files may colour the points by class: that is no camera colour.
    if header.palette_colors {
        vertices.cloud.colors = None;
    }
    let labels = match (plan.has(LABEL), vertices.foreign) {
        (false, _) => FileLabels::Absent,
        (true, None) => FileLabels::Classes,
        (true, Some((index, value))) => {
            // Not our ids: none of them is a class (a segment id 3 is no upper arm).
            vertices.cloud.labels.fill(Label::UNKNOWN);
            FileLabels::Foreign { index, value }
        }
    };
    let mut cloud = vertices.cloud;
    let grid = match header.grid {
        (Some(width), Some(height)) if organised => {
            place_on_grid(&mut cloud, width, height, range_grid, plan.has(PIXEL))
        }
        _ => None,
    };
    Ok(CloudFile {
        cloud,
        labels,
        grid,
    })
}

/// The grid of an organised PLY: each vertex's pixel set to its cell (from `range_grid`,
/// else the vertex index when there are exactly `width × height` vertices; a `pixel`
/// property is kept), every cell's colour. `None` when the vertices
/// cannot be placed: no `range_grid` of `width × height` cells and another vertex count,
/// or a `range_grid` that names a vertex twice or one that does not exist.
fn place_on_grid(
    cloud: &mut LabeledCloud,
    width: u32,
    height: u32,
    range_grid: Option<RangeGrid>,
    has_pixel: bool,
) -> Option<CloudGrid> {
    let cells = (width as usize).checked_mul(height as usize)?;
    let n = cloud.len();
    // Bounded by the data: the range grid was decoded from it, the vertices too.
    let cell_of: Vec<u32> = match range_grid {
        Some(range) if range.len() == cells => {
            let mut cell_of = vec![u32::MAX; n];
            for (cell, v) in range.iter().enumerate() {
                if let Some(v) = *v {
                    match cell_of.get_mut(v as usize) {
                        Some(c) if *c == u32::MAX => *c = cell as u32,
                        // A vertex out of range, or named twice.
                        _ => return None,
                    }
                }
            }
            if cell_of.contains(&u32::MAX) {
                return None; // a vertex without a cell
            }
            cell_of
        }
        None if n == cells => (0..n as u32).collect(),
        // num_cols/num_rows without a range_grid of as many cells, or as many vertices.
        _ => return None,
    };
    if !has_pixel {
        for (o, &c) in cloud.origins.iter_mut().zip(&cell_of) {
            o.pixel = c;
        }
    }
    let colors = cloud.colors.as_ref().map(|colors| {
        let mut all = vec![[0u8; 3]; cells];
        for (&c, &rgb) in cell_of.iter().zip(colors) {
            all[c as usize] = rgb;
        }
        all
    });
    Some(CloudGrid {
        width,
        height,
        colors,
    })
}
