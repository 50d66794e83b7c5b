//! The few file operations the commands need beyond bodyseg-io's readers and writers,
//! built on bodyseg-io (the only crate that touches the file system).

use anyhow::Result;
use std::path::Path;

/// Writes text atomically (temporary file, then rename): a failed write leaves `path` as
/// it was. The error names the file.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    // IoError's message starts with the path and holds the cause once.
    Ok(bodyseg_io::write_bytes_atomic(path, text.as_bytes())?)
}
