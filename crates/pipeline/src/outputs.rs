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

/// Reads a cloud file by its extension (`.pcd`, `.ply`) as it is: labels of any kind or
/// none, an organised cloud's grid ([`bodyseg_io::read_cloud_file`]); the caller decides
/// what the labels must be.
///
/// # Errors
/// Another extension, or the reader's error (naming the file).
pub(crate) fn read_cloud_file(path: &Path) -> Result<bodyseg_io::CloudFile> {
    Ok(bodyseg_io::read_cloud_file(path)?)
}

/// Reads a PLY cloud whose labels must be bodyseg's class ids (`refine`, `eval`).
///
/// # Errors
/// The reader's error; a cloud without a `label` field or with another tool's ids
/// (PCL's segment ids): the message names the fix.
pub(crate) fn read_labelled_ply(path: &Path) -> Result<LabeledCloud> {
    let file = bodyseg_io::read_ply_file(path)?;
    if file.labels == bodyseg_io::FileLabels::Absent {
        bail!(
            "{}: the cloud has no 'label' property: this command needs bodyseg's class ids \
             (0..=6, 255 = unknown); label the cloud first (bodyseg project, or bodyseg run), \
             or find person boxes without labels (bodyseg boxes --mode geometry)",
            path.display()
        );
    }
    Ok(file.into_class_labels("vertex", path)?)
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
        assert!(read_cloud_file(Path::new("x.xyz")).is_err());
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
