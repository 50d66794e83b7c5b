//! Lens distortion on normalised coordinates: OpenCV's Brown-Conrady (five coefficients)
//! and rational (eight coefficients) models, as `cv::projectPoints` applies them.

/// Lens distortion of one sensor, applied to normalised coordinates `(x/z, y/z)`, in
/// OpenCV's coefficient order (`cv::projectPoints`, `cv::undistortPoints`).
///
/// With `r² = x² + y²`, both models map `(x, y)` to
///
/// ```text
/// x_d = x·R(r²) + 2 p1 x y + p2 (r² + 2x²)
/// y_d = y·R(r²) + p1 (r² + 2y²) + 2 p2 x y
/// ```
///
/// where the radial factor `R` is `1 + k1 r² + k2 r⁴ + k3 r⁶` for
/// [`Distortion::BrownConrady`] and `(1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)`
/// for [`Distortion::Rational`]. A rational model with `k4 = k5 = k6 = 0` maps every point
/// exactly as the Brown-Conrady model with the same first five coefficients.
///
/// Names in other tools: ROS `plumb_bob` is [`Distortion::BrownConrady`], ROS
/// `rational_polynomial` (8 values) is [`Distortion::Rational`]; so is the Azure Kinect's
/// factory model, although the SDK calls it `BrownConrady` (its parameters are stored in
/// another order: see `read_azure_kinect_json`). OpenCV picks the model from the number
/// of coefficients (4, 5 or 8), as [`Distortion::from_opencv`] does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distortion {
    /// `[k1, k2, p1, p2, k3]`: radial k1 k2 k3, tangential p1 p2 (unitless).
    BrownConrady([f64; 5]),
    /// `[k1, k2, p1, p2, k3, k4, k5, k6]`: radial numerator k1 k2 k3, denominator k4 k5 k6,
    /// tangential p1 p2 (unitless; OpenCV's `CALIB_RATIONAL_MODEL`).
    Rational([f64; 8]),
}

impl Default for Distortion {
    fn default() -> Self {
        Distortion::NONE
    }
}

impl Distortion {
    /// No distortion (a pinhole camera): Brown-Conrady with every coefficient 0.
    pub const NONE: Distortion = Distortion::BrownConrady([0.0; 5]);

    /// The model OpenCV uses for a distortion vector of this length: 0 values (none),
    /// 4 (`k1 k2 p1 p2`, k3 = 0) or 5 → Brown-Conrady, 8 → rational. `None` for other
    /// lengths (12 and 14 add OpenCV's thin-prism and tilt terms, which bodyseg does
    /// not model).
    pub fn from_opencv(coefficients: &[f64]) -> Option<Distortion> {
        match *coefficients {
            [] => Some(Distortion::NONE),
            [k1, k2, p1, p2] => Some(Distortion::BrownConrady([k1, k2, p1, p2, 0.0])),
            [k1, k2, p1, p2, k3] => Some(Distortion::BrownConrady([k1, k2, p1, p2, k3])),
            [k1, k2, p1, p2, k3, k4, k5, k6] => {
                Some(Distortion::Rational([k1, k2, p1, p2, k3, k4, k5, k6]))
            }
            _ => None,
        }
    }

    /// Why [`Distortion::from_opencv`] refuses a vector of `n` values, for error messages.
    pub(crate) fn unsupported_count(n: usize) -> String {
        format!(
            "has {n} values: OpenCV's pinhole models have 0, 4 or 5 (k1 k2 p1 p2 [k3]) or 8 \
             (k1 k2 p1 p2 k3 k4 k5 k6)"
        )
    }

    /// The coefficients in OpenCV's order: 5 for Brown-Conrady, 8 for rational.
    pub fn coefficients(&self) -> &[f64] {
        match self {
            Distortion::BrownConrady(c) => c,
            Distortion::Rational(c) => c,
        }
    }

    /// The eight coefficients of the rational model that maps every point as this one
    /// (`k4 = k5 = k6 = 0` for Brown-Conrady).
    pub fn rational_coefficients(&self) -> [f64; 8] {
        match *self {
            Distortion::BrownConrady([k1, k2, p1, p2, k3]) => [k1, k2, p1, p2, k3, 0.0, 0.0, 0.0],
            Distortion::Rational(c) => c,
        }
    }

    /// Whether the model has a radial denominator (it is [`Distortion::Rational`]).
    pub fn is_rational(&self) -> bool {
        matches!(self, Distortion::Rational(_))
    }

    /// The radial factor `R(r²)` and its derivative `dR/d(r²)`; `None` where the
    /// rational model's denominator is ≤ 0 (no lens is described there: the factor
    /// changes sign through a pole).
    #[inline]
    fn radial(&self, r2: f64) -> Option<(f64, f64)> {
        match *self {
            Distortion::BrownConrady([k1, k2, _, _, k3]) => Some((
                1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)),
                k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2),
            )),
            Distortion::Rational([k1, k2, _, _, k3, k4, k5, k6]) => {
                let num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                let den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
                // NaN fails too.
                if den.is_nan() || den <= 0.0 {
                    return None;
                }
                let d_num = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
                let d_den = k4 + r2 * (2.0 * k5 + 3.0 * k6 * r2);
                Some((num / den, (d_num * den - num * d_den) / (den * den)))
            }
        }
    }

    /// `(p1, p2)`.
    #[inline]
    fn tangential(&self) -> (f64, f64) {
        match *self {
            Distortion::BrownConrady([_, _, p1, p2, _]) => (p1, p2),
            Distortion::Rational([_, _, p1, p2, ..]) => (p1, p2),
        }
    }

    /// Applies the distortion to normalised coordinates (see the type's formula).
    /// `None` only for the rational model where its denominator is ≤ 0 (far outside any
    /// real lens' field of view); Brown-Conrady always maps.
    #[inline]
    pub fn distort(&self, xy: [f64; 2]) -> Option<[f64; 2]> {
        let [x, y] = xy;
        let r2 = x * x + y * y;
        let (radial, _) = self.radial(r2)?;
        let (p1, p2) = self.tangential();
        Some([
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        ])
    }

    /// [`Distortion::distort`] and its Jacobian at `xy`: rows (∂x_d, ∂y_d), columns
    /// (∂x, ∂y).
    pub(crate) fn distort_with_jacobian(&self, xy: [f64; 2]) -> Option<([f64; 2], [[f64; 2]; 2])> {
        let [x, y] = xy;
        let r2 = x * x + y * y;
        let (radial, d_radial) = self.radial(r2)?;
        let (p1, p2) = self.tangential();
        let distorted = [
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        ];
        let dxd_dx = radial + x * d_radial * 2.0 * x + 2.0 * p1 * y + 6.0 * p2 * x;
        let dxd_dy = x * d_radial * 2.0 * y + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyd_dx = y * d_radial * 2.0 * x + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyd_dy = radial + y * d_radial * 2.0 * y + 6.0 * p1 * y + 2.0 * p2 * x;
        Some((distorted, [[dxd_dx, dxd_dy], [dyd_dx, dyd_dy]]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AZURE_DEPTH: Distortion = crate::testing::AZURE_DEPTH_DISTORTION;

    #[test]
    fn jacobian_matches_finite_differences() {
        let bc = Distortion::BrownConrady([0.0966, -0.283, 0.000159, -0.000508, 0.105]);
        for model in [bc, AZURE_DEPTH] {
            let h = 1e-7;
            for xy in [
                [0.3, -0.2],
                [-0.6, 0.5],
                [0.0, 0.0],
                [0.1, 0.7],
                [1.1, -0.9],
            ] {
                let (_, j) = model
                    .distort_with_jacobian(xy)
                    .expect("in the model's domain");
                for col in 0..2 {
                    let mut plus = xy;
                    let mut minus = xy;
                    plus[col] += h;
                    minus[col] -= h;
                    let dp = model.distort(plus).expect("domain");
                    let dm = model.distort(minus).expect("domain");
                    for row in 0..2 {
                        let numeric = (dp[row] - dm[row]) / (2.0 * h);
                        // Central differences with h = 1e-7 are accurate to ~1e-8 here.
                        assert!(
                            (numeric - j[row][col]).abs() < 1e-6,
                            "{model:?} xy {xy:?} J[{row}][{col}] = {} vs numeric {numeric}",
                            j[row][col]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn rational_with_zero_denominator_terms_is_brown_conrady_bit_for_bit() {
        let c = [0.0966, -0.283, 0.000159, -0.000508, 0.105];
        let bc = Distortion::BrownConrady(c);
        let rational = Distortion::Rational([c[0], c[1], c[2], c[3], c[4], 0.0, 0.0, 0.0]);
        for xy in [[0.3, -0.2], [-0.61, 0.47], [1e-9, 0.0], [0.9, 0.9]] {
            let (a, b) = (bc.distort(xy), rational.distort(xy));
            // Dividing by a denominator of exactly 1.0 is exact.
            assert_eq!(a, b, "{xy:?}");
        }
        assert_eq!(bc.rational_coefficients(), rational.rational_coefficients());
    }

    #[test]
    fn opencv_lengths_pick_the_model() {
        assert_eq!(Distortion::from_opencv(&[]), Some(Distortion::NONE));
        assert_eq!(
            Distortion::from_opencv(&[1.0, 2.0, 3.0, 4.0]),
            Some(Distortion::BrownConrady([1.0, 2.0, 3.0, 4.0, 0.0]))
        );
        let eight = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        assert_eq!(
            Distortion::from_opencv(&eight),
            Some(Distortion::Rational(eight))
        );
        assert_eq!(
            Distortion::from_opencv(&eight).map(|d| d.coefficients().len()),
            Some(8)
        );
        assert!(Distortion::from_opencv(&[0.0; 12]).is_none());
        assert!(Distortion::from_opencv(&[0.0; 6]).is_none());
    }

    #[test]
    fn rational_denominator_at_or_below_zero_has_no_image() {
        // 1 - r² reaches 0 at r = 1.
        let d = Distortion::Rational([0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0]);
        assert!(d.distort([0.5, 0.0]).is_some());
        assert!(d.distort([1.0, 0.0]).is_none());
        assert!(d.distort([0.8, 0.8]).is_none());
        assert!(d.distort([f64::NAN, 0.0]).is_none(), "NaN fails den > 0");
    }
}
