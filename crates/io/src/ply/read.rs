//! PLY reader: header, then a fixed-stride decode of the vertex block (binary) or one
//! line per entry (ASCII). Other elements are walked past, never decoded.

use super::header::{Element, Encoding, PropKind, Scalar, parse_header};
use crate::{CloudFile, CloudGrid, FileLabels, IoError};
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use std::path::Path;

/// The vertex properties we read, in a fixed order; values travel as `f64`, which holds
/// every PLY scalar type exactly.
const ROLES: [&str; NROLES] = [
    "x", "y", "z", "label", "red", "green", "blue", "camera", "pixel",
];
const NROLES: usize = 9;
const X: usize = 0;
const Y: usize = 1;
const Z: usize = 2;
const LABEL: usize = 3;
const RED: usize = 4;
const GREEN: usize = 5;
const BLUE: usize = 6;
const CAMERA: usize = 7;
const PIXEL: usize = 8;
/// Roles without which a file is rejected.
const REQUIRED: [usize; 3] = [X, Y, Z];
/// Roles that must be scalars when present (a list there is a malformed file).
const SCALAR_ONLY: [usize; 4] = [X, Y, Z, LABEL];

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

/// PCL's element of an organised cloud's cells: one list property, each cell's vertex.
fn is_range_grid(e: &Element) -> bool {
    e.name == "range_grid"
        && matches!(e.props[..], [ref p] if matches!(p.kind, PropKind::List { .. }))
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

/// Which vertex property feeds each role, and its type.
struct Plan {
    /// Property index per role; `None` when absent (colours: all three or none).
    prop: [Option<usize>; NROLES],
    /// Type per role (meaningless where `prop` is `None`).
    ty: [Scalar; NROLES],
}

impl Plan {
    fn new(vertex: &Element, path: &Path) -> Result<Plan, IoError> {
        let mut plan = Plan {
            prop: [None; NROLES],
            ty: [Scalar::U8; NROLES],
        };
        for (role, name) in ROLES.iter().enumerate() {
            let Some((k, p)) = vertex
                .props
                .iter()
                .enumerate()
                .find(|(_, p)| p.name == *name)
            else {
                continue;
            };
            match p.kind {
                PropKind::Scalar(s) => {
                    plan.prop[role] = Some(k);
                    plan.ty[role] = s;
                }
                PropKind::List { .. } if SCALAR_ONLY.contains(&role) => {
                    return Err(IoError::BadHeader {
                        line: p.line,
                        reason: format!("vertex property '{name}' is a list, expected a scalar"),
                        path: path.to_path_buf(),
                    });
                }
                PropKind::List { .. } => {} // an optional role we cannot use: ignored
            }
        }
        for role in REQUIRED {
            if plan.prop[role].is_none() {
                return Err(IoError::MissingProperty {
                    element: "vertex".into(),
                    property: ROLES[role].into(),
                    path: path.to_path_buf(),
                });
            }
        }
        if [RED, GREEN, BLUE].iter().any(|&r| plan.prop[r].is_none()) {
            for r in [RED, GREEN, BLUE] {
                plan.prop[r] = None;
            }
        }
        Ok(plan)
    }

    fn has(&self, role: usize) -> bool {
        self.prop[role].is_some()
    }

    /// The role of each vertex property (`None` = ignored).
    fn role_of_prop(&self, vertex: &Element) -> Vec<Option<usize>> {
        let mut roles = vec![None; vertex.props.len()];
        for (role, prop) in self.prop.iter().enumerate() {
            if let Some(k) = prop {
                roles[*k] = Some(role);
            }
        }
        roles
    }
}

/// PCL's `range_grid` of an organised PLY: each cell's first vertex index, if any.
type RangeGrid = Vec<Option<u32>>;

/// The vertices read, and the first label that is no class id (vertex, value).
struct Vertices {
    cloud: LabeledCloud,
    foreign: Option<(usize, String)>,
}

/// Collects validated vertices into a cloud.
struct Sink<'a> {
    cloud: LabeledCloud,
    foreign: Option<(usize, String)>,
    plan: &'a Plan,
    path: &'a Path,
}

impl<'a> Sink<'a> {
    /// `capacity` must already be bounded by the data size (a header may lie).
    fn new(plan: &'a Plan, capacity: usize, path: &'a Path) -> Sink<'a> {
        let has_colors = plan.has(RED);
        Sink {
            cloud: LabeledCloud {
                positions_m: Vec::with_capacity(capacity),
                labels: Vec::with_capacity(capacity),
                colors: has_colors.then(|| Vec::with_capacity(capacity)),
                origins: Vec::with_capacity(capacity),
            },
            foreign: None,
            plan,
            path,
        }
    }

    fn finish(self) -> Vertices {
        Vertices {
            cloud: self.cloud,
            foreign: self.foreign,
        }
    }

    /// Validates and appends vertex `index` (`v` indexed by role).
    #[inline]
    fn push(&mut self, index: usize, v: &[f64; NROLES]) -> Result<(), IoError> {
        let p = [v[X] as f32, v[Y] as f32, v[Z] as f32];
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            let role = (X..=Z).find(|&r| !(v[r] as f32).is_finite()).unwrap_or(X);
            return Err(self.bad(index, role, v, "a finite number (within float range)"));
        }
        let label = if self.plan.has(LABEL) {
            let class = whole(v[LABEL], 255.0).and_then(|id| Label::from_id(id as u8));
            class.unwrap_or_else(|| {
                // Another tool's ids; the caller decides (FileLabels::Foreign).
                self.foreign
                    .get_or_insert_with(|| (index, v[LABEL].to_string()));
                Label::UNKNOWN
            })
        } else {
            Label::UNKNOWN
        };
        if let Some(colors) = &mut self.cloud.colors {
            let mut rgb = [0u8; 3];
            for (c, role) in rgb.iter_mut().zip([RED, GREEN, BLUE]) {
                let ty = self.plan.ty[role];
                let value = if ty.is_float() {
                    (0.0..=1.0)
                        .contains(&v[role])
                        .then(|| (v[role] * 255.0).round() as u8)
                } else {
                    whole(v[role], 255.0).map(|c| c as u8)
                };
                *c = match value {
                    Some(c) => c,
                    None => {
                        let want = if ty.is_float() { "0..=1" } else { "0..=255" };
                        return Err(bad_value(index, role, v, want, self.path));
                    }
                };
            }
            colors.push(rgb);
        }
        let camera = if self.plan.has(CAMERA) {
            whole(v[CAMERA], 255.0).ok_or_else(|| self.bad(index, CAMERA, v, "0..=255"))? as u8
        } else {
            0
        };
        let pixel = if self.plan.has(PIXEL) {
            whole(v[PIXEL], f64::from(u32::MAX))
                .ok_or_else(|| self.bad(index, PIXEL, v, "0..=4294967295"))?
        } else {
            u32::try_from(index).map_err(|_| IoError::BadValue {
                element: "vertex".into(),
                index,
                property: "pixel".into(),
                value: "absent".into(),
                expected: "a pixel property in clouds of more than 2^32 points",
                path: self.path.to_path_buf(),
            })?
        };
        self.cloud.positions_m.push(p);
        self.cloud.labels.push(label);
        self.cloud.origins.push(PointOrigin { camera, pixel });
        Ok(())
    }

    #[cold]
    fn bad(&self, index: usize, role: usize, v: &[f64; NROLES], expected: &'static str) -> IoError {
        bad_value(index, role, v, expected, self.path)
    }
}

#[cold]
fn bad_value(
    index: usize,
    role: usize,
    v: &[f64; NROLES],
    expected: &'static str,
    path: &Path,
) -> IoError {
    IoError::BadValue {
        element: "vertex".into(),
        index,
        property: ROLES[role].into(),
        value: v[role].to_string(),
        expected,
        path: path.to_path_buf(),
    }
}

/// `v` as a whole number in `0..=max`.
#[inline]
fn whole(v: f64, max: f64) -> Option<u32> {
    // NaN fails both comparisons.
    (v >= 0.0 && v <= max && v.fract() == 0.0).then_some(v as u32)
}

fn truncated(element: &Element, read: usize, path: &Path) -> IoError {
    IoError::Truncated {
        element: element.name.clone(),
        expected: element.count,
        read,
        path: path.to_path_buf(),
    }
}

// ---------------------------------------------------------------------------------------
// Binary

/// One scalar of type `ty` at `b[off..]`, widened to `f64` (exact for every PLY type).
#[inline(always)]
fn read_scalar<const BIG_ENDIAN: bool>(b: &[u8], off: usize, ty: Scalar) -> f64 {
    macro_rules! num {
        ($t:ty, $n:literal) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[off..off + $n]);
            if BIG_ENDIAN {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            }
        }};
    }
    match ty {
        Scalar::I8 => f64::from(i8::from_ne_bytes([b[off]])),
        Scalar::U8 => f64::from(b[off]),
        Scalar::I16 => f64::from(num!(i16, 2)),
        Scalar::U16 => f64::from(num!(u16, 2)),
        Scalar::I32 => f64::from(num!(i32, 4)),
        Scalar::U32 => f64::from(num!(u32, 4)),
        Scalar::F32 => f64::from(num!(f32, 4)),
        Scalar::F64 => num!(f64, 8),
    }
}

/// The vertices, and with `organised` the `range_grid` element's cells (each one's first
/// vertex index, if any) when the file has one after the vertices.
fn binary<const BIG_ENDIAN: bool>(
    data: &[u8],
    before: &[Element],
    vertex: &Element,
    after: &[Element],
    plan: &Plan,
    organised: bool,
    path: &Path,
) -> Result<(Vertices, Option<RangeGrid>), IoError> {
    let mut pos = 0;
    for e in before {
        skip_binary::<BIG_ENDIAN>(data, &mut pos, e, path)?;
    }
    let vertices = match vertex.fixed_stride() {
        Some(stride) => vertices_fixed::<BIG_ENDIAN>(data, &mut pos, stride, vertex, plan, path)?,
        None => vertices_walked::<BIG_ENDIAN>(data, &mut pos, vertex, plan, path)?,
    };
    let mut range_grid = None;
    for e in after {
        if organised && is_range_grid(e) {
            range_grid = Some(range_grid_binary::<BIG_ENDIAN>(data, &mut pos, e, path)?);
        } else {
            skip_binary::<BIG_ENDIAN>(data, &mut pos, e, path)?;
        }
    }
    Ok((vertices, range_grid))
}

/// Decodes PCL's `range_grid` (one list per cell) in binary: each cell's first vertex
/// index, `None` for an empty list (or an index that is no `u32`).
fn range_grid_binary<const BIG_ENDIAN: bool>(
    data: &[u8],
    pos: &mut usize,
    element: &Element,
    path: &Path,
) -> Result<Vec<Option<u32>>, IoError> {
    let PropKind::List { count, item } = element.props[0].kind else {
        return Err(truncated(element, 0, path)); // is_range_grid checked the kind
    };
    let fits = |p: usize, len: usize| p.checked_add(len).is_some_and(|end| end <= data.len());
    // Each cell takes at least one byte, which bounds the capacity.
    let mut out = Vec::with_capacity(element.count.min(data.len() - *pos));
    for i in 0..element.count {
        let p = *pos;
        if !fits(p, count.size()) {
            return Err(truncated(element, i, path));
        }
        let n = read_scalar::<BIG_ENDIAN>(data, p, count);
        let items = p + count.size();
        let len = whole(n, f64::from(u32::MAX)).and_then(|n| (n as usize).checked_mul(item.size()));
        let Some(len) = len.filter(|&len| fits(items, len)) else {
            return Err(truncated(element, i, path));
        };
        let first = (len > 0).then(|| read_scalar::<BIG_ENDIAN>(data, items, item));
        out.push(first.and_then(|v| whole(v, f64::from(u32::MAX))));
        *pos = items + len;
    }
    Ok(out)
}

/// The common case: every vertex property is a scalar, so vertex `i` starts at
/// `i * stride` and each role sits at a fixed offset.
fn vertices_fixed<const BIG_ENDIAN: bool>(
    data: &[u8],
    pos: &mut usize,
    stride: usize,
    vertex: &Element,
    plan: &Plan,
    path: &Path,
) -> Result<Vertices, IoError> {
    let rest = &data[*pos..];
    // stride > 0: the vertex element has at least x, y, z.
    let need = stride
        .checked_mul(vertex.count)
        .filter(|&need| need <= rest.len())
        .ok_or_else(|| truncated(vertex, rest.len() / stride.max(1), path))?;
    let mut prop_offset = Vec::with_capacity(vertex.props.len());
    let mut off = 0;
    for p in &vertex.props {
        prop_offset.push(off);
        if let PropKind::Scalar(s) = p.kind {
            off += s.size();
        }
    }
    // (role, offset, type) of each role present; the inner loop only reads these.
    let fields: Vec<(usize, usize, Scalar)> = (0..NROLES)
        .filter_map(|r| plan.prop[r].map(|k| (r, prop_offset[k], plan.ty[r])))
        .collect();
    let block = &rest[..need];
    *pos += need;
    if let Some(vertices) = vertices_common::<BIG_ENDIAN>(block, stride, &fields, plan) {
        return Ok(vertices);
    }
    // Other types, or a bad value somewhere: the general path (which names the vertex).
    let mut sink = Sink::new(plan, vertex.count, path);
    let mut v = [0.0; NROLES];
    for (i, rec) in block.chunks_exact(stride).enumerate() {
        for &(role, off, ty) in &fields {
            v[role] = read_scalar::<BIG_ENDIAN>(rec, off, ty);
        }
        sink.push(i, &v)?;
    }
    Ok(sink.finish())
}

#[inline(always)]
fn f32_at<const BIG_ENDIAN: bool>(rec: &[u8], off: usize) -> f32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&rec[off..off + 4]);
    if BIG_ENDIAN {
        f32::from_be_bytes(a)
    } else {
        f32::from_le_bytes(a)
    }
}

#[inline(always)]
fn u32_at<const BIG_ENDIAN: bool>(rec: &[u8], off: usize) -> u32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&rec[off..off + 4]);
    if BIG_ENDIAN {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}

/// The fast path for the layout nearly every writer (ours included) uses: `float`
/// coordinates, `uchar` label, colours and camera, `uint` pixel. No per-value type
/// dispatch and no per-vertex error branch: validity is accumulated and checked once.
/// Returns `None` when the types differ or any value is invalid; the general path then
/// decodes the block again and reports the first bad vertex.
fn vertices_common<const BIG_ENDIAN: bool>(
    block: &[u8],
    stride: usize,
    fields: &[(usize, usize, Scalar)],
    plan: &Plan,
) -> Option<Vertices> {
    let mut off: [Option<usize>; NROLES] = [None; NROLES];
    for &(role, o, ty) in fields {
        let want = match role {
            X | Y | Z => Scalar::F32,
            PIXEL => Scalar::U32,
            _ => Scalar::U8,
        };
        if ty != want {
            return None;
        }
        off[role] = Some(o);
    }
    let n = block.len() / stride;
    let (ox, oy, oz, ol) = (off[X]?, off[Y]?, off[Z]?, off[LABEL]);
    let rgb = match (off[RED], off[GREEN], off[BLUE]) {
        (Some(r), Some(g), Some(b)) => Some((r, g, b)),
        _ => None,
    };
    let (ocam, opix) = (off[CAMERA], off[PIXEL]);
    if opix.is_none() && u32::try_from(n).is_err() {
        return None;
    }
    // Column by column: each pass is a tight loop over the (cache-warm) block, and
    // collecting from `chunks_exact` allocates once with no per-push capacity check.
    let records = || block.chunks_exact(stride);
    let mut ok = true;
    let positions_m: Vec<_> = records()
        .map(|rec| {
            let p = [
                f32_at::<BIG_ENDIAN>(rec, ox),
                f32_at::<BIG_ENDIAN>(rec, oy),
                f32_at::<BIG_ENDIAN>(rec, oz),
            ];
            ok &= p[0].is_finite() & p[1].is_finite() & p[2].is_finite();
            p
        })
        .collect();
    let mut labels_ok = true;
    let mut labels: Vec<_> = match ol {
        Some(ol) => records()
            .map(|rec| {
                let label = Label::from_id(rec[ol]);
                labels_ok &= label.is_some();
                label.unwrap_or(Label::UNKNOWN)
            })
            .collect(),
        None => vec![Label::UNKNOWN; n],
    };
    // Another tool's ids: the first one, and every label unknown.
    let foreign = match ol {
        Some(ol) if !labels_ok => {
            let index = records().position(|rec| Label::from_id(rec[ol]).is_none())?;
            labels.fill(Label::UNKNOWN);
            Some((index, block[index * stride + ol].to_string()))
        }
        _ => None,
    };
    let colors = rgb.map(|(r, g, b)| records().map(|rec| [rec[r], rec[g], rec[b]]).collect());
    let origins = records()
        .enumerate()
        .map(|(i, rec)| PointOrigin {
            camera: ocam.map_or(0, |o| rec[o]),
            // i < n <= u32::MAX when there is no pixel property (checked above).
            pixel: opix.map_or(i as u32, |o| u32_at::<BIG_ENDIAN>(rec, o)),
        })
        .collect();
    debug_assert_eq!(plan.has(RED), colors.is_some());
    ok.then_some(Vertices {
        cloud: LabeledCloud {
            positions_m,
            labels,
            colors,
            origins,
        },
        foreign,
    })
}

/// The rare case of a vertex element with list properties: walk each entry.
fn vertices_walked<const BIG_ENDIAN: bool>(
    data: &[u8],
    pos: &mut usize,
    vertex: &Element,
    plan: &Plan,
    path: &Path,
) -> Result<Vertices, IoError> {
    let roles = plan.role_of_prop(vertex);
    // Each entry takes at least one byte (x is a scalar), which bounds the capacity.
    let mut sink = Sink::new(plan, vertex.count.min(data.len() - *pos), path);
    let mut v = [0.0; NROLES];
    for i in 0..vertex.count {
        let complete = walk_entry::<BIG_ENDIAN>(data, pos, vertex, i, path, |k, off| {
            if let Some(role) = roles[k] {
                v[role] = read_scalar::<BIG_ENDIAN>(data, off, plan.ty[role]);
            }
        })?;
        if !complete {
            return Err(truncated(vertex, i, path));
        }
        sink.push(i, &v)?;
    }
    Ok(sink.finish())
}

/// Moves `pos` past every entry of an element we do not read.
fn skip_binary<const BIG_ENDIAN: bool>(
    data: &[u8],
    pos: &mut usize,
    element: &Element,
    path: &Path,
) -> Result<(), IoError> {
    let rest = data.len() - *pos;
    if let Some(stride) = element.fixed_stride() {
        match stride.checked_mul(element.count) {
            Some(need) if need <= rest => {
                *pos += need;
                Ok(())
            }
            _ => Err(truncated(element, rest / stride.max(1), path)),
        }
    } else {
        for i in 0..element.count {
            if !walk_entry::<BIG_ENDIAN>(data, pos, element, i, path, |_, _| {})? {
                return Err(truncated(element, i, path));
            }
        }
        Ok(())
    }
}

/// Walks one binary entry starting at `pos`, calling `at(property index, byte offset)`
/// for each scalar property. Returns `false` (leaving `pos`) when the data ends inside it.
fn walk_entry<const BIG_ENDIAN: bool>(
    data: &[u8],
    pos: &mut usize,
    element: &Element,
    index: usize,
    path: &Path,
    mut at: impl FnMut(usize, usize),
) -> Result<bool, IoError> {
    let mut p = *pos;
    let fits = |p: usize, len: usize| p.checked_add(len).is_some_and(|end| end <= data.len());
    for (k, prop) in element.props.iter().enumerate() {
        match prop.kind {
            PropKind::Scalar(s) => {
                if !fits(p, s.size()) {
                    return Ok(false);
                }
                at(k, p);
                p += s.size();
            }
            PropKind::List { count, item } => {
                if !fits(p, count.size()) {
                    return Ok(false);
                }
                let n = read_scalar::<BIG_ENDIAN>(data, p, count);
                p += count.size();
                // Integer count types only (checked in the header): whole, at most 2³²−1.
                if n < 0.0 {
                    return Err(IoError::BadValue {
                        element: element.name.clone(),
                        index,
                        property: prop.name.clone(),
                        value: n.to_string(),
                        expected: "a list length >= 0",
                        path: path.to_path_buf(),
                    });
                }
                let len = (n as usize).checked_mul(item.size());
                match len {
                    Some(len) if fits(p, len) => p += len,
                    _ => return Ok(false),
                }
            }
        }
    }
    *pos = p;
    Ok(true)
}

// ---------------------------------------------------------------------------------------
// ASCII

/// Newline-terminated, non-blank lines of ASCII PLY data.
struct AsciiLines<'a> {
    data: &'a [u8],
    pos: usize,
    /// 1-based number of the last line returned (counting header lines).
    line_no: usize,
}

impl<'a> AsciiLines<'a> {
    /// The next non-blank line and its number; `None` at the end of the data or when the
    /// last line has no newline (a cut file).
    fn next_entry(&mut self) -> Option<(usize, &'a [u8])> {
        loop {
            let rest = self.data.get(self.pos..).filter(|r| !r.is_empty())?;
            let len = rest.iter().position(|&b| b == b'\n')?;
            self.pos += len + 1;
            self.line_no += 1;
            let line = &rest[..len];
            if !line.iter().all(u8::is_ascii_whitespace) {
                return Some((self.line_no, line));
            }
        }
    }
}

/// Parses one ASCII token as a value of type `ty`, widened to `f64`.
fn parse_token(tok: &[u8], ty: Scalar) -> Option<f64> {
    let text = std::str::from_utf8(tok).ok()?;
    match ty.int_range() {
        Some((lo, hi)) => {
            let n: i64 = text.parse().ok()?;
            (lo..=hi).contains(&n).then_some(n as f64)
        }
        // Parse floats at their own precision: going through f64 would round twice.
        None if ty == Scalar::F32 => text.parse::<f32>().ok().map(f64::from),
        None => text.parse::<f64>().ok(),
    }
}

/// Splits one entry line into values, storing the ones `roles` asks for in `v`.
fn ascii_entry(
    (line_no, line): (usize, &[u8]),
    element: &Element,
    index: usize,
    roles: &[Option<usize>],
    v: &mut [f64; NROLES],
    path: &Path,
) -> Result<(), IoError> {
    let mut toks = line
        .split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty());
    let line_error = |reason: &str| IoError::BadAsciiLine {
        line: line_no,
        element: element.name.clone(),
        index,
        reason: reason.into(),
        path: path.to_path_buf(),
    };
    let bad = |prop: &str, tok: &[u8], expected: &'static str| IoError::BadValue {
        element: element.name.clone(),
        index,
        property: prop.into(),
        value: String::from_utf8_lossy(tok).into_owned(),
        expected,
        path: path.to_path_buf(),
    };
    const SHORT: &str = "fewer values than the header declares";
    for (k, prop) in element.props.iter().enumerate() {
        let tok = toks.next().ok_or_else(|| line_error(SHORT))?;
        match prop.kind {
            PropKind::Scalar(ty) => {
                if let Some(role) = roles.get(k).copied().flatten() {
                    v[role] =
                        parse_token(tok, ty).ok_or_else(|| bad(&prop.name, tok, ty.describe()))?;
                }
            }
            PropKind::List { count, .. } => {
                let n = parse_token(tok, count)
                    .filter(|&n| n >= 0.0)
                    .ok_or_else(|| bad(&prop.name, tok, "a list length >= 0"))?;
                for _ in 0..n as u64 {
                    toks.next().ok_or_else(|| line_error(SHORT))?;
                }
            }
        }
    }
    if toks.next().is_some() {
        return Err(line_error("more values than the header declares"));
    }
    Ok(())
}

/// Decodes PCL's `range_grid` (one list per cell, one line each) in ASCII: each cell's
/// first vertex index, `None` for an empty list.
fn range_grid_ascii(
    lines: &mut AsciiLines<'_>,
    element: &Element,
    path: &Path,
) -> Result<Vec<Option<u32>>, IoError> {
    let PropKind::List { count, item } = element.props[0].kind else {
        return Err(truncated(element, 0, path)); // is_range_grid checked the kind
    };
    // A line takes at least 2 bytes ("0\n"), which bounds the capacity.
    let mut out = Vec::with_capacity(element.count.min(lines.data.len() / 2));
    for i in 0..element.count {
        let (line_no, line) = lines
            .next_entry()
            .ok_or_else(|| truncated(element, i, path))?;
        let toks: Vec<&[u8]> = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty())
            .collect();
        let n = toks.first().and_then(|t| parse_token(t, count));
        let items = &toks[1.min(toks.len())..];
        if n != Some(items.len() as f64) {
            return Err(IoError::BadAsciiLine {
                line: line_no,
                element: element.name.clone(),
                index: i,
                reason: "the list's length is not the number of values after it".into(),
                path: path.to_path_buf(),
            });
        }
        let first = items.first().and_then(|t| parse_token(t, item));
        out.push(first.and_then(|v| whole(v, f64::from(u32::MAX))));
    }
    Ok(out)
}

fn skip_ascii(lines: &mut AsciiLines<'_>, element: &Element, path: &Path) -> Result<(), IoError> {
    let mut unused = [0.0; NROLES];
    for i in 0..element.count {
        let line = lines
            .next_entry()
            .ok_or_else(|| truncated(element, i, path))?;
        ascii_entry(line, element, i, &[], &mut unused, path)?;
    }
    Ok(())
}

fn vertices_ascii(
    lines: &mut AsciiLines<'_>,
    vertex: &Element,
    plan: &Plan,
    path: &Path,
) -> Result<Vertices, IoError> {
    let roles = plan.role_of_prop(vertex);
    // An entry line takes at least 2 bytes ("0\n"), which bounds the capacity.
    let capacity = vertex.count.min(lines.data.len() / 2);
    let mut sink = Sink::new(plan, capacity, path);
    let mut v = [0.0; NROLES];
    for i in 0..vertex.count {
        let line = lines
            .next_entry()
            .ok_or_else(|| truncated(vertex, i, path))?;
        ascii_entry(line, vertex, i, &roles, &mut v, path)?;
        sink.push(i, &v)?;
    }
    Ok(sink.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_accepts_only_whole_numbers_in_range() {
        assert_eq!(whole(0.0, 255.0), Some(0));
        assert_eq!(whole(255.0, 255.0), Some(255));
        assert_eq!(
            whole(f64::from(u32::MAX), f64::from(u32::MAX)),
            Some(u32::MAX)
        );
        for bad in [256.0, -1.0, 0.5, f64::NAN, f64::INFINITY] {
            assert_eq!(whole(bad, 255.0), None, "{bad}");
        }
    }

    #[test]
    fn tokens_parse_at_their_declared_type() {
        assert_eq!(parse_token(b"255", Scalar::U8), Some(255.0));
        assert_eq!(parse_token(b"256", Scalar::U8), None);
        assert_eq!(parse_token(b"-128", Scalar::I8), Some(-128.0));
        assert_eq!(parse_token(b"+7", Scalar::I32), Some(7.0));
        assert_eq!(parse_token(b"1.0", Scalar::U8), None);
        assert_eq!(parse_token(b"1e2", Scalar::F64), Some(100.0));
        assert_eq!(parse_token(b"x", Scalar::F32), None);
        // Just above 1 + 2^-24, the midpoint between 1.0 and the next f32: parsed at f32
        // precision it rounds up; through f64 it would first round to the midpoint, then
        // (ties to even) down to 1.0.
        let text = b"1.00000005960464477539062500000000000086736173798840354720596224069595336914";
        let want = f32::from_bits(1.0f32.to_bits() + 1);
        assert_eq!(parse_token(text, Scalar::F32), Some(f64::from(want)));
    }
}
