//! [`IoError`]: everything that can go wrong reading or writing bodyseg's files.

use bodyseg_core::CloudError;
use std::path::PathBuf;

/// An error reading or writing one of bodyseg's files. Every variant names the file
/// (`path`, the last field); messages start with it, so `{err}` alone is actionable.
///
/// # Causes are in the message, not in `source()`
/// Variants that wrap a lower-level error (`Read`, `Write`, `InvalidCloud`, `BoxesJson`)
/// print it inside their own message (`x.ply: cannot read: No such file or directory`) and
/// do **not** return it from [`source()`](std::error::Error::source), which is `None` for
/// every variant. An error chain printer (anyhow's `{:#}`, `{:?}`) walks `source()` and
/// appends each cause, so having both would print the cause twice; of the two, the message
/// is the one that must carry it: `to_string()` has to say what went wrong on its own, in
/// one line, for callers that print just `{err}`. The wrapped errors stay available as
/// the `cause` fields. (The fields are deliberately not named `source`: thiserror would
/// make such a field the error source implicitly.)
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened or read.
    #[error("{}: cannot read: {cause}", .path.display())]
    Read {
        /// What the operating system said.
        cause: std::io::Error,
        /// The file.
        path: PathBuf,
    },
    /// A text file (configuration, report) is not valid UTF-8.
    #[error(
        "{}: not UTF-8 text: invalid byte sequence on line {line} (byte offset {offset})",
        .path.display()
    )]
    NotUtf8 {
        /// 1-based line number of the first invalid byte.
        line: usize,
        /// 0-based byte offset of the first invalid byte in the file.
        offset: usize,
        /// The file.
        path: PathBuf,
    },
    /// The file (or its temporary sibling) could not be created, written, synced or
    /// renamed into place. The destination is left as it was.
    #[error("{}: cannot write: {cause}", .path.display())]
    Write {
        /// What the operating system (or the writing closure) said.
        cause: std::io::Error,
        /// The destination file.
        path: PathBuf,
    },
    /// The file does not start with the `ply` magic line.
    #[error("{}: not a PLY file (the first line is not 'ply')", .path.display())]
    NotPly {
        /// The file.
        path: PathBuf,
    },
    /// The header's `format` line names something other than `ascii`,
    /// `binary_little_endian` or `binary_big_endian`.
    #[error(
        "{}: unsupported PLY format '{format}' (expected ascii, binary_little_endian or binary_big_endian)",
        .path.display()
    )]
    UnsupportedFormat {
        /// The format as written in the header.
        format: String,
        /// The file.
        path: PathBuf,
    },
    /// A header line could not be understood.
    #[error("{}: PLY header line {line}: {reason}", .path.display())]
    BadHeader {
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong with it.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// The header never ends: no `end_header` line (usually a truncated file).
    #[error("{}: PLY header has no end_header line (truncated file?)", .path.display())]
    UnterminatedHeader {
        /// The file.
        path: PathBuf,
    },
    /// The header declares no element with this name.
    #[error("{}: PLY file has no '{element}' element", .path.display())]
    MissingElement {
        /// The element we need (`vertex`).
        element: String,
        /// The file.
        path: PathBuf,
    },
    /// A required property is not declared (or is a list where a scalar is needed).
    #[error("{}: PLY {element} element has no '{property}' property", .path.display())]
    MissingProperty {
        /// The element (`vertex`).
        element: String,
        /// The missing property (`x`, `y`, `z` or `label`).
        property: String,
        /// The file.
        path: PathBuf,
    },
    /// The data ends before all entries the header declares.
    #[error(
        "{}: truncated PLY: header declares {expected} {element} entries, data holds only {read}",
        .path.display()
    )]
    Truncated {
        /// The element whose data is cut short (`vertex`, `face`, ...).
        element: String,
        /// The count the header declares.
        expected: usize,
        /// How many complete entries the data holds.
        read: usize,
        /// The file.
        path: PathBuf,
    },
    /// A value that does not fit its meaning (a label id 17, a non-finite coordinate, a
    /// token that is not a number of the declared type).
    #[error("{}: {element} {index}: {property} is {value}, expected {expected}", .path.display())]
    BadValue {
        /// The element (`vertex`, ...).
        element: String,
        /// 0-based index of the entry within its element.
        index: usize,
        /// The property.
        property: String,
        /// The offending value as text.
        value: String,
        /// What would have been accepted.
        expected: &'static str,
        /// The file.
        path: PathBuf,
    },
    /// An ASCII PLY data line has the wrong number of values.
    #[error("{}: line {line}: {element} {index}: {reason}", .path.display())]
    BadAsciiLine {
        /// 1-based line number in the file.
        line: usize,
        /// The element the line belongs to.
        element: String,
        /// 0-based index of the entry within its element.
        index: usize,
        /// What is wrong with it.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A PCD header line could not be understood, or a required header line or field is
    /// missing.
    #[error("{}: PCD header line {line}: {reason}", .path.display())]
    PcdHeader {
        /// 1-based line number in the file (the line after the header when a line is
        /// missing).
        line: usize,
        /// What is wrong with it.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// The PCD `DATA` line names a storage other than `ascii`, `binary` or
    /// `binary_compressed`.
    #[error(
        "{}: unsupported PCD DATA kind '{kind}' (expected ascii, binary or binary_compressed)",
        .path.display()
    )]
    PcdDataKind {
        /// The kind as written in the header.
        kind: String,
        /// The file.
        path: PathBuf,
    },
    /// The PCD header's `WIDTH × HEIGHT` is not its `POINTS`.
    #[error(
        "{}: PCD header says WIDTH {width} x HEIGHT {height} = {product} but POINTS {points}",
        .path.display()
    )]
    PcdPointCount {
        /// `WIDTH`.
        width: u64,
        /// `HEIGHT`.
        height: u64,
        /// Their product.
        product: u64,
        /// `POINTS`.
        points: u64,
        /// The file.
        path: PathBuf,
    },
    /// The PCD data is shorter than the header declares (or, compressed, does not
    /// decompress to the declared size).
    #[error("{}: truncated PCD data: {reason}", .path.display())]
    PcdTruncated {
        /// What was expected and what was found.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A cloud's `label` field holds a value that is no bodyseg class id (PCL's segment
    /// ids): where labels are needed, the cloud is refused.
    #[error(
        "{}: {element} {index}: label is {value}, not a bodyseg class id (0..=6, 255 = unknown): \
         the label field holds other ids (PCL's segment ids?); relabel the cloud with bodyseg's \
         classes, or find person boxes without labels (bodyseg boxes --mode geometry), which \
         ignores the field",
        .path.display()
    )]
    ForeignLabels {
        /// `point` (PCD) or `vertex` (PLY).
        element: &'static str,
        /// 0-based index of the first such point.
        index: usize,
        /// Its label, as text.
        value: String,
        /// The file.
        path: PathBuf,
    },
    /// A cloud file's extension is neither `.ply` nor `.pcd`.
    #[error("{}: unknown cloud format: give a .ply or .pcd file", .path.display())]
    UnknownCloudFormat {
        /// The file.
        path: PathBuf,
    },
    /// A cloud handed to a writer is inconsistent (array lengths differ, non-finite
    /// coordinate); nothing was written.
    #[error("{}: refusing to write an invalid cloud: {cause}", .path.display())]
    InvalidCloud {
        /// What [`bodyseg_core::LabeledCloud::validate`] reported.
        cause: CloudError,
        /// The destination file.
        path: PathBuf,
    },
    /// Camera colours were asked for but the cloud has none; nothing was written.
    #[error(
        "{}: camera colours requested but the cloud has none (use the class palette)",
        .path.display()
    )]
    NoCameraColors {
        /// The destination file.
        path: PathBuf,
    },
    /// A boxes file is not valid JSON or does not have FORMATS.md's shape. serde's
    /// message carries the line and column.
    #[error("{}: bad boxes JSON: {cause}", .path.display())]
    BoxesJson {
        /// serde_json's error (with line and column).
        cause: serde_json::Error,
        /// The file.
        path: PathBuf,
    },
    /// A box is well-formed JSON but unusable (see [`bodyseg_core::PersonBox::invalid_reason`]).
    #[error("{}: boxes[{index}]: {reason}", .path.display())]
    InvalidBox {
        /// Position of the box in the `boxes` array.
        index: usize,
        /// Why it is unusable.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A PNG file cannot be decoded (not a PNG, truncated, corrupt), or an image handed
    /// to a PNG writer cannot be encoded.
    #[error("{}: bad PNG: {cause}", .path.display())]
    Png {
        /// What the PNG decoder or encoder said.
        cause: String,
        /// The file.
        path: PathBuf,
    },
    /// A PNG decodes but its pixel format is not the one the file must have (an 8-bit
    /// depth image, an RGB label image).
    #[error("{}: {what} is {got}, expected {expected}", .path.display())]
    PixelFormat {
        /// Which image (`depth PNG`, `label PNG`).
        what: &'static str,
        /// Its pixel format (`8-bit`, `8-bit RGB`).
        got: String,
        /// The format it must have (`16-bit millimetres`).
        expected: &'static str,
        /// The file.
        path: PathBuf,
    },
    /// A colour image cannot be decoded (not a PNG or JPEG, truncated, corrupt).
    #[error("{}: cannot decode colour image: {cause}", .path.display())]
    Decode {
        /// What the image decoder said.
        cause: String,
        /// The file.
        path: PathBuf,
    },
    /// A label image pixel holds an id that is neither a class (0..=6) nor 255.
    #[error(
        "{}: pixel (u {u}, v {v}): label id {id} is not a class id (0..=6) or 255 (not labelled)",
        .path.display()
    )]
    BadLabelPixel {
        /// Column, pixels.
        u: u32,
        /// Row, pixels.
        v: u32,
        /// The offending id.
        id: u8,
        /// The file.
        path: PathBuf,
    },
    /// An image handed to a writer is inconsistent (its pixel array does not hold
    /// `width * height` values); nothing was written.
    #[error("{}: refusing to write an invalid image: {reason}", .path.display())]
    InvalidImage {
        /// What is wrong with it.
        reason: String,
        /// The destination file.
        path: PathBuf,
    },
    /// A MATLAB MAT file is not one bodyseg can read (not Level 5, truncated, corrupt),
    /// lacks the variable asked for, or the variable is not a real 2-D numeric matrix.
    #[error("{}: MAT file: {reason}", .path.display())]
    Mat {
        /// What is wrong.
        reason: String,
        /// The file.
        path: PathBuf,
    },
    /// A folder the caller needs does not exist (or is not a folder).
    #[error("{}: {what} folder is missing", .path.display())]
    MissingFolder {
        /// What the folder is (`camera`).
        what: String,
        /// The folder.
        path: PathBuf,
    },
}
