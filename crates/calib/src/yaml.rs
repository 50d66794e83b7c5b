//! Access to plain YAML documents (ROS `camera_info`, OpenPTrack `camera_poses.yaml`)
//! through `yaml-rust2`, with errors that name the file and the dotted key.

use std::path::Path;

use yaml_rust2::{Yaml, YamlLoader};

use crate::CalibError;

/// Parses the first document of a YAML text (a leading byte order mark is ignored); an
/// empty text is an empty document (Null).
pub(crate) fn load(text: &str, path: &Path) -> Result<Yaml, CalibError> {
    let docs = YamlLoader::load_from_str(crate::files::without_bom(text)).map_err(|e| {
        CalibError::Syntax {
            line: e.marker().line(),
            reason: e.info().to_string(),
            path: path.to_path_buf(),
        }
    })?;
    Ok(docs.into_iter().next().unwrap_or(Yaml::Null))
}

/// `parent.key`, or `key` at the top level.
pub(crate) fn join(parent: &str, key: &str) -> String {
    if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    }
}

/// Type name of a node for error messages.
pub(crate) fn type_name(node: &Yaml) -> &'static str {
    match node {
        Yaml::Real(_) => "a float",
        Yaml::Integer(_) => "an integer",
        Yaml::String(_) => "a string",
        Yaml::Boolean(_) => "a boolean",
        Yaml::Array(_) => "a sequence",
        Yaml::Hash(_) => "a mapping",
        Yaml::Alias(_) => "an alias",
        Yaml::Null => "null",
        Yaml::BadValue => "an invalid value",
    }
}

/// A YAML document being read, for errors that name its file.
pub(crate) struct Doc<'p> {
    pub(crate) path: &'p Path,
}

impl Doc<'_> {
    pub(crate) fn bad(&self, key: &str, reason: impl Into<String>) -> CalibError {
        CalibError::BadValue {
            key: key.to_string(),
            reason: reason.into(),
            path: self.path.to_path_buf(),
        }
    }

    pub(crate) fn missing(&self, key: &str) -> CalibError {
        CalibError::MissingKey {
            key: key.to_string(),
            path: self.path.to_path_buf(),
        }
    }

    /// `node[key]` where `node` must be a mapping; `parent` is the node's dotted key.
    pub(crate) fn get<'y>(
        &self,
        node: &'y Yaml,
        parent: &str,
        key: &str,
    ) -> Result<&'y Yaml, CalibError> {
        let Yaml::Hash(map) = node else {
            let what = if parent.is_empty() {
                "document"
            } else {
                parent
            };
            return Err(self.bad(what, format!("must be a mapping, got {}", type_name(node))));
        };
        map.get(&Yaml::String(key.to_string()))
            .ok_or_else(|| self.missing(&join(parent, key)))
    }

    /// A finite number (a YAML float or integer); `key` is the full dotted key.
    pub(crate) fn number(&self, node: &Yaml, key: &str) -> Result<f64, CalibError> {
        let v = match node {
            Yaml::Real(s) => node
                .as_f64()
                .ok_or_else(|| self.bad(key, format!("{s:?} is not a number")))?,
            // Integers are exact in f64 up to 2^53, far beyond any calibration value.
            Yaml::Integer(i) => *i as f64,
            other => {
                return Err(self.bad(key, format!("must be a number, got {}", type_name(other))));
            }
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.bad(key, format!("must be finite, got {v}")))
        }
    }

    /// A positive integer pixel count.
    pub(crate) fn count(&self, node: &Yaml, key: &str) -> Result<u32, CalibError> {
        match node {
            Yaml::Integer(i) if *i > 0 => u32::try_from(*i)
                .map_err(|_| self.bad(key, format!("must be a pixel count, got {i}"))),
            Yaml::Integer(i) => Err(self.bad(key, format!("must be > 0, got {i}"))),
            other => Err(self.bad(key, format!("must be an integer, got {}", type_name(other)))),
        }
    }

    /// A ROS-style matrix `{rows, cols, data: [...]}` that must be `rows × cols`; values
    /// row-major.
    pub(crate) fn matrix(
        &self,
        node: &Yaml,
        key: &str,
        rows: u32,
        cols: u32,
    ) -> Result<Vec<f64>, CalibError> {
        let got_rows = self.count(self.get(node, key, "rows")?, &join(key, "rows"))?;
        let got_cols = self.count(self.get(node, key, "cols")?, &join(key, "cols"))?;
        if (got_rows, got_cols) != (rows, cols) {
            return Err(self.bad(
                key,
                format!("must be a {rows}x{cols} matrix, the file says {got_rows}x{got_cols}"),
            ));
        }
        self.data(node, key, rows as usize, cols as usize)
    }

    /// A ROS-style vector `{rows, cols, data: [...]}` of any length: one of rows and
    /// cols is 1 (or both 0); values in order.
    pub(crate) fn vector(&self, node: &Yaml, key: &str) -> Result<Vec<f64>, CalibError> {
        let dim = |name: &str| -> Result<usize, CalibError> {
            let k = join(key, name);
            match self.get(node, key, name)? {
                Yaml::Integer(i) => usize::try_from(*i)
                    .map_err(|_| self.bad(&k, format!("must be a count >= 0, got {i}"))),
                other => Err(self.bad(&k, format!("must be an integer, got {}", type_name(other)))),
            }
        };
        let (rows, cols) = (dim("rows")?, dim("cols")?);
        if rows > 1 && cols > 1 {
            return Err(self.bad(
                key,
                format!("must be a 1xN vector, the file says {rows}x{cols}"),
            ));
        }
        self.data(node, key, rows, cols)
    }

    /// `node.data`: exactly `rows × cols` finite numbers (an empty `data:` for 0).
    fn data(
        &self,
        node: &Yaml,
        key: &str,
        rows: usize,
        cols: usize,
    ) -> Result<Vec<f64>, CalibError> {
        let n = rows * cols;
        let data_key = join(key, "data");
        let items = match self.get(node, key, "data")? {
            Yaml::Array(items) => items.as_slice(),
            Yaml::Null if n == 0 => &[],
            _ => return Err(self.bad(&data_key, "must be a sequence of numbers")),
        };
        if items.len() != n {
            return Err(self.bad(
                &data_key,
                format!(
                    "a {rows}x{cols} matrix needs {n} values, got {}",
                    items.len()
                ),
            ));
        }
        items
            .iter()
            .enumerate()
            .map(|(k, item)| self.number(item, &format!("{data_key}[{k}]")))
            .collect()
    }
}
