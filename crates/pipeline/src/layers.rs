//! Layers of TOML configuration: tables merged key by key (a later file overrides only the
//! keys it sets) and `KEY=VALUE` settings with dotted keys (`--set refine.eps_m=0.03`,
//! and `bodyseg synth --set rig.cameras=4` for scene keys). The result is deserialized
//! once, by the caller, into its configuration type.

use anyhow::{Result, bail};

/// Merges `over` into `base`: a table merges key by key (recursively), any other value
/// (numbers, strings, arrays) replaces the one in `base`.
pub(crate) fn merge_tables(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge_tables(b, o),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

/// One `KEY=VALUE` setting: the dotted key and the value, parsed as a TOML value
/// (`0.03`, `true`, `"m-n"`, `[1, 2]`), a bare word that is not one taken as a string
/// (`refine.steps=M-N`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Setting {
    /// The dotted key, `section.key`.
    pub key: String,
    /// The value.
    pub value: toml::Value,
}

impl Setting {
    /// Parses `KEY=VALUE`.
    ///
    /// # Errors
    /// No `=`, or an empty key or key part (`a..b`).
    pub(crate) fn parse(item: &str) -> Result<Setting> {
        let Some((key, value)) = item.split_once('=') else {
            bail!("`{item}` is not KEY=VALUE (e.g. refine.eps_m=0.03)");
        };
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|p| p.trim().is_empty()) {
            bail!("`{item}`: the key must be a dotted name such as refine.eps_m");
        }
        let value = value.trim();
        let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.to_string()));
        Ok(Setting {
            key: key.split('.').map(str::trim).collect::<Vec<_>>().join("."),
            value: parsed,
        })
    }

    /// Sets the value at the dotted key in `table`, creating the tables on the way.
    ///
    /// # Errors
    /// A part of the key before the last names a value that is not a table.
    pub(crate) fn apply(&self, table: &mut toml::Table) -> Result<()> {
        let parts: Vec<&str> = self.key.split('.').collect();
        let (last, parents) = parts.split_last().unwrap_or((&"", &[]));
        let mut node = table;
        for part in parents {
            let entry = node
                .entry((*part).to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let toml::Value::Table(next) = entry else {
                bail!("{}: `{part}` is not a table", self.key);
            };
            node = next;
        }
        node.insert((*last).to_string(), self.value.clone());
        Ok(())
    }
}

/// Whether the dotted `key` names a value (not a table) of `known` (e.g. the serialized
/// defaults, which hold every key).
pub(crate) fn has_key(known: &toml::Table, key: &str) -> bool {
    let mut node = known;
    let mut parts = key.split('.').peekable();
    while let Some(part) = parts.next() {
        match node.get(part) {
            Some(toml::Value::Table(t)) if parts.peek().is_some() => node = t,
            Some(toml::Value::Table(_)) | None => return false,
            Some(_) => return parts.peek().is_none(),
        }
    }
    false
}

/// The keys of the table at the dotted `section` of `known` (sorted), for an error
/// message; the top-level keys when there is no such section.
pub(crate) fn keys_of(known: &toml::Table, section: &str) -> Vec<String> {
    let mut node = known;
    for part in section.split('.').filter(|p| !p.is_empty()) {
        match node.get(part) {
            Some(toml::Value::Table(t)) => node = t,
            _ => {
                node = known;
                break;
            }
        }
    }
    let mut keys: Vec<String> = node.keys().cloned().collect();
    keys.sort();
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).expect("valid TOML")
    }

    #[test]
    fn a_later_table_overrides_only_the_keys_it_sets() {
        let mut base =
            table("[refine]\neps_m = 0.05\nmin_points = 40\n[boxes]\nmode = \"labels\"\n");
        merge_tables(&mut base, table("[refine]\nmin_points = 7\n"));
        assert_eq!(
            base,
            table("[refine]\neps_m = 0.05\nmin_points = 7\n[boxes]\nmode = \"labels\"\n")
        );
        merge_tables(&mut base, table("[project]\nmode = \"naive\"\n"));
        assert_eq!(base["project"]["mode"].as_str(), Some("naive"));
    }

    #[test]
    fn settings_parse_toml_values_or_strings_and_set_dotted_keys() {
        let s = Setting::parse(" refine.eps_m = 0.03").expect("valid");
        assert_eq!(s.key, "refine.eps_m");
        assert_eq!(s.value, toml::Value::Float(0.03));
        assert_eq!(
            Setting::parse("refine.steps=M-N").expect("valid").value,
            toml::Value::String("M-N".into())
        );
        assert_eq!(
            Setting::parse("project.occlusion=false")
                .expect("valid")
                .value,
            toml::Value::Boolean(false)
        );
        assert!(Setting::parse("refine.eps_m").is_err());
        assert!(Setting::parse("=1").is_err());
        assert!(Setting::parse("refine..eps_m=1").is_err());

        let mut t = table("[refine]\neps_m = 0.05\n");
        Setting::parse("refine.eps_m=0.03")
            .expect("valid")
            .apply(&mut t)
            .expect("set");
        Setting::parse("boxes.mode=geometry")
            .expect("valid")
            .apply(&mut t)
            .expect("set");
        assert_eq!(
            t,
            table("[refine]\neps_m = 0.03\n[boxes]\nmode = \"geometry\"\n")
        );
        let e = Setting::parse("refine.eps_m.x=1")
            .expect("valid")
            .apply(&mut t)
            .expect_err("not a table");
        assert!(e.to_string().contains("`eps_m` is not a table"), "{e}");
    }

    #[test]
    fn known_keys_are_values_of_the_reference_table() {
        let known = table("[refine]\neps_m = 0.05\n[parsing]\nmodel = \"\"\n");
        assert!(has_key(&known, "refine.eps_m"));
        assert!(!has_key(&known, "refine"));
        assert!(!has_key(&known, "refine.epsilon"));
        assert!(!has_key(&known, "refine.eps_m.x"));
        assert!(!has_key(&known, "refin.eps_m"));
        assert_eq!(keys_of(&known, "refine"), ["eps_m"]);
        assert_eq!(keys_of(&known, "nope"), ["parsing", "refine"]);
    }
}
