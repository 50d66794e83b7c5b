//! The file helpers the commands share beyond bodyseg-io's readers and writers (bodyseg-io
//! is the only crate that touches the file system): text written atomically, where the
//! resolved configuration of an output goes, a cloud read by its extension, PLY options.

use anyhow::{Result, bail};
use bodyseg_core::LabeledCloud;
use bodyseg_io::{PlyFormat, PlyWriteOptions};
use std::path::{Path, PathBuf};

/// Writes text atomically (temporary file, then rename): a failed write leaves `path` as
/// it was. The error names the file.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    // IoError's message starts with the path and holds the cause once.
    Ok(bodyseg_io::write_bytes_atomic(path, text.as_bytes())?)
}

/// Where the resolved configuration of an output goes: `refined.ply` →
/// `refined.config.resolved.toml`, in the same folder.
pub(crate) fn resolved_config_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    out.with_file_name(format!("{stem}.config.resolved.toml"))
}

/// Reads a cloud by its extension: `.pcd` with [`bodyseg_io::read_pcd`], `.ply` with
/// [`bodyseg_io::read_ply`].
///
/// # Errors
/// Another extension, or the reader's error (naming the file).
pub(crate) fn read_cloud(path: &Path) -> Result<LabeledCloud> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("pcd") => Ok(bodyseg_io::read_pcd(path)?),
        Some("ply") => Ok(bodyseg_io::read_ply(path)?),
        _ => bail!(
            "{}: unknown cloud format: give a .ply or .pcd file",
            path.display()
        ),
    }
}

/// Binary little-endian PLY, or ASCII when `ascii` (the commands' `--ascii`).
pub(crate) fn ply_options(ascii: bool) -> PlyWriteOptions {
    PlyWriteOptions {
        format: if ascii {
            PlyFormat::Ascii
        } else {
            PlyFormat::BinaryLittleEndian
        },
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolved_config_sits_beside_the_output_and_clouds_are_read_by_extension() {
        assert!(read_cloud(Path::new("x.xyz")).is_err());
        assert_eq!(
            resolved_config_path(Path::new("out/refined.ply")),
            Path::new("out/refined.config.resolved.toml")
        );
        assert_eq!(
            resolved_config_path(Path::new("a")),
            Path::new("a.config.resolved.toml")
        );
    }
}
