//! Pinhole camera with OpenCV's lens distortion ([`Distortion`]: Brown-Conrady or rational).

use crate::{CalibError, Distortion};

/// Iterations [`Intrinsics::undistort`] may take. Newton converges in 3–6 on real lenses;
/// the limit only stops a diverging case.
const UNDISTORT_MAX_ITERATIONS: usize = 50;

/// Largest reprojection residual, pixels, that [`Intrinsics::undistort`] accepts as
/// converged. Two orders below the 1e-6 px the crate promises, so f64 rounding in
/// `project` cannot push a round trip over it.
const UNDISTORT_TOLERANCE_PX: f64 = 1e-8;

/// Intrinsics of one sensor: image size, pinhole parameters and lens distortion as
/// OpenCV defines them (`cv::projectPoints` with `k1 k2 p1 p2 k3`, or the rational
/// model's eight coefficients).
///
/// Frame: the sensor's OpenCV optical frame (x right, y down, z forward, metres).
/// Pixel coordinates (u, v) = (column, row), integer values at pixel centres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point, column, pixels.
    pub cx: f64,
    /// Principal point, row, pixels.
    pub cy: f64,
    /// Lens distortion on normalised coordinates (unitless coefficients).
    pub distortion: Distortion,
}

impl Intrinsics {
    /// A pinhole camera without distortion: image size (pixels), focal lengths and
    /// principal point (pixels); add a lens with [`Intrinsics::with_distortion`].
    pub const fn pinhole(width: u32, height: u32, fx: f64, fy: f64, cx: f64, cy: f64) -> Self {
        Intrinsics {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
            distortion: Distortion::NONE,
        }
    }

    /// The same camera with lens distortion `distortion`.
    #[must_use]
    pub const fn with_distortion(self, distortion: Distortion) -> Self {
        Intrinsics { distortion, ..self }
    }

    /// Checks sizes > 0, focal lengths finite and > 0, every other value finite.
    /// The error names the field.
    pub fn validate(&self) -> Result<(), CalibError> {
        if self.width == 0 {
            return Err(CalibError::invalid("width", "must be > 0, got 0"));
        }
        if self.height == 0 {
            return Err(CalibError::invalid("height", "must be > 0, got 0"));
        }
        if u32::try_from(self.num_pixels()).is_err() {
            return Err(CalibError::invalid(
                "width",
                format!(
                    "{}x{} has more pixels than a u32 pixel index can address",
                    self.width, self.height
                ),
            ));
        }
        for (field, value) in [("fx", self.fx), ("fy", self.fy)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(CalibError::invalid(
                    field,
                    format!("must be finite and > 0, got {value}"),
                ));
            }
        }
        for (field, value) in [("cx", self.cx), ("cy", self.cy)] {
            if !value.is_finite() {
                return Err(CalibError::invalid(
                    field,
                    format!("must be finite, got {value}"),
                ));
            }
        }
        if let Some(bad) = self
            .distortion
            .coefficients()
            .iter()
            .find(|d| !d.is_finite())
        {
            return Err(CalibError::invalid(
                "distortion",
                format!("must be finite, got {bad}"),
            ));
        }
        Ok(())
    }

    /// The intrinsics of an OpenCV camera matrix `K` (3×3, row-major) and a distortion
    /// vector as OpenCV reads it (see [`Distortion::from_opencv`]), not validated. `None`
    /// when the distortion vector's length is not one OpenCV's pinhole models use.
    ///
    /// # Panics
    /// Never for `k` of 9 values (callers check the shape).
    #[cfg(feature = "opencv")]
    pub(crate) fn from_camera_matrix(
        width: u32,
        height: u32,
        k: &[f64],
        d: &[f64],
    ) -> Option<Self> {
        Some(
            Intrinsics::pinhole(width, height, k[0], k[4], k[2], k[5])
                .with_distortion(Distortion::from_opencv(d)?),
        )
    }

    /// Number of pixels, `width * height`.
    pub fn num_pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// True when (u, v) lies on the image: pixel centres are integers, so the image spans
    /// `[-0.5, width - 0.5) × [-0.5, height - 0.5)`.
    pub fn contains(&self, uv_px: [f64; 2]) -> bool {
        let [u, v] = uv_px;
        u >= -0.5
            && v >= -0.5
            && u < f64::from(self.width) - 0.5
            && v < f64::from(self.height) - 0.5
    }

    /// Projects a point of the sensor frame (metres) to pixel coordinates, distortion
    /// included. `None` when the point is not in front of the camera (z ≤ 0), not
    /// finite, or where a rational model's denominator is ≤ 0 (see
    /// [`Distortion::distort`]). The pixel may lie outside the image; see
    /// [`Intrinsics::contains`].
    pub fn project(&self, p_camera: [f64; 3]) -> Option<[f64; 2]> {
        let [x, y, z] = p_camera;
        if z <= 0.0 || !x.is_finite() || !y.is_finite() || !z.is_finite() {
            return None;
        }
        let [xd, yd] = self.distort([x / z, y / z])?;
        Some([self.fx * xd + self.cx, self.fy * yd + self.cy])
    }

    /// Applies the distortion to normalised coordinates (x/z, y/z); see [`Distortion`].
    pub fn distort(&self, xy: [f64; 2]) -> Option<[f64; 2]> {
        self.distortion.distort(xy)
    }

    /// Inverts [`Intrinsics::distort`] by Newton's method, starting from the distorted
    /// point. Returns the normalised coordinates whose distortion lands within 1e-8 px
    /// of `xy_distorted`, or `None` when the iteration does not get there or lands beyond
    /// the fold of the radial factor (far outside the image, where the model is not
    /// invertible: it maps two rays to one pixel) or beyond a rational model's pole.
    ///
    /// Inside the field of view of real lenses, Brown-Conrady and rational alike, it
    /// converges in a few iterations (tests: every pixel of a Kinect v2 and of an Azure
    /// Kinect's depth and colour sensors, round trip < 1e-6 px). Beyond the fold it
    /// returns `None` rather than a second root.
    pub fn undistort(&self, xy_distorted: [f64; 2]) -> Option<[f64; 2]> {
        // Tolerance in normalised units: pixels over the larger focal length.
        let tol = UNDISTORT_TOLERANCE_PX / self.fx.max(self.fy);
        let mut xy = xy_distorted;
        for _ in 0..UNDISTORT_MAX_ITERATIONS {
            let (d, [[a, b], [c, e]]) = self.distortion.distort_with_jacobian(xy)?;
            let rx = d[0] - xy_distorted[0];
            let ry = d[1] - xy_distorted[1];
            let det = a * e - b * c;
            if rx.abs() <= tol && ry.abs() <= tol {
                // det ≤ 0: a root beyond the fold of the radial polynomial, where the
                // model no longer describes the lens (it maps two rays to one pixel).
                return (det > 0.0).then_some(xy);
            }
            if !det.is_finite() || det.abs() < 1e-12 {
                return None;
            }
            xy = [
                xy[0] - (e * rx - b * ry) / det,
                xy[1] - (a * ry - c * rx) / det,
            ];
            if !(xy[0].is_finite() && xy[1].is_finite()) {
                return None;
            }
        }
        None
    }

    /// The ray through pixel (u, v), as undistorted normalised coordinates `(x', y', 1)`:
    /// the point at depth z (metres) is `z · ray`. `None` when undistortion does not
    /// converge (see [`Intrinsics::undistort`]).
    pub fn unproject(&self, u: f64, v: f64) -> Option<[f64; 3]> {
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        let [x, y] = self.undistort([xd, yd])?;
        Some([x, y, 1.0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinect_ir() -> Intrinsics {
        Intrinsics {
            width: 512,
            height: 424,
            fx: 366.9,
            fy: 364.8,
            cx: 243.0,
            cy: 207.7,
            distortion: Distortion::BrownConrady([0.0966, -0.283, 0.000159, -0.000508, 0.105]),
        }
    }

    #[test]
    fn undistort_refuses_points_beyond_the_fold() {
        // r_d = r (1 - 0.5 r²) peaks at r = sqrt(2/3), r_d ≈ 0.544: beyond it there is no
        // solution, below it the root on the rising branch is the physical one.
        let cam = Intrinsics {
            distortion: Distortion::BrownConrady([-0.5, 0.0, 0.0, 0.0, 0.0]),
            ..kinect_ir()
        };
        assert!(cam.undistort([0.6, 0.0]).is_none());
        let xy = cam.undistort([0.5, 0.0]).expect("on the rising branch");
        assert!(xy[0] < (2.0_f64 / 3.0).sqrt(), "{xy:?}");
        // Residual below the 1e-8 px acceptance over fx ≈ 367.
        assert!((cam.distort(xy).expect("Brown-Conrady maps every point")[0] - 0.5).abs() < 1e-10);
    }

    #[test]
    fn project_rejects_points_behind_or_on_the_camera_plane() {
        let cam = kinect_ir();
        assert!(cam.project([0.1, 0.1, -1.0]).is_none());
        assert!(cam.project([0.1, 0.1, 0.0]).is_none());
        assert!(cam.project([f64::NAN, 0.1, 1.0]).is_none());
        assert!(cam.project([0.0, 0.0, 2.0]).is_some());
    }

    #[test]
    fn principal_point_projects_to_itself() {
        let cam = kinect_ir();
        let uv = cam
            .project([0.0, 0.0, 1.5])
            .expect("in front of the camera");
        assert_eq!(uv, [cam.cx, cam.cy]);
    }

    #[test]
    fn zero_distortion_is_plain_pinhole() {
        let cam = Intrinsics {
            distortion: Distortion::NONE,
            ..kinect_ir()
        };
        let uv = cam.project([0.5, -0.25, 2.0]).expect("in front");
        // Exact arithmetic up to one rounding per operation.
        assert!((uv[0] - (366.9 * 0.25 + 243.0)).abs() < 1e-9);
        assert!((uv[1] - (364.8 * -0.125 + 207.7)).abs() < 1e-9);
    }

    #[test]
    fn validate_names_the_bad_field() {
        let bad = Intrinsics {
            fy: -1.0,
            ..kinect_ir()
        };
        let msg = bad.validate().expect_err("negative fy").to_string();
        assert!(msg.starts_with("fy "), "{msg}");
        let bad = Intrinsics {
            cx: f64::NAN,
            ..kinect_ir()
        };
        assert!(
            bad.validate()
                .expect_err("NaN cx")
                .to_string()
                .starts_with("cx ")
        );
        let bad = Intrinsics {
            width: 0,
            ..kinect_ir()
        };
        assert!(bad.validate().is_err());
        assert!(kinect_ir().validate().is_ok());
    }

    #[test]
    fn contains_uses_pixel_centres() {
        let cam = kinect_ir();
        assert!(cam.contains([-0.5, -0.5]));
        assert!(cam.contains([511.49, 423.49]));
        assert!(!cam.contains([511.5, 0.0]));
        assert!(!cam.contains([0.0, -0.51]));
    }
}
