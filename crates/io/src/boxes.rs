//! Person boxes as JSON (FORMATS.md, "Person boxes").

use crate::{Durability, IoError, write_atomic_with};
use bodyseg_core::PersonBoxes;
use std::path::Path;

/// Reads a frame's person boxes from a JSON file; see [`parse_boxes`].
///
/// # Errors
/// [`IoError::Read`] when the file cannot be read, otherwise as [`parse_boxes`].
pub fn read_boxes(path: &Path) -> Result<PersonBoxes, IoError> {
    let bytes = std::fs::read(path).map_err(|cause| IoError::Read {
        cause,
        path: path.to_path_buf(),
    })?;
    parse_boxes(&bytes, path)
}

/// Parses person boxes from JSON text; `path_for_errors` only names the file in errors.
///
/// Unknown keys are ignored, `frame` and `yaw_rad` default to `""` and 0. Every box
/// must pass [`bodyseg_core::PersonBox::invalid_reason`].
///
/// # Errors
/// [`IoError::BoxesJson`] (with serde's line and column) when the text is not JSON of
/// FORMATS.md's shape, [`IoError::InvalidBox`] naming the first unusable box.
pub fn parse_boxes(bytes: &[u8], path_for_errors: &Path) -> Result<PersonBoxes, IoError> {
    let boxes: PersonBoxes = serde_json::from_slice(bytes).map_err(|cause| IoError::BoxesJson {
        cause,
        path: path_for_errors.to_path_buf(),
    })?;
    validate(&boxes, path_for_errors)?;
    Ok(boxes)
}

/// Writes person boxes to `path` as pretty-printed JSON, atomically (see
/// [`write_atomic`]).
///
/// # Errors
/// [`IoError::InvalidBox`] when a box is unusable (nothing is written: such a file could
/// not be read back), [`IoError::Write`] on I/O failure (the destination is untouched).
pub fn write_boxes(path: &Path, boxes: &PersonBoxes) -> Result<(), IoError> {
    write_boxes_with(path, boxes, Durability::Synced)
}

/// [`write_boxes`] with a choice of [`Durability`].
///
/// # Errors
/// As [`write_boxes`].
pub fn write_boxes_with(
    path: &Path,
    boxes: &PersonBoxes,
    durability: Durability,
) -> Result<(), IoError> {
    validate(boxes, path)?;
    write_atomic_with(path, durability, |w| {
        serde_json::to_writer_pretty(&mut *w, boxes)?;
        w.write_all(b"\n")
    })
}

fn validate(boxes: &PersonBoxes, path: &Path) -> Result<(), IoError> {
    for (index, b) in boxes.boxes.iter().enumerate() {
        if let Some(reason) = b.invalid_reason() {
            return Err(IoError::InvalidBox {
                index,
                reason,
                path: path.to_path_buf(),
            });
        }
    }
    Ok(())
}
