//! PLY header: the magic line, the format, and the elements with their properties.

use crate::IoError;
use std::path::Path;

/// How the data after the header is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// A PLY scalar type. Each has two spellings (`uchar` / `uint8`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type with this header name (either spelling).
    pub(crate) fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// The classic (PLY 1.0 paper) spelling, for messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// What a value of this type looks like, for messages.
    pub(crate) fn describe(self) -> &'static str {
        match self {
            Scalar::I8 => "a char (-128..=127)",
            Scalar::U8 => "a uchar (0..=255)",
            Scalar::I16 => "a short (-32768..=32767)",
            Scalar::U16 => "a ushort (0..=65535)",
            Scalar::I32 => "an int (-2147483648..=2147483647)",
            Scalar::U32 => "a uint (0..=4294967295)",
            Scalar::F32 => "a float",
            Scalar::F64 => "a double",
        }
    }

    /// Size in bytes in the binary encodings.
    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// True for the two floating-point types.
    pub(crate) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The inclusive value range of an integer type (`None` for floats).
    pub(crate) fn int_range(self) -> Option<(i64, i64)> {
        Some(match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => return None,
        })
    }
}

/// A property's type: one scalar, or a list (count type, item type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// One `property` line.
#[derive(Clone, Debug)]
pub(crate) struct Property {
    pub(crate) name: String,
    pub(crate) kind: PropKind,
    /// 1-based header line, for messages.
    pub(crate) line: usize,
}

/// One `element` line and its properties.
#[derive(Clone, Debug)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) count: usize,
    pub(crate) props: Vec<Property>,
}

impl Element {
    /// Bytes per entry in the binary encodings when every property is a scalar.
    pub(crate) fn fixed_stride(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => Some(s.size()),
                PropKind::List { .. } => None,
            })
            .sum()
    }
}

/// A parsed header.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<Element>,
    /// Byte offset of the first data byte (just after `end_header`'s newline).
    pub(crate) data_offset: usize,
    /// Number of header lines (data line numbers continue from here).
    pub(crate) lines: usize,
    /// A comment says the colours are the class palette ([`PALETTE_COMMENT`]), not the
    /// camera's.
    pub(crate) palette_colors: bool,
    /// `obj_info num_cols W` and `obj_info num_rows H` (PCL's writer, for an organised
    /// cloud): the grid's columns and rows.
    pub(crate) grid: (Option<u32>, Option<u32>),
}

/// What bodyseg's PLY comment says when red, green and blue are the class palette.
pub(crate) const PALETTE_COMMENT: &str = "red green blue = class palette";

/// Parses the header at the start of `bytes`.
pub(crate) fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err(IoError::NotPly {
            path: path.to_path_buf(),
        });
    }
    let bad = |line: usize, reason: String| IoError::BadHeader {
        line,
        reason,
        path: path.to_path_buf(),
    };
    let mut encoding = None;
    let mut palette_colors = false;
    let mut grid = (None, None);
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(IoError::UnterminatedHeader {
                path: path.to_path_buf(),
            });
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        if line_no == 1 {
            continue; // the magic, checked above
        }
        let text =
            std::str::from_utf8(raw).map_err(|_| bad(line_no, "header line is not text".into()))?;
        let mut words = text.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue; // blank line
        };
        let rest: Vec<&str> = words.collect();
        match keyword {
            "comment" => palette_colors |= text.contains(PALETTE_COMMENT),
            // Other obj_info lines, and numbers that are not a u32, are of no use here.
            "obj_info" => match rest[..] {
                ["num_cols", w] => grid.0 = w.parse().ok(),
                ["num_rows", h] => grid.1 = h.parse().ok(),
                _ => {}
            },
            "end_header" => break,
            "format" => {
                let [fmt, _version] = rest[..] else {
                    return Err(bad(
                        line_no,
                        format!("expected 'format <type> 1.0', got '{text}'"),
                    ));
                };
                encoding = Some(match fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    _ => {
                        return Err(IoError::UnsupportedFormat {
                            format: fmt.to_string(),
                            path: path.to_path_buf(),
                        });
                    }
                });
            }
            "element" => {
                let [name, count] = rest[..] else {
                    return Err(bad(
                        line_no,
                        format!("expected 'element <name> <count>', got '{text}'"),
                    ));
                };
                let count = count.parse().map_err(|_| {
                    bad(
                        line_no,
                        format!("element count '{count}' is not a non-negative integer"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let scalar = |name: &str| {
                    Scalar::from_name(name)
                        .ok_or_else(|| bad(line_no, format!("unknown property type '{name}'")))
                };
                let (kind, name) = match rest[..] {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if count.is_float() {
                            return Err(bad(
                                line_no,
                                format!(
                                    "list count type '{}' is not an integer type",
                                    count.name()
                                ),
                            ));
                        }
                        (
                            PropKind::List {
                                count,
                                item: scalar(item)?,
                            },
                            name,
                        )
                    }
                    [ty, name] if ty != "list" => (PropKind::Scalar(scalar(ty)?), name),
                    _ => {
                        return Err(bad(
                            line_no,
                            format!(
                                "expected 'property <type> <name>' or 'property list <count type> <item type> <name>', got '{text}'"
                            ),
                        ));
                    }
                };
                let Some(element) = elements.last_mut() else {
                    return Err(bad(line_no, "property before any element".into()));
                };
                element.props.push(Property {
                    name: name.to_string(),
                    kind,
                    line: line_no,
                });
            }
            other => return Err(bad(line_no, format!("unknown header keyword '{other}'"))),
        }
    }
    let encoding = encoding.ok_or_else(|| bad(line_no, "header has no 'format' line".into()))?;
    Ok(Header {
        encoding,
        elements,
        data_offset: pos,
        lines: line_no,
        palette_colors,
        grid,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Header, IoError> {
        parse_header(text.as_bytes(), Path::new("t.ply"))
    }

    #[test]
    fn parses_elements_lists_and_skips_comments() {
        let text = "ply\r\nformat binary_big_endian 1.0\ncomment hi\nobj_info x\nelement face 2\n\
             property list uint8 int32 vertex_indices\nelement vertex 3\nproperty float32 x\n\
             property uchar label\nend_header\nDATA";
        let h = parse(text).expect("valid header");
        assert_eq!(h.encoding, Encoding::BinaryBigEndian);
        assert_eq!(h.elements.len(), 2);
        assert_eq!(h.elements[0].fixed_stride(), None);
        assert_eq!(h.elements[1].count, 3);
        assert_eq!(h.elements[1].fixed_stride(), Some(5));
        assert_eq!(h.lines, 10);
        assert_eq!(&text.as_bytes()[h.data_offset..], b"DATA");
    }

    #[test]
    fn rejects_bad_headers() {
        /// A bad header and whether an error is the one it must give.
        type Case = (&'static str, fn(&IoError) -> bool);
        // The line number is checked where the error names one.
        let cases: [Case; 7] = [
            ("plx\n", |e| matches!(e, IoError::NotPly { .. })),
            ("ply\nformat ascii 1.0\nelement vertex 1\n", |e| {
                matches!(e, IoError::UnterminatedHeader { .. })
            }),
            ("ply\nformat binary_middle_endian 1.0\nend_header\n", |e| {
                matches!(e, IoError::UnsupportedFormat { .. })
            }),
            (
                "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
                |e| matches!(e, IoError::BadHeader { line: 3, .. }),
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
                |e| matches!(e, IoError::BadHeader { line: 4, .. }),
            ),
            ("ply\nelement vertex 1\nend_header\n", |e| {
                matches!(e, IoError::BadHeader { .. })
            }),
            (
                "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
                |e| matches!(e, IoError::BadHeader { line: 3, .. }),
            ),
        ];
        for (text, is_expected) in cases {
            let err = parse(text).expect_err(text);
            assert!(is_expected(&err), "{text:?}: {err:?}");
        }
    }
}
