//! PLY binary decoding, either byte order: a fixed-stride pass over the vertex block when
//! its records have a fixed size, otherwise a walk entry by entry.

use super::header::{Element, PropKind, Scalar};
use super::plan::{
    BLUE, CAMERA, GREEN, LABEL, NROLES, PIXEL, Plan, RED, RangeGrid, Sink, Vertices, X, Y, Z,
    is_range_grid, truncated, whole,
};
use crate::IoError;
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use std::path::Path;

/// One scalar of type `ty` at `b[off..]`, widened to `f64` (exact for every PLY type).
#[inline(always)]
pub(crate) fn read_scalar<const BIG_ENDIAN: bool>(b: &[u8], off: usize, ty: Scalar) -> f64 {
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
pub(crate) fn binary<const BIG_ENDIAN: bool>(
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
pub(crate) fn range_grid_binary<const BIG_ENDIAN: bool>(
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
pub(crate) fn vertices_fixed<const BIG_ENDIAN: bool>(
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

/// The `f32` at byte `off` of `rec`: its bits as [`u32_at`] reads them (what
/// `f32::from_{be,le}_bytes` do).
#[inline(always)]
pub(crate) fn f32_at<const BIG_ENDIAN: bool>(rec: &[u8], off: usize) -> f32 {
    f32::from_bits(u32_at::<BIG_ENDIAN>(rec, off))
}

#[inline(always)]
pub(crate) fn u32_at<const BIG_ENDIAN: bool>(rec: &[u8], off: usize) -> u32 {
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
pub(crate) fn vertices_common<const BIG_ENDIAN: bool>(
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
pub(crate) fn vertices_walked<const BIG_ENDIAN: bool>(
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
pub(crate) fn skip_binary<const BIG_ENDIAN: bool>(
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
pub(crate) fn walk_entry<const BIG_ENDIAN: bool>(
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
