//! One camera's images of a recorded frame (FORMATS.md "Recording"), read and checked
//! against the rig's sensor sizes: the one place `project`, `parse`, `boxes` and `run` read
//! them.

use crate::parse::color_path;
use crate::project::{depth_path, parsing_path};
use anyhow::{Context, Result, bail};
use bodyseg_calib::RgbdCamera;
use bodyseg_core::{LabelImage, RgbImage};
use bodyseg_io::DepthImage;
use std::path::{Path, PathBuf};

/// `REC/<camera>/depth/<frame>.png`, 16-bit, the depth sensor's size; with its path.
pub(crate) fn read_depth(
    rec: &Path,
    camera: &RgbdCamera,
    frame: &str,
) -> Result<(DepthImage, PathBuf)> {
    let path = depth_path(rec, &camera.name, frame);
    let image =
        bodyseg_io::read_depth_png(&path).with_context(|| format!("camera {}", camera.name))?;
    let want = (camera.depth.width, camera.depth.height);
    check_size(
        camera,
        &path,
        "depth image",
        (image.width, image.height),
        want,
        "",
    )?;
    Ok((image, path))
}

/// `REC/<camera>/parsing/<frame>.png`, 8-bit class ids, the colour sensor's size.
pub(crate) fn read_parsing(
    rec: &Path,
    camera: &RgbdCamera,
    frame: &str,
) -> Result<(LabelImage, PathBuf)> {
    let path = parsing_path(rec, &camera.name, frame);
    let image =
        bodyseg_io::read_label_png(&path).with_context(|| format!("camera {}", camera.name))?;
    let want = (camera.color.width, camera.color.height);
    check_size(
        camera,
        &path,
        "label image",
        (image.width, image.height),
        want,
        "the colour sensor is ",
    )?;
    Ok((image, path))
}

/// `REC/<camera>/color/<frame>.png|.jpg|.jpeg`, the colour sensor's size.
pub(crate) fn read_color(
    rec: &Path,
    camera: &RgbdCamera,
    frame: &str,
) -> Result<(RgbImage, PathBuf)> {
    let path = color_path(rec, &camera.name, frame);
    let image =
        bodyseg_io::read_rgb_image(&path).with_context(|| format!("camera {}", camera.name))?;
    let want = (camera.color.width, camera.color.height);
    check_size(
        camera,
        &path,
        "colour image",
        (image.width, image.height),
        want,
        "",
    )?;
    Ok((image, path))
}

/// `REC/<camera>/depth_labels/<frame>.png`: the truth of every depth pixel, the depth
/// sensor's size.
pub(crate) fn read_depth_labels(
    rec: &Path,
    camera: &RgbdCamera,
    frame: &str,
) -> Result<(LabelImage, PathBuf)> {
    let path = rec
        .join(&camera.name)
        .join("depth_labels")
        .join(format!("{frame}.png"));
    let image = bodyseg_io::read_label_png(&path)
        .with_context(|| format!("camera {}: ground truth", camera.name))?;
    let want = (camera.depth.width, camera.depth.height);
    check_size(
        camera,
        &path,
        "ground-truth label image",
        (image.width, image.height),
        want,
        "",
    )?;
    Ok((image, path))
}

/// `camera cam0: PATH: WHAT is WxH, rig.toml says [SENSOR]WxH` when the sizes differ.
fn check_size(
    camera: &RgbdCamera,
    path: &Path,
    what: &str,
    got: (u32, u32),
    want: (u32, u32),
    sensor: &str,
) -> Result<()> {
    if got != want {
        bail!(
            "camera {}: {}: {what} is {}x{}, rig.toml says {sensor}{}x{}",
            camera.name,
            path.display(),
            got.0,
            got.1,
            want.0,
            want.1
        );
    }
    Ok(())
}
