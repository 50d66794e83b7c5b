//! Rigid transforms between frames, named `a_from_b`.

use crate::CalibError;

/// Largest deviation of `R·Rᵀ` from the identity (any entry) and of `det R` from +1 that a
/// rotation matrix may have. Calibration files print 16–17 significant digits, so a real
/// rotation is orthonormal to ~1e-15; 1e-6 still catches a typo or a transposed entry.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// Largest deviation of a quaternion's norm from 1 that is accepted (and then normalised
/// away). Hand-written quaternions with 4 decimals are off by ~1e-4; more than 1e-3 is
/// taken as a mistake rather than rounding.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// A rigid transform `a_from_b`: `p_a = rotation · p_b + translation_m`.
///
/// The rotation is validated on construction (orthonormal within [`ROTATION_TOLERANCE`],
/// determinant +1), so a `Pose` is always a proper rigid motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    rotation: [[f64; 3]; 3],
    translation_m: [f64; 3],
}

impl Default for Pose {
    fn default() -> Self {
        Self::identity()
    }
}

impl Pose {
    /// The identity transform (frame a = frame b).
    pub fn identity() -> Self {
        Pose {
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation_m: [0.0; 3],
        }
    }

    /// From a row-major rotation matrix and a translation (metres). Errors name the field:
    /// `rotation` when the matrix is not finite, not orthonormal or a reflection,
    /// `translation_m` when the translation is not finite.
    pub fn from_rotation_translation(
        rotation: [[f64; 3]; 3],
        translation_m: [f64; 3],
    ) -> Result<Self, CalibError> {
        validate_rotation(&rotation)?;
        validate_translation(translation_m)?;
        Ok(Pose {
            rotation,
            translation_m,
        })
    }

    /// From a unit quaternion `[w, x, y, z]` (Hamilton convention, rotating b into a) and
    /// a translation (metres). The quaternion is normalised; its norm must be within
    /// [`QUATERNION_NORM_TOLERANCE`] of 1 (error on field `quaternion_wxyz`).
    pub fn from_quaternion_wxyz(q: [f64; 4], translation_m: [f64; 3]) -> Result<Self, CalibError> {
        let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !norm.is_finite() || (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(CalibError::invalid(
                "quaternion_wxyz",
                format!(
                    "must have norm 1 (within {QUATERNION_NORM_TOLERANCE}), got {q:?} with norm {norm}"
                ),
            ));
        }
        let [w, x, y, z] = q.map(|c| c / norm);
        let rotation = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        Self::from_rotation_translation(rotation, translation_m)
    }

    /// The rotation matrix, row-major.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        self.rotation
    }

    /// The translation, metres (the origin of frame b expressed in frame a).
    pub fn translation_m(&self) -> [f64; 3] {
        self.translation_m
    }

    /// The rotation as a unit quaternion `[w, x, y, z]` with w ≥ 0 (Shepperd's method).
    pub fn quaternion_wxyz(&self) -> [f64; 4] {
        let r = &self.rotation;
        let trace = r[0][0] + r[1][1] + r[2][2];
        let q = if trace > 0.0 {
            let s = 2.0 * (trace + 1.0).sqrt();
            [
                0.25 * s,
                (r[2][1] - r[1][2]) / s,
                (r[0][2] - r[2][0]) / s,
                (r[1][0] - r[0][1]) / s,
            ]
        } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
            let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
            [
                (r[2][1] - r[1][2]) / s,
                0.25 * s,
                (r[0][1] + r[1][0]) / s,
                (r[0][2] + r[2][0]) / s,
            ]
        } else if r[1][1] > r[2][2] {
            let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
            [
                (r[0][2] - r[2][0]) / s,
                (r[0][1] + r[1][0]) / s,
                0.25 * s,
                (r[1][2] + r[2][1]) / s,
            ]
        } else {
            let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
            [
                (r[1][0] - r[0][1]) / s,
                (r[0][2] + r[2][0]) / s,
                (r[1][2] + r[2][1]) / s,
                0.25 * s,
            ]
        };
        if q[0] < 0.0 { q.map(|c| -c) } else { q }
    }

    /// Maps a point of frame b into frame a: `R · p_b + t`.
    pub fn transform_point(&self, p_b: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        let t = self.translation_m;
        [
            r[0][0] * p_b[0] + r[0][1] * p_b[1] + r[0][2] * p_b[2] + t[0],
            r[1][0] * p_b[0] + r[1][1] * p_b[1] + r[1][2] * p_b[2] + t[1],
            r[2][0] * p_b[0] + r[2][1] * p_b[1] + r[2][2] * p_b[2] + t[2],
        ]
    }

    /// The inverse transform, `b_from_a`.
    pub fn inverse(&self) -> Pose {
        let r = &self.rotation;
        let rt = [
            [r[0][0], r[1][0], r[2][0]],
            [r[0][1], r[1][1], r[2][1]],
            [r[0][2], r[1][2], r[2][2]],
        ];
        let t = self.translation_m;
        let mut ti = [0.0; 3];
        for i in 0..3 {
            ti[i] = -(rt[i][0] * t[0] + rt[i][1] * t[1] + rt[i][2] * t[2]);
        }
        Pose {
            rotation: rt,
            translation_m: ti,
        }
    }

    /// Composition: `a_from_b.compose(&b_from_c)` is `a_from_c`
    /// (`p_a = a_from_b · (b_from_c · p_c)`).
    pub fn compose(&self, b_from_c: &Pose) -> Pose {
        let a = &self.rotation;
        let b = &b_from_c.rotation;
        let mut rotation = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rotation[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            }
        }
        Pose {
            rotation,
            translation_m: self.transform_point(b_from_c.translation_m),
        }
    }
}

fn validate_rotation(r: &[[f64; 3]; 3]) -> Result<(), CalibError> {
    if r.iter().flatten().any(|c| !c.is_finite()) {
        return Err(CalibError::invalid(
            "rotation",
            format!("must be finite, got {r:?}"),
        ));
    }
    let mut worst = 0.0_f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot = r[i][0] * r[j][0] + r[i][1] * r[j][1] + r[i][2] * r[j][2];
            let want = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((dot - want).abs());
        }
    }
    if worst > ROTATION_TOLERANCE {
        return Err(CalibError::invalid(
            "rotation",
            format!(
                "is not orthonormal (R·Rᵀ differs from I by {worst:e} > {ROTATION_TOLERANCE:e}): {r:?}"
            ),
        ));
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if (det - 1.0).abs() > ROTATION_TOLERANCE {
        return Err(CalibError::invalid(
            "rotation",
            format!("must have determinant +1 (a reflection is not a rotation), got {det}: {r:?}"),
        ));
    }
    Ok(())
}

fn validate_translation(t: [f64; 3]) -> Result<(), CalibError> {
    if t.iter().any(|c| !c.is_finite()) {
        return Err(CalibError::invalid(
            "translation_m",
            format!("must be finite, got {t:?}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    // Comparisons of f64 results of a handful of products: 1e-12 leaves room for rounding.
    const EPS: f64 = 1e-12;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < EPS)
    }

    #[test]
    fn quaternion_about_z_rotates_x_into_y() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let pose = Pose::from_quaternion_wxyz([h, 0.0, 0.0, h], [1.0, 2.0, 3.0]).expect("valid");
        assert!(close(
            pose.transform_point([1.0, 0.0, 0.0]),
            [1.0, 3.0, 3.0]
        ));
    }

    #[test]
    fn quaternion_round_trips_through_the_matrix() {
        for q in [
            [1.0, 0.0, 0.0, 0.0],
            [0.5, 0.5, -0.5, 0.5],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [0.1, 0.7, -0.7, 0.1],
        ] {
            let n = q.iter().map(|c: &f64| c * c).sum::<f64>().sqrt();
            let q = q.map(|c| c / n);
            let pose = Pose::from_quaternion_wxyz(q, [0.0; 3]).expect("valid");
            let back = pose.quaternion_wxyz();
            // q and -q are the same rotation; compare up to sign.
            let sign = if back[0] * q[0] + back[1] * q[1] + back[2] * q[2] + back[3] * q[3] < 0.0 {
                -1.0
            } else {
                1.0
            };
            for i in 0..4 {
                assert!((back[i] - sign * q[i]).abs() < EPS, "{q:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn inverse_and_compose_undo_each_other() {
        let pose = Pose::from_quaternion_wxyz([0.9, 0.1, -0.3, 0.2], [0.5, -1.0, 2.0]);
        let err = pose.expect_err("norm 0.97 is too far from 1");
        assert!(err.to_string().starts_with("quaternion_wxyz "), "{err}");
        let q = [0.9_f64, 0.1, -0.3, 0.2];
        let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        let pose = Pose::from_quaternion_wxyz(q.map(|c| c / n), [0.5, -1.0, 2.0]).expect("valid");
        let p = [0.3, -0.7, 1.9];
        assert!(close(
            pose.inverse().transform_point(pose.transform_point(p)),
            p
        ));
        let id = pose.compose(&pose.inverse());
        assert!(close(id.transform_point(p), p));
        let twice = pose.compose(&pose);
        assert!(close(
            twice.transform_point(p),
            pose.transform_point(pose.transform_point(p))
        ));
    }

    #[test]
    fn bad_rotations_are_rejected_naming_the_field() {
        let scaled = [[1.001, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let err = Pose::from_rotation_translation(scaled, [0.0; 3]).expect_err("not orthonormal");
        assert!(
            err.to_string().starts_with("rotation is not orthonormal"),
            "{err}"
        );
        let reflection = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let err = Pose::from_rotation_translation(reflection, [0.0; 3]).expect_err("det -1");
        assert!(err.to_string().contains("determinant +1"), "{err}");
        let nan = [[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(Pose::from_rotation_translation(nan, [0.0; 3]).is_err());
        let err =
            Pose::from_rotation_translation(Pose::identity().rotation(), [0.0, f64::INFINITY, 0.0])
                .expect_err("infinite translation");
        assert!(err.to_string().starts_with("translation_m "), "{err}");
    }
}
