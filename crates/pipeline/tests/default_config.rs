//! `configs/default.toml` is the built-in configuration: same values, every field present.

use bodyseg_pipeline::PipelineConfig;
use std::path::PathBuf;

fn default_toml() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../configs/default.toml")
}

#[test]
fn default_toml_equals_the_built_in_defaults() {
    let loaded = PipelineConfig::load(&default_toml());
    assert_eq!(
        loaded.as_ref().ok(),
        Some(&PipelineConfig::default()),
        "{loaded:?}"
    );
}

#[test]
fn default_toml_spells_out_every_field() {
    // Keys of the serialized defaults vs keys written in the file, per section: a field
    // added to a stage config must be documented in configs/default.toml too.
    let keys = |text: &str| -> Vec<(String, Vec<String>)> {
        let table: toml::Table = toml::from_str(text).expect("valid TOML");
        let mut sections: Vec<(String, Vec<String>)> = table
            .into_iter()
            .map(|(name, value)| {
                let mut fields: Vec<String> = value
                    .as_table()
                    .map(|t| t.keys().cloned().collect())
                    .unwrap_or_default();
                fields.sort();
                (name, fields)
            })
            .collect();
        sections.sort();
        sections
    };
    let file = std::fs::read_to_string(default_toml()).expect("configs/default.toml is readable");
    let resolved = PipelineConfig::default()
        .resolved_toml()
        .expect("defaults serialize");
    assert_eq!(keys(&file), keys(&resolved));
}
