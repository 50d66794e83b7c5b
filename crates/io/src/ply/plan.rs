//! Shared by the PLY decoders: the vertex roles we read, the plan of which property feeds
//! each, and the sink that checks values and collects vertices.

use super::header::{Element, PropKind, Scalar};
use crate::IoError;
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use std::path::Path;

/// The vertex properties we read, in a fixed order; values travel as `f64`, which holds
/// every PLY scalar type exactly.
pub(crate) const ROLES: [&str; NROLES] = [
    "x", "y", "z", "label", "red", "green", "blue", "camera", "pixel",
];
pub(crate) const NROLES: usize = 9;
pub(crate) const X: usize = 0;
pub(crate) const Y: usize = 1;
pub(crate) const Z: usize = 2;
pub(crate) const LABEL: usize = 3;
pub(crate) const RED: usize = 4;
pub(crate) const GREEN: usize = 5;
pub(crate) const BLUE: usize = 6;
pub(crate) const CAMERA: usize = 7;
pub(crate) const PIXEL: usize = 8;
/// Roles without which a file is rejected.
pub(crate) const REQUIRED: [usize; 3] = [X, Y, Z];
/// Roles that must be scalars when present (a list there is a malformed file).
pub(crate) const SCALAR_ONLY: [usize; 4] = [X, Y, Z, LABEL];

/// Which vertex property feeds each role, and its type.
pub(crate) struct Plan {
    /// Property index per role; `None` when absent (colours: all three or none).
    pub(crate) prop: [Option<usize>; NROLES],
    /// Type per role (meaningless where `prop` is `None`).
    pub(crate) ty: [Scalar; NROLES],
}

impl Plan {
    pub(crate) fn new(vertex: &Element, path: &Path) -> Result<Plan, IoError> {
        let mut plan = Plan {
            prop: [None; NROLES],
            ty: [Scalar::U8; NROLES],
        };
        for (role, name) in ROLES.iter().enumerate() {
            let Some((k, p)) = vertex
                .props
                .iter()
                .enumerate()
                .find(|(_, p)| p.name == *name)
            else {
                continue;
            };
            match p.kind {
                PropKind::Scalar(s) => {
                    plan.prop[role] = Some(k);
                    plan.ty[role] = s;
                }
                PropKind::List { .. } if SCALAR_ONLY.contains(&role) => {
                    return Err(IoError::BadHeader {
                        line: p.line,
                        reason: format!("vertex property '{name}' is a list, expected a scalar"),
                        path: path.to_path_buf(),
                    });
                }
                PropKind::List { .. } => {} // an optional role we cannot use: ignored
            }
        }
        for role in REQUIRED {
            if plan.prop[role].is_none() {
                return Err(IoError::MissingProperty {
                    element: "vertex".into(),
                    property: ROLES[role].into(),
                    path: path.to_path_buf(),
                });
            }
        }
        if [RED, GREEN, BLUE].iter().any(|&r| plan.prop[r].is_none()) {
            for r in [RED, GREEN, BLUE] {
                plan.prop[r] = None;
            }
        }
        Ok(plan)
    }

    pub(crate) fn has(&self, role: usize) -> bool {
        self.prop[role].is_some()
    }

    /// The role of each vertex property (`None` = ignored).
    pub(crate) fn role_of_prop(&self, vertex: &Element) -> Vec<Option<usize>> {
        let mut roles = vec![None; vertex.props.len()];
        for (role, prop) in self.prop.iter().enumerate() {
            if let Some(k) = prop {
                roles[*k] = Some(role);
            }
        }
        roles
    }
}

/// PCL's `range_grid` of an organised PLY: each cell's first vertex index, if any.
pub(crate) type RangeGrid = Vec<Option<u32>>;

/// The vertices read, and the first label that is no class id (vertex, value).
pub(crate) struct Vertices {
    pub(crate) cloud: LabeledCloud,
    pub(crate) foreign: Option<(usize, String)>,
}

/// Collects validated vertices into a cloud.
pub(crate) struct Sink<'a> {
    pub(crate) cloud: LabeledCloud,
    pub(crate) foreign: Option<(usize, String)>,
    pub(crate) plan: &'a Plan,
    pub(crate) path: &'a Path,
}

impl<'a> Sink<'a> {
    /// `capacity` must already be bounded by the data size (a header may lie).
    pub(crate) fn new(plan: &'a Plan, capacity: usize, path: &'a Path) -> Sink<'a> {
        let has_colors = plan.has(RED);
        Sink {
            cloud: LabeledCloud {
                positions_m: Vec::with_capacity(capacity),
                labels: Vec::with_capacity(capacity),
                colors: has_colors.then(|| Vec::with_capacity(capacity)),
                origins: Vec::with_capacity(capacity),
            },
            foreign: None,
            plan,
            path,
        }
    }

    pub(crate) fn finish(self) -> Vertices {
        Vertices {
            cloud: self.cloud,
            foreign: self.foreign,
        }
    }

    /// Validates and appends vertex `index` (`v` indexed by role).
    #[inline]
    pub(crate) fn push(&mut self, index: usize, v: &[f64; NROLES]) -> Result<(), IoError> {
        let p = [v[X] as f32, v[Y] as f32, v[Z] as f32];
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            let role = (X..=Z).find(|&r| !(v[r] as f32).is_finite()).unwrap_or(X);
            return Err(self.bad(index, role, v, "a finite number (within float range)"));
        }
        let label = if self.plan.has(LABEL) {
            let class = whole(v[LABEL], 255.0).and_then(|id| Label::from_id(id as u8));
            class.unwrap_or_else(|| {
                // Another tool's ids; the caller decides (FileLabels::Foreign).
                self.foreign
                    .get_or_insert_with(|| (index, v[LABEL].to_string()));
                Label::UNKNOWN
            })
        } else {
            Label::UNKNOWN
        };
        if let Some(colors) = &mut self.cloud.colors {
            let mut rgb = [0u8; 3];
            for (c, role) in rgb.iter_mut().zip([RED, GREEN, BLUE]) {
                let ty = self.plan.ty[role];
                let value = if ty.is_float() {
                    (0.0..=1.0)
                        .contains(&v[role])
                        .then(|| (v[role] * 255.0).round() as u8)
                } else {
                    whole(v[role], 255.0).map(|c| c as u8)
                };
                *c = match value {
                    Some(c) => c,
                    None => {
                        let want = if ty.is_float() { "0..=1" } else { "0..=255" };
                        return Err(bad_value(index, role, v, want, self.path));
                    }
                };
            }
            colors.push(rgb);
        }
        let camera = if self.plan.has(CAMERA) {
            whole(v[CAMERA], 255.0).ok_or_else(|| self.bad(index, CAMERA, v, "0..=255"))? as u8
        } else {
            0
        };
        let pixel = if self.plan.has(PIXEL) {
            whole(v[PIXEL], f64::from(u32::MAX))
                .ok_or_else(|| self.bad(index, PIXEL, v, "0..=4294967295"))?
        } else {
            u32::try_from(index).map_err(|_| IoError::BadValue {
                element: "vertex".into(),
                index,
                property: "pixel".into(),
                value: "absent".into(),
                expected: "a pixel property in clouds of more than 2^32 points",
                path: self.path.to_path_buf(),
            })?
        };
        self.cloud.positions_m.push(p);
        self.cloud.labels.push(label);
        self.cloud.origins.push(PointOrigin { camera, pixel });
        Ok(())
    }

    #[cold]
    pub(crate) fn bad(
        &self,
        index: usize,
        role: usize,
        v: &[f64; NROLES],
        expected: &'static str,
    ) -> IoError {
        bad_value(index, role, v, expected, self.path)
    }
}

#[cold]
pub(crate) fn bad_value(
    index: usize,
    role: usize,
    v: &[f64; NROLES],
    expected: &'static str,
    path: &Path,
) -> IoError {
    IoError::BadValue {
        element: "vertex".into(),
        index,
        property: ROLES[role].into(),
        value: v[role].to_string(),
        expected,
        path: path.to_path_buf(),
    }
}

/// `v` as a whole number in `0..=max`.
#[inline]
pub(crate) fn whole(v: f64, max: f64) -> Option<u32> {
    // NaN fails both comparisons.
    (v >= 0.0 && v <= max && v.fract() == 0.0).then_some(v as u32)
}

pub(crate) fn truncated(element: &Element, read: usize, path: &Path) -> IoError {
    IoError::Truncated {
        element: element.name.clone(),
        expected: element.count,
        read,
        path: path.to_path_buf(),
    }
}

// ---------------------------------------------------------------------------------------
// Binary

/// PCL's element of an organised cloud's cells: one list property, each cell's vertex.
pub(crate) fn is_range_grid(e: &Element) -> bool {
    e.name == "range_grid"
        && matches!(e.props[..], [ref p] if matches!(p.kind, PropKind::List { .. }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_accepts_only_whole_numbers_in_range() {
        assert_eq!(whole(0.0, 255.0), Some(0));
        assert_eq!(whole(255.0, 255.0), Some(255));
        assert_eq!(
            whole(f64::from(u32::MAX), f64::from(u32::MAX)),
            Some(u32::MAX)
        );
        for bad in [256.0, -1.0, 0.5, f64::NAN, f64::INFINITY] {
            assert_eq!(whole(bad, 255.0), None, "{bad}");
        }
    }
}
