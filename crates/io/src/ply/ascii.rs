//! PLY ASCII decoding: one line per entry, tokens parsed by declared type.

use super::header::{Element, PropKind, Scalar};
use super::plan::{NROLES, Plan, Sink, Vertices, truncated, whole};
use crate::IoError;
use std::path::Path;

/// Newline-terminated, non-blank lines of ASCII PLY data.
pub(crate) struct AsciiLines<'a> {
    pub(crate) data: &'a [u8],
    pub(crate) pos: usize,
    /// 1-based number of the last line returned (counting header lines).
    pub(crate) line_no: usize,
}

impl<'a> AsciiLines<'a> {
    /// The next non-blank line and its number; `None` at the end of the data or when the
    /// last line has no newline (a cut file).
    pub(crate) fn next_entry(&mut self) -> Option<(usize, &'a [u8])> {
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
pub(crate) fn parse_token(tok: &[u8], ty: Scalar) -> Option<f64> {
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
pub(crate) fn ascii_entry(
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
pub(crate) fn range_grid_ascii(
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

pub(crate) fn skip_ascii(
    lines: &mut AsciiLines<'_>,
    element: &Element,
    path: &Path,
) -> Result<(), IoError> {
    let mut unused = [0.0; NROLES];
    for i in 0..element.count {
        let line = lines
            .next_entry()
            .ok_or_else(|| truncated(element, i, path))?;
        ascii_entry(line, element, i, &[], &mut unused, path)?;
    }
    Ok(())
}

pub(crate) fn vertices_ascii(
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
