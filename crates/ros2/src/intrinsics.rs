//! `sensor_msgs/CameraInfo` → [`Intrinsics`], with ROS' semantics:
//! - a raw image (distorted, as the sensor saw it) is described by `k` and `d` with
//!   `distortion_model` `plumb_bob` (k1 k2 p1 p2 k3) or `rational_polynomial`
//!   (k1 k2 p1 p2 k3 k4 k5 k6); an empty `d` is no distortion;
//! - a rectified image (`image_rect`, iai_kinect2's `*_rect`) by `p` (fx = p[0],
//!   fy = p[5], cx = p[2], cy = p[6]) and no distortion.
//!
//! `binning_x`/`binning_y` above 1 are refused (the published image would be smaller
//! than the calibration); `roi` is ignored (a non-empty region with `do_rectify` is
//! noted by the caller).

use crate::Ros2Error;
use crate::msg::CameraInfoMsg;
use bodyseg_calib::{Distortion, Intrinsics};

/// The intrinsics of images described by `info`: rectified (`rect`) or raw.
///
/// # Errors
/// [`Ros2Error::Unsupported`] naming `distortion_model` or `binning_x`/`binning_y`;
/// [`Ros2Error::Invalid`] naming `d` (a coefficient count the model does not have),
/// `k` / `p` (zero focal length, skew, a last row other than 0 0 1) or the intrinsics
/// bodyseg-calib refuses.
pub fn intrinsics_of(info: &CameraInfoMsg, rect: bool) -> Result<Intrinsics, Ros2Error> {
    for (field, value) in [("binning_x", info.binning_x), ("binning_y", info.binning_y)] {
        if value > 1 {
            return Err(Ros2Error::Unsupported {
                field: field.into(),
                value: value.to_string(),
                supported: "0 or 1: bodyseg reads unbinned images".into(),
            });
        }
    }
    let (fx, fy, cx, cy, distortion) = if rect {
        let p = &info.p;
        if p[1] != 0.0 || p[4] != 0.0 || [p[8], p[9], p[10], p[11]] != [0.0, 0.0, 1.0, 0.0] {
            return Err(Ros2Error::invalid(format!(
                "field p: must be [fx 0 cx Tx; 0 fy cy Ty; 0 0 1 0] for rectified images, \
                 got {p:?}"
            )));
        }
        (p[0], p[5], p[2], p[6], Distortion::NONE)
    } else {
        let k = &info.k;
        if k[1] != 0.0 || [k[3], k[6], k[7], k[8]] != [0.0, 0.0, 0.0, 1.0] {
            return Err(Ros2Error::invalid(format!(
                "field k: must be [fx 0 cx; 0 fy cy; 0 0 1] (no skew), got {k:?}"
            )));
        }
        (k[0], k[4], k[2], k[5], distortion_of(info)?)
    };
    let intrinsics =
        Intrinsics::pinhole(info.width, info.height, fx, fy, cx, cy).with_distortion(distortion);
    intrinsics.validate().map_err(|e| {
        Ros2Error::invalid(format!(
            "field {}: {e} (width {}, height {})",
            if rect { "p" } else { "k" },
            info.width,
            info.height
        ))
    })?;
    Ok(intrinsics)
}

/// The distortion of a raw image: the model's name, then the coefficients' count.
fn distortion_of(info: &CameraInfoMsg) -> Result<Distortion, Ros2Error> {
    let d = &info.d;
    let wrong_count = |want: &str| {
        Ros2Error::invalid(format!(
            "field d: {} values under distortion_model {:?}, which has {want}",
            d.len(),
            info.distortion_model
        ))
    };
    match info.distortion_model.as_str() {
        // A camera without calibration publishes an empty model and no coefficients.
        "" if d.is_empty() => Ok(Distortion::NONE),
        "plumb_bob" | "" => match d.len() {
            0 | 4 | 5 => Distortion::from_opencv(d).ok_or_else(|| wrong_count("5")),
            _ => Err(wrong_count("5 (k1 k2 p1 p2 k3)")),
        },
        "rational_polynomial" => match d.len() {
            8 => Distortion::from_opencv(d).ok_or_else(|| wrong_count("8")),
            // Some drivers publish only the first five; the rest are 0.
            5 => Distortion::from_opencv(&[d[0], d[1], d[2], d[3], d[4], 0.0, 0.0, 0.0])
                .ok_or_else(|| wrong_count("8")),
            _ => Err(wrong_count("8 (k1 k2 p1 p2 k3 k4 k5 k6)")),
        },
        other => Err(Ros2Error::Unsupported {
            field: "distortion_model".into(),
            value: other.into(),
            supported: "plumb_bob, rational_polynomial".into(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{Header, Roi};

    fn info(model: &str, d: Vec<f64>) -> CameraInfoMsg {
        CameraInfoMsg {
            header: Header::default(),
            height: 424,
            width: 512,
            distortion_model: model.into(),
            d,
            k: [366.0, 0.0, 256.0, 0.0, 365.0, 212.0, 0.0, 0.0, 1.0],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: [
                360.0, 0.0, 250.0, 0.0, 0.0, 361.0, 210.0, 0.0, 0.0, 0.0, 1.0, 0.0,
            ],
            binning_x: 0,
            binning_y: 0,
            roi: Roi::default(),
        }
    }

    #[test]
    fn raw_images_take_k_and_d_rectified_ones_p_and_no_distortion() {
        let i = info("plumb_bob", vec![0.1, -0.2, 0.001, 0.002, 0.05]);
        let raw = intrinsics_of(&i, false).expect("raw");
        assert_eq!(
            (raw.fx, raw.fy, raw.cx, raw.cy),
            (366.0, 365.0, 256.0, 212.0)
        );
        assert_eq!(
            raw.distortion,
            Distortion::BrownConrady([0.1, -0.2, 0.001, 0.002, 0.05])
        );
        let rect = intrinsics_of(&i, true).expect("rect");
        assert_eq!(
            (rect.fx, rect.fy, rect.cx, rect.cy),
            (360.0, 361.0, 250.0, 210.0)
        );
        assert_eq!(rect.distortion, Distortion::NONE);
        let rational = info(
            "rational_polynomial",
            (1..=8).map(|k| f64::from(k) * 0.01).collect(),
        );
        assert!(
            intrinsics_of(&rational, false)
                .expect("rational")
                .distortion
                .is_rational()
        );
    }

    #[test]
    fn unsupported_models_counts_and_binning_name_the_field() {
        let e = intrinsics_of(&info("equidistant", vec![0.0; 4]), false).expect_err("model");
        assert!(
            e.to_string()
                .contains("field distortion_model: \"equidistant\""),
            "{e}"
        );
        let e = intrinsics_of(&info("plumb_bob", vec![0.0; 7]), false).expect_err("count");
        assert!(e.to_string().contains("field d: 7 values"), "{e}");
        let mut binned = info("plumb_bob", vec![]);
        binned.binning_x = 2;
        let e = intrinsics_of(&binned, false).expect_err("binning");
        assert!(e.to_string().contains("binning_x"), "{e}");
        let mut zero = info("plumb_bob", vec![]);
        zero.p = [0.0; 12];
        let e = intrinsics_of(&zero, true).expect_err("zero p");
        assert!(e.to_string().contains("field p"), "{e}");
    }
}
