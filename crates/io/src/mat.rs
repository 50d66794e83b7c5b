//! A reader for the subset of MATLAB's MAT-file format (Level 5, "MAT v5/v6/v7") that
//! datasets use for images: 2-D numeric matrices (`double`, `single`, integer classes),
//! stored plain or zlib-compressed (`miCOMPRESSED`, what MATLAB's default `save` and
//! `scipy.io.savemat(..., do_compression=True)` write), either byte order.
//!
//! Out of scope, each with an error that says so: MAT v7.3 (an HDF5 file), MAT v4,
//! complex, sparse, cell, struct, char and object arrays, and arrays of more than two
//! dimensions.
//!
//! Reference: MathWorks, "MAT-File Format", Level 5 chapter (file header, data element
//! tags and their small-element form, `miMATRIX` sub-elements, `miCOMPRESSED`).
//!
//! Variables are found by scanning the top-level elements: a compressed element is
//! inflated only as far as its name unless it is the one asked for, and an uncompressed
//! one is skipped with a seek, so picking one frame out of a file that holds a whole
//! sequence reads little more than that frame.

use crate::IoError;
use crate::limits::MAX_DECLARED_BYTES;
use flate2::read::ZlibDecoder;
use std::fs::File;
use std::io::{BufReader, Cursor, ErrorKind, Read, Seek, SeekFrom};
use std::path::Path;

/// Length of the Level 5 file header (text, subsystem offset, version, endian indicator).
const HEADER_LEN: usize = 128;
/// Header version of a Level 5 file.
const VERSION_5: u16 = 0x0100;
/// Header version of a v7.3 (HDF5) file.
const VERSION_73: u16 = 0x0200;
/// Data type of a matrix element.
const MI_MATRIX: u32 = 14;
/// Data type of a zlib-compressed element.
const MI_COMPRESSED: u32 = 15;
/// How many variable names an error lists before "…".
const NAMES_IN_ERRORS: usize = 6;
/// Largest array flags, dimensions or name sub-element read, bytes: 64 KiB. MATLAB names
/// are at most 63 characters and 64 KiB of dimensions are 8192 of them; the limit keeps a
/// compressed element that inflates a huge "name" from allocating it.
const MAX_ARRAY_HEADER_BYTES: u64 = 64 << 10;

/// A 2-D numeric matrix read from a MAT file, converted to `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct MatMatrix {
    /// Number of rows (MATLAB's first dimension; an image's height).
    pub rows: usize,
    /// Number of columns (an image's width).
    pub cols: usize,
    /// The values, **row-major** (`values[row * cols + col]`), converted from the file's
    /// column-major order.
    pub values: Vec<f64>,
}

impl MatMatrix {
    /// The value at (`row`, `col`), `None` outside the matrix.
    pub fn get(&self, row: usize, col: usize) -> Option<f64> {
        (row < self.rows && col < self.cols).then(|| self.values[row * self.cols + col])
    }
}

/// The names of the variables (top-level arrays of any class) in a MAT file, in file order.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be opened; [`IoError::Mat`] when it is not a
/// Level 5 MAT file (v7.3/HDF5 and v4 files are named as such) or is truncated.
pub fn read_mat_variable_names(path: &Path) -> Result<Vec<String>, IoError> {
    variable_names(&mut open(path)?, path)
}

/// [`read_mat_variable_names`] on the bytes of a MAT file; `path_for_errors` only names
/// the file in error messages.
///
/// # Errors
/// As [`read_mat_variable_names`], without the read.
pub fn parse_mat_variable_names(
    bytes: &[u8],
    path_for_errors: &Path,
) -> Result<Vec<String>, IoError> {
    variable_names(&mut Cursor::new(bytes), path_for_errors)
}

fn variable_names<R: Read + Seek>(file: &mut R, path: &Path) -> Result<Vec<String>, IoError> {
    let mut names = Vec::new();
    scan(file, path, |header| {
        names.push(header.name.clone());
        Visit::Skip
    })?;
    Ok(names)
}

/// Reads the variable `name` of a MAT file as a 2-D numeric matrix.
///
/// # Errors
/// [`IoError::Read`] when the file cannot be opened; [`IoError::Mat`] when it is not a
/// Level 5 MAT file, is truncated, has no variable `name` (the message lists the ones it
/// has), or the variable is not a real 2-D numeric matrix, or holds more than
/// [`MAX_DECLARED_BYTES`](crate::MAX_DECLARED_BYTES) of values as `f64` (its declared
/// sizes are checked against each other and that budget before its data is read).
pub fn read_mat_matrix(path: &Path, name: &str) -> Result<MatMatrix, IoError> {
    matrix(&mut open(path)?, name, path)
}

/// [`read_mat_matrix`] on the bytes of a MAT file; `path_for_errors` only names the file
/// in error messages.
///
/// # Errors
/// As [`read_mat_matrix`], without the read.
pub fn parse_mat_matrix(
    bytes: &[u8],
    name: &str,
    path_for_errors: &Path,
) -> Result<MatMatrix, IoError> {
    matrix(&mut Cursor::new(bytes), name, path_for_errors)
}

fn matrix<R: Read + Seek>(file: &mut R, name: &str, path: &Path) -> Result<MatMatrix, IoError> {
    let mut names = Vec::new();
    let found = scan(file, path, |header| {
        names.push(header.name.clone());
        if header.name == name {
            Visit::Read
        } else {
            Visit::Skip
        }
    })?;
    found.ok_or_else(|| {
        mat_error(
            path,
            format!("no variable '{name}' (it has {})", list_names(&names)),
        )
    })
}

/// `no variables` or `3 variables: 'a', 'b', 'c'` (the first few, then `…`) for error messages.
fn list_names(names: &[String]) -> String {
    if names.is_empty() {
        return "no variables".to_string();
    }
    let shown: Vec<String> = names
        .iter()
        .take(NAMES_IN_ERRORS)
        .map(|n| format!("'{n}'"))
        .collect();
    let more = if names.len() > NAMES_IN_ERRORS {
        ", …"
    } else {
        ""
    };
    format!("{} variables: {}{more}", names.len(), shown.join(", "))
}

fn mat_error(path: &Path, reason: impl Into<String>) -> IoError {
    IoError::Mat {
        reason: reason.into(),
        path: path.to_path_buf(),
    }
}

/// Byte order of a file, from its header's endian indicator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Endian {
    Little,
    Big,
}

impl Endian {
    fn u16(self, b: [u8; 2]) -> u16 {
        match self {
            Endian::Little => u16::from_le_bytes(b),
            Endian::Big => u16::from_be_bytes(b),
        }
    }

    fn u32(self, b: [u8; 4]) -> u32 {
        match self {
            Endian::Little => u32::from_le_bytes(b),
            Endian::Big => u32::from_be_bytes(b),
        }
    }
}

/// What went wrong inside the file; [`scan`] adds the path.
#[derive(Debug)]
enum Bad {
    /// An I/O error other than a short read.
    Io(std::io::Error),
    /// The content is not what the format says.
    Format(String),
}

impl From<std::io::Error> for Bad {
    fn from(e: std::io::Error) -> Bad {
        match e.kind() {
            ErrorKind::UnexpectedEof => Bad::Format("truncated file".to_string()),
            // A corrupt zlib stream reads as InvalidInput/InvalidData.
            ErrorKind::InvalidInput | ErrorKind::InvalidData => {
                Bad::Format(format!("corrupt compressed data ({e})"))
            }
            _ => Bad::Io(e),
        }
    }
}

fn bad(reason: impl Into<String>) -> Bad {
    Bad::Format(reason.into())
}

/// The start of an `miMATRIX` element: enough to decide whether to read its data.
struct ArrayHeader {
    name: String,
    class: u8,
    complex: bool,
    dims: Vec<i64>,
}

/// What [`scan`]'s visitor wants done with an array.
enum Visit {
    /// Move on to the next element.
    Skip,
    /// Read this array as a matrix and stop.
    Read,
}

/// Opens a MAT file for [`scan`].
fn open(path: &Path) -> Result<BufReader<File>, IoError> {
    let file = File::open(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    Ok(BufReader::new(file))
}

/// Walks the file's top-level elements, calling `visit` with each array's header; returns
/// the first array `visit` asks to read, or `None` when the file ends. `path` names the
/// file in errors.
fn scan<R: Read + Seek>(
    file: &mut R,
    path: &Path,
    mut visit: impl FnMut(&ArrayHeader) -> Visit,
) -> Result<Option<MatMatrix>, IoError> {
    scan_reader(file, &mut visit).map_err(|e| match e {
        Bad::Io(cause) => IoError::Read {
            cause,
            path: path.to_path_buf(),
        },
        Bad::Format(reason) => mat_error(path, reason),
    })
}

fn scan_reader<R: Read + Seek>(
    file: &mut R,
    visit: &mut impl FnMut(&ArrayHeader) -> Visit,
) -> Result<Option<MatMatrix>, Bad> {
    let endian = read_file_header(file)?;
    let mut pos = HEADER_LEN as u64;
    loop {
        let mut tag = [0u8; 8];
        if !read_exact_or_eof(file, &mut tag)? {
            return Ok(None);
        }
        let ty = endian.u32([tag[0], tag[1], tag[2], tag[3]]);
        let len = u64::from(endian.u32([tag[4], tag[5], tag[6], tag[7]]));
        let found = match ty {
            MI_MATRIX => visit_array(&mut file.by_ref().take(len), endian, visit)?,
            MI_COMPRESSED => {
                let mut inflated = ZlibDecoder::new(file.by_ref().take(len));
                let (inner_ty, inner_len, _) = read_tag(&mut inflated, endian)?;
                if inner_ty != MI_MATRIX {
                    None // Compressed non-array elements (none in practice) are skipped.
                } else {
                    visit_array(&mut inflated.take(inner_len), endian, visit)?
                }
            }
            _ => None,
        };
        if found.is_some() {
            return Ok(found);
        }
        // Uncompressed elements are padded to 8 bytes; compressed ones are not.
        let padded = if ty == MI_COMPRESSED {
            len
        } else {
            len.next_multiple_of(8)
        };
        pos += 8 + padded;
        file.seek(SeekFrom::Start(pos))?;
    }
}

/// Reads and checks the 128-byte header; returns the byte order.
fn read_file_header<R: Read>(file: &mut R) -> Result<Endian, Bad> {
    let mut header = [0u8; HEADER_LEN];
    let mut got = 0;
    while got < HEADER_LEN {
        let n = file.read(&mut header[got..])?;
        if n == 0 {
            break;
        }
        got += n;
    }
    let text = &header[..got.min(116)];
    if text.starts_with(b"\x89HDF") || text.starts_with(b"MATLAB 7.3") {
        return Err(v73());
    }
    if got < HEADER_LEN {
        return Err(bad(format!(
            "not a MAT file: {got} bytes, shorter than the {HEADER_LEN}-byte MAT v5 header"
        )));
    }
    let endian = match &header[126..128] {
        b"IM" => Endian::Little,
        b"MI" => Endian::Big,
        _ => {
            return Err(bad(
                "not a MAT v5 file: no 'IM'/'MI' endian indicator in the header (MAT v4 files are not supported)",
            ));
        }
    };
    match endian.u16([header[124], header[125]]) {
        VERSION_5 => Ok(endian),
        VERSION_73 => Err(v73()),
        other => Err(bad(format!("unsupported MAT header version 0x{other:04x}"))),
    }
}

fn v73() -> Bad {
    bad(
        "MAT v7.3 (HDF5) files are not supported; save as v7 (MATLAB: save(..., '-v7')) or with scipy.io.savemat",
    )
}

/// Fills `buf`; `Ok(false)` when the reader is at its end before the first byte.
fn read_exact_or_eof<R: Read>(r: &mut R, buf: &mut [u8]) -> Result<bool, Bad> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) if got == 0 => return Ok(false),
            Ok(0) => return Err(bad("truncated file")),
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(true)
}

/// A data element tag: `(type, byte count, small-element data)`. In the small form the
/// data (≤ 4 bytes) sits in the tag itself.
fn read_tag<R: Read>(r: &mut R, endian: Endian) -> Result<(u32, u64, Option<[u8; 4]>), Bad> {
    let mut tag = [0u8; 8];
    r.read_exact(&mut tag)?;
    let first = endian.u32([tag[0], tag[1], tag[2], tag[3]]);
    if first >> 16 != 0 {
        // Small data element: type in the low 16 bits, size in the high 16.
        let ty = match endian {
            Endian::Little => first & 0xffff,
            Endian::Big => first >> 16,
        };
        let len = match endian {
            Endian::Little => first >> 16,
            Endian::Big => first & 0xffff,
        };
        if len > 4 {
            return Err(bad(format!(
                "small data element of {len} bytes (at most 4)"
            )));
        }
        return Ok((ty, u64::from(len), Some([tag[4], tag[5], tag[6], tag[7]])));
    }
    let len = endian.u32([tag[4], tag[5], tag[6], tag[7]]);
    Ok((first, u64::from(len), None))
}

/// Reads one array header sub-element (flags, dimensions, name; at most
/// [`MAX_ARRAY_HEADER_BYTES`]): `(type, data)`.
fn read_header_sub<R: Read>(r: &mut R, endian: Endian, what: &str) -> Result<(u32, Vec<u8>), Bad> {
    let (ty, len, small) = read_tag(r, endian)?;
    if len > MAX_ARRAY_HEADER_BYTES {
        return Err(bad(format!(
            "array {what} element of {len} bytes (at most {MAX_ARRAY_HEADER_BYTES})"
        )));
    }
    read_sub_data(r, (ty, len, small))
}

/// Reads the data of one sub-element whose tag is read (data, padding to 8 bytes):
/// `(type, data)`. The caller has bounded `len`.
fn read_sub_data<R: Read>(
    r: &mut R,
    (ty, len, small): (u32, u64, Option<[u8; 4]>),
) -> Result<(u32, Vec<u8>), Bad> {
    if let Some(small) = small {
        return Ok((ty, small[..len as usize].to_vec()));
    }
    let mut data = Vec::new();
    r.take(len).read_to_end(&mut data)?;
    if (data.len() as u64) < len {
        return Err(bad("truncated file"));
    }
    let pad = len.next_multiple_of(8) - len;
    if pad > 0 {
        let mut skip = [0u8; 8];
        // The last sub-element of a compressed array may lack its padding: not an error.
        let _ = read_exact_or_eof(r, &mut skip[..pad as usize])?;
    }
    Ok((ty, data))
}

/// Reads an array's flags, dimensions and name, asks `visit`, and reads its data when
/// asked to.
fn visit_array<R: Read>(
    r: &mut R,
    endian: Endian,
    visit: &mut impl FnMut(&ArrayHeader) -> Visit,
) -> Result<Option<MatMatrix>, Bad> {
    let (_, flags) = read_header_sub(r, endian, "flags")?;
    if flags.len() < 4 {
        return Err(bad("array flags element is too short"));
    }
    let word = endian.u32([flags[0], flags[1], flags[2], flags[3]]);
    let class = (word & 0xff) as u8;
    let complex = word & 0x0800 != 0;
    let (dims_ty, dims_raw) = read_header_sub(r, endian, "dimensions")?;
    let dims = decode_numbers(dims_ty, &dims_raw, endian)
        .ok_or_else(|| bad(format!("array dimensions have data type {dims_ty}")))?
        .into_iter()
        .map(|d| d as i64)
        .collect();
    let (_, name_raw) = read_header_sub(r, endian, "name")?;
    let header = ArrayHeader {
        name: String::from_utf8_lossy(&name_raw).into_owned(),
        class,
        complex,
        dims,
    };
    match visit(&header) {
        Visit::Skip => Ok(None),
        Visit::Read => read_matrix_data(r, endian, &header).map(Some),
    }
}

/// MATLAB's name for an array class, for messages.
fn class_name(class: u8) -> &'static str {
    match class {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        _ => "unknown-class",
    }
}

fn read_matrix_data<R: Read>(
    r: &mut R,
    endian: Endian,
    header: &ArrayHeader,
) -> Result<MatMatrix, Bad> {
    let name = &header.name;
    if !(6..=15).contains(&header.class) {
        return Err(bad(format!(
            "variable '{name}' is a {} array, expected a numeric matrix",
            class_name(header.class)
        )));
    }
    if header.complex {
        return Err(bad(format!(
            "variable '{name}' is complex, expected a real matrix"
        )));
    }
    let dims_text = || {
        header
            .dims
            .iter()
            .map(i64::to_string)
            .collect::<Vec<_>>()
            .join("x")
    };
    let (rows, cols) = match header.dims.as_slice() {
        [rows, cols, rest @ ..] if rest.iter().all(|&d| d == 1) && *rows >= 0 && *cols >= 0 => {
            (*rows as usize, *cols as usize)
        }
        _ => {
            return Err(bad(format!(
                "variable '{name}' is {}, expected a 2-D matrix",
                dims_text()
            )));
        }
    };
    // Checked before the data is read: the values as f64 fit the budget.
    let count = rows
        .checked_mul(cols)
        .filter(|&count| (count as u64).saturating_mul(8) <= MAX_DECLARED_BYTES)
        .ok_or_else(|| {
            bad(format!(
                "variable '{name}' is too large ({}: more than {MAX_DECLARED_BYTES} bytes as f64)",
                dims_text()
            ))
        })?;
    let (ty, len, small) = read_tag(r, endian)?;
    let item = number_size(ty).ok_or_else(|| {
        bad(format!(
            "variable '{name}' stores its values with unsupported data type {ty}"
        ))
    })?;
    // The declared data length must match the dimensions before it is read.
    if len != count as u64 * item {
        return Err(bad(format!(
            "variable '{name}' is {} ({count} values) but holds {} values",
            dims_text(),
            len / item
        )));
    }
    let (_, raw) = read_sub_data(r, (ty, len, small))?;
    let column_major = decode_numbers(ty, &raw, endian).ok_or_else(|| {
        bad(format!(
            "variable '{name}' stores its values with unsupported data type {ty}"
        ))
    })?;
    if column_major.len() != count {
        return Err(bad(format!(
            "variable '{name}' is {} ({count} values) but holds {} values",
            dims_text(),
            column_major.len()
        )));
    }
    let mut values = vec![0.0; count];
    // count > 0 here means rows > 0: a 0×n matrix has nothing to transpose (and n may be
    // huge).
    if count > 0 {
        for (c, column) in column_major.chunks_exact(rows).enumerate() {
            for (row, &v) in column.iter().enumerate() {
                values[row * cols + c] = v;
            }
        }
    }
    Ok(MatMatrix { rows, cols, values })
}

/// Bytes per number of a numeric data type; `None` for a non-numeric type.
fn number_size(ty: u32) -> Option<u64> {
    Some(match ty {
        1 | 2 => 1,
        3 | 4 => 2,
        5..=7 => 4,
        9 | 12 | 13 => 8,
        _ => return None,
    })
}

/// Decodes the numbers of a numeric data element as `f64`; `None` for a non-numeric type.
fn decode_numbers(ty: u32, raw: &[u8], endian: Endian) -> Option<Vec<f64>> {
    fn each<const N: usize>(raw: &[u8], f: impl Fn([u8; N]) -> f64) -> Vec<f64> {
        raw.chunks_exact(N)
            .map(|c| {
                let mut b = [0u8; N];
                b.copy_from_slice(c);
                f(b)
            })
            .collect()
    }
    let big = endian == Endian::Big;
    macro_rules! num {
        ($t:ty, $n:literal) => {
            each::<$n>(raw, |b| {
                (if big {
                    <$t>::from_be_bytes(b)
                } else {
                    <$t>::from_le_bytes(b)
                }) as f64
            })
        };
    }
    Some(match ty {
        1 => num!(i8, 1),
        2 => num!(u8, 1),
        3 => num!(i16, 2),
        4 => num!(u16, 2),
        5 => num!(i32, 4),
        6 => num!(u32, 4),
        7 => num!(f32, 4),
        9 => num!(f64, 8),
        12 => num!(i64, 8),
        13 => num!(u64, 8),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// A little-endian Level 5 file holding one uncompressed 2x3 `double` matrix `a`
    /// (`[[1, 2, 3], [4, 5, 6]]`) whose name uses the small-element form.
    fn one_matrix_file() -> Vec<u8> {
        let mut f = Vec::new();
        let mut text = b"MATLAB 5.0 MAT-file, test".to_vec();
        text.resize(116, b' ');
        f.extend_from_slice(&text);
        f.extend_from_slice(&[0u8; 8]);
        f.extend_from_slice(&VERSION_5.to_le_bytes());
        f.extend_from_slice(b"IM");
        let mut body = Vec::new();
        let le = |v: u32| v.to_le_bytes();
        body.extend_from_slice(&le(6)); // miUINT32 flags
        body.extend_from_slice(&le(8));
        body.extend_from_slice(&le(6)); // mxDOUBLE_CLASS
        body.extend_from_slice(&le(0));
        body.extend_from_slice(&le(5)); // miINT32 dims
        body.extend_from_slice(&le(8));
        body.extend_from_slice(&2i32.to_le_bytes());
        body.extend_from_slice(&3i32.to_le_bytes());
        body.extend_from_slice(&(1u32 | (1 << 16)).to_le_bytes()); // small miINT8, 1 byte
        body.extend_from_slice(&[b'a', 0, 0, 0]);
        body.extend_from_slice(&le(9)); // miDOUBLE
        body.extend_from_slice(&le(48));
        for v in [1.0f64, 4.0, 2.0, 5.0, 3.0, 6.0] {
            body.extend_from_slice(&v.to_le_bytes());
        }
        f.extend_from_slice(&le(MI_MATRIX));
        f.extend_from_slice(&le(body.len() as u32));
        f.extend_from_slice(&body);
        f
    }

    fn read(bytes: Vec<u8>, name: &str) -> Result<Option<MatMatrix>, Bad> {
        scan_reader(&mut Cursor::new(bytes), &mut |h: &ArrayHeader| {
            if h.name == name {
                Visit::Read
            } else {
                Visit::Skip
            }
        })
    }

    #[test]
    fn reads_a_column_major_double_matrix_row_major() {
        let m = read(one_matrix_file(), "a")
            .ok()
            .flatten()
            .expect("matrix a");
        assert_eq!((m.rows, m.cols), (2, 3));
        assert_eq!(m.values, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(m.get(1, 2), Some(6.0));
        assert_eq!(m.get(2, 0), None);
        assert!(matches!(read(one_matrix_file(), "b"), Ok(None)));
    }

    #[test]
    fn truncation_and_v73_are_named() {
        let mut cut = one_matrix_file();
        cut.truncate(cut.len() - 5);
        assert!(matches!(read(cut, "a"), Err(Bad::Format(r)) if r.contains("truncated")));
        let mut v73 = one_matrix_file();
        v73[124..126].copy_from_slice(&VERSION_73.to_le_bytes());
        assert!(matches!(read(v73, "a"), Err(Bad::Format(r)) if r.contains("v7.3")));
        let mut v4 = one_matrix_file();
        v4[126..128].copy_from_slice(b"xx");
        assert!(matches!(read(v4, "a"), Err(Bad::Format(r)) if r.contains("not a MAT v5")));
    }
}
