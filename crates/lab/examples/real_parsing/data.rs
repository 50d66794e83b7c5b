//! The real photographs of `scripts/real_parsing_data.py` (.data/real_parsing/): the index
//! and one image's person regions (the index's boxes, which stand in for depth boxes).
//! Shared by the `real_parsing` example and crates/lab/tests/real_parsing.rs.

use anyhow::Context;
use bodyseg_core::RgbImage;
use bodyseg_parsing::{PersonRegion, PixelBox, ViewInput};
use std::path::{Path, PathBuf};

/// One image of the index.
#[derive(Debug)]
pub struct Item {
    /// Its name: `images/<name>.jpg`, `labels/<name>.png`.
    pub name: String,
    /// `parts7` (the 7 classes, exact) or `super5` (coarse super-classes).
    pub scheme: String,
    /// The index's `split` when it has one (`holdout`: added after the rule was tuned,
    /// never looked at while tuning), else `None` (the tune / test images).
    pub split: Option<String>,
    /// Person boxes, inclusive pixel centres, image px.
    pub regions: Vec<PersonRegion>,
}

impl Item {
    /// The segmenter's input for this item's `image`: one view, its person boxes as regions.
    pub fn view<'a>(&'a self, image: &'a RgbImage) -> ViewInput<'a> {
        ViewInput {
            camera: "photo",
            frame: &self.name,
            image: Some(image),
            recorded: None,
            regions: Some(&self.regions),
        }
    }
}

/// The data folder of a checkout: `<workspace>/.data/real_parsing`.
pub fn default_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.data/real_parsing")
}

/// Reads `dir/index.json`.
///
/// # Errors
/// The index cannot be read or an entry lacks `name`, `scheme` or four-number boxes (the
/// error names the file and the entry).
pub fn read_index(dir: &Path) -> anyhow::Result<Vec<Item>> {
    let path = dir.join("index.json");
    let text = std::fs::read_to_string(&path).with_context(|| path.display().to_string())?;
    let value: serde_json::Value =
        serde_json::from_str(&text).with_context(|| path.display().to_string())?;
    let entries = value
        .as_array()
        .with_context(|| format!("{}: not a list", path.display()))?;
    let mut items = Vec::with_capacity(entries.len());
    for (i, entry) in entries.iter().enumerate() {
        let field = |key: &str| {
            entry[key]
                .as_str()
                .map(str::to_owned)
                .with_context(|| format!("{}: entry {i}: no string {key}", path.display()))
        };
        let name = field("name")?;
        let scheme = field("scheme")?;
        let split = entry["split"].as_str().map(str::to_owned);
        let boxes = entry["person_boxes"]
            .as_array()
            .with_context(|| format!("{}: {name}: no person_boxes list", path.display()))?;
        let mut regions = Vec::with_capacity(boxes.len());
        for b in boxes {
            let v: Vec<f64> = b
                .as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default();
            let [x0, y0, x1, y1] = v[..] else {
                anyhow::bail!(
                    "{}: {name}: a person box is not [x0, y0, x1, y1]",
                    path.display()
                );
            };
            regions.push(PersonRegion {
                bounds: PixelBox { x0, y0, x1, y1 },
                // No depth: overlapping people are decided by the nearer bone.
                depth_m: f64::NAN,
            });
        }
        items.push(Item {
            name,
            scheme,
            split,
            regions,
        });
    }
    Ok(items)
}
