//! The file helpers the commands share beyond bodyseg-io's readers and writers (bodyseg-io
//! is the only crate that touches the file system): text written atomically, where the
//! resolved configuration of an output goes, a cloud read by its extension, PLY options.

use crate::config::PipelineConfig;
use crate::stage::{Stage, timed};
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

/// The inputs of a command, as its messages name them (`("--cloud", path)`).
pub type NamedInputs<'a> = [(&'a str, &'a Path)];

/// Checks a single-file output before anything is written (one guard for every command's
/// `--out` FILE): the path must not be a folder, a device, a FIFO or a socket; it must not
/// be one of the command's inputs (the same file also through a symbolic or hard link:
/// device and inode are compared); and a file already there is replaced only when it is
/// of a kind the command writes (its extension is one of `ours`, e.g. `eval --out in.ply`
/// is refused: a cloud is not a report).
///
/// # Errors
/// The first rule broken; the message names `--out`, the path and the input.
pub fn check_output_file(out: &Path, ours: &[&str], inputs: &NamedInputs<'_>) -> Result<()> {
    if let Ok(meta) = std::fs::metadata(out) {
        let kind = special_kind(&meta);
        if meta.is_dir() {
            bail!("--out {}: is a folder; give a file path", out.display());
        }
        if let Some(kind) = kind {
            bail!(
                "--out {}: is a {kind}, not a regular file: bodyseg does not replace it",
                out.display()
            );
        }
        for (name, input) in inputs {
            if same_file(out, input) {
                bail!(
                    "--out {} is the input {name} ({}): it would be overwritten; write the output elsewhere",
                    out.display(),
                    input.display()
                );
            }
        }
        let ext = out
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if !ours.contains(&ext.as_str()) {
            bail!(
                "--out {}: exists and is not a file this command writes ({}): remove it first or write elsewhere",
                out.display(),
                ours.iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    Ok(())
}

/// Checks an output folder (`run`, `convert`) before anything is written: not a file, a
/// device, a FIFO or a socket; not the input folder itself and not inside it (`run --out
/// REC` would overwrite the recording's own `boxes/`). The input inside the output folder
/// is fine: the outputs go to fixed subfolders (`clouds/`, `boxes/`, `frames/`, ...).
///
/// # Errors
/// The first rule broken; the message names `--out`, the path and the input.
pub fn check_output_folder(out: &Path, input_name: &str, input: &Path) -> Result<()> {
    if let Ok(meta) = std::fs::metadata(out) {
        if let Some(kind) = special_kind(&meta) {
            bail!("--out {}: is a {kind}, not a folder", out.display());
        }
        if !meta.is_dir() {
            bail!("--out {}: is a file; give a folder", out.display());
        }
    }
    // Compare canonical paths; `out` may not exist yet: canonicalise its nearest existing
    // ancestor and append the rest.
    let (Some(out_abs), Ok(input_abs)) = (canonical_prefix(out), std::fs::canonicalize(input))
    else {
        return Ok(());
    };
    if out_abs.starts_with(&input_abs) {
        bail!(
            "--out {} is {} the input {input_name} ({}): outputs would overwrite or mix with its files; write the output elsewhere",
            out.display(),
            if out_abs == input_abs {
                "the folder of"
            } else {
                "inside"
            },
            input.display()
        );
    }
    Ok(())
}

/// `path` made absolute and canonical as far as it exists (the rest appended as given).
fn canonical_prefix(path: &Path) -> Option<PathBuf> {
    let mut rest = Vec::new();
    let mut cur = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().ok()?.join(path)
    };
    loop {
        if let Ok(c) = std::fs::canonicalize(&cur) {
            return Some(
                rest.into_iter()
                    .rev()
                    .fold(c, |acc: PathBuf, p| acc.join(p)),
            );
        }
        rest.push(cur.file_name()?.to_os_string());
        cur = cur.parent()?.to_path_buf();
    }
}

/// "device", "FIFO" or "socket" for such a file; `None` for a file, folder or link.
fn special_kind(meta: &std::fs::Metadata) -> Option<&'static str> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_block_device() || t.is_char_device() {
            return Some("device");
        }
        if t.is_fifo() {
            return Some("FIFO");
        }
        if t.is_socket() {
            return Some("socket");
        }
    }
    #[cfg(not(unix))]
    let _ = meta;
    None
}

/// Whether two paths name one existing file (device and inode on Unix, canonical paths
/// elsewhere).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Writes a command's main output with `write_main`, then, if given, its resolved
/// configuration beside it (`(path, text)`). When the side file cannot be written the main
/// output is removed again, so that exit status 1 leaves nothing behind.
///
/// # Errors
/// Either write fails (the error names the file).
pub(crate) fn write_with_side_file(
    out: &Path,
    side: Option<(&Path, &str)>,
    write_main: impl FnOnce() -> Result<()>,
) -> Result<()> {
    write_main()?;
    if let Some((path, text)) = side
        && let Err(e) = write_text(path, text)
    {
        let _ = std::fs::remove_file(out);
        return Err(e.context("resolved configuration (the main output was removed again)"));
    }
    Ok(())
}

/// A command's `write` stage: its output `out` written by `write_main` and, when
/// `write_resolved_config`, the resolved configuration beside it
/// ([`write_with_side_file`], [`resolved_config_path`]). The stage's line names `out`, the
/// configuration and `also` (a file `write_main` writes besides `out`, such as a preview).
/// Returns where the configuration went, and the stage.
///
/// # Errors
/// The configuration cannot be serialised, or a write fails (the error names the file).
pub(crate) fn write_stage(
    out: &Path,
    config: &PipelineConfig,
    write_resolved_config: bool,
    also: Option<&Path>,
    write_main: impl FnOnce() -> Result<()>,
) -> Result<(Option<PathBuf>, Stage)> {
    let resolved_config = write_resolved_config.then(|| resolved_config_path(out));
    let resolved_text = match &resolved_config {
        Some(_) => Some(config.resolved_toml()?),
        None => None,
    };
    let side = resolved_config.as_deref().zip(resolved_text.as_deref());
    let ((), took) = timed(|| write_with_side_file(out, side, write_main))?;
    let mut written = out.display().to_string();
    for path in resolved_config.as_deref().into_iter().chain(also) {
        written.push_str(&format!(", {}", path.display()));
    }
    Ok((resolved_config, Stage::new("write", took, written)))
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

    #[test]
    fn an_output_never_replaces_an_input_a_device_or_a_foreign_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let d = dir.path();
        let cloud = d.join("in.ply");
        std::fs::write(&cloud, b"ply").expect("write");
        let err = |r: Result<()>| format!("{:#}", r.expect_err("refused"));
        // The input itself, through a symbolic link and through a hard link.
        let e = err(check_output_file(&cloud, &["ply"], &[("--cloud", &cloud)]));
        assert!(e.contains("is the input --cloud"), "{e}");
        let sym = d.join("sym.ply");
        std::os::unix::fs::symlink(&cloud, &sym).expect("symlink");
        let e = err(check_output_file(&sym, &["ply"], &[("--cloud", &cloud)]));
        assert!(e.contains("is the input --cloud"), "{e}");
        let hard = d.join("hard.ply");
        std::fs::hard_link(&cloud, &hard).expect("hard link");
        let e = err(check_output_file(&hard, &["ply"], &[("--cloud", &cloud)]));
        assert!(e.contains("is the input --cloud"), "{e}");
        // A report over a cloud; a device; a folder.
        let e = err(check_output_file(&cloud, &["md", "json"], &[]));
        assert!(
            e.contains("exists and is not a file this command writes (.md, .json)"),
            "{e}"
        );
        let e = err(check_output_file(Path::new("/dev/null"), &["ply"], &[]));
        assert!(e.contains("is a device, not a regular file"), "{e}");
        let e = err(check_output_file(d, &["ply"], &[]));
        assert!(e.contains("is a folder"), "{e}");
        // A new file, or an earlier output of ours, is fine.
        assert!(check_output_file(&d.join("new.ply"), &["ply"], &[("--cloud", &cloud)]).is_ok());
        let old = d.join("old.ply");
        std::fs::write(&old, b"ply").expect("write");
        assert!(check_output_file(&old, &["ply"], &[("--cloud", &cloud)]).is_ok());

        // Folders: not the recording, not inside it; the recording inside OUT is fine.
        let rec = d.join("rec");
        std::fs::create_dir(&rec).expect("mkdir");
        let e = err(check_output_folder(&rec, "REC", &rec));
        assert!(e.contains("is the folder of the input REC"), "{e}");
        let e = err(check_output_folder(&rec.join("out/x"), "REC", &rec));
        assert!(e.contains("is inside the input REC"), "{e}");
        let e = err(check_output_folder(
            &d.join("rec/../rec/boxes"),
            "REC",
            &rec,
        ));
        assert!(e.contains("is inside the input REC"), "{e}");
        assert!(check_output_folder(d, "REC", &rec).is_ok());
        assert!(check_output_folder(&d.join("out"), "REC", &rec).is_ok());
        let e = err(check_output_folder(&cloud, "REC", &rec));
        assert!(e.contains("is a file; give a folder"), "{e}");
    }
}
