//! The synthetic camera network: Kinect v2-like RGB-D cameras around the workspace, and the
//! (optionally wrong) rig written for the pipeline.

// The calibration values are copied digit for digit from the iai_kinect2 files, more
// digits than an f64 holds, so that they can be compared with the files by eye.
#![allow(clippy::excessive_precision)]

use crate::config::{DsaConfig, RigConfig, SynthError};
use bodyseg_calib::{Distortion, Intrinsics, Pose, RgbdCamera, Rig};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The depth (IR) sensor of the Kinect v2 in `../shared/data/iai_kinect2/196605135147`
/// (`calib_ir.yaml`, iai_kinect2's calibration of a real device), 512×424.
pub fn kinect_v2_depth() -> Intrinsics {
    Intrinsics::pinhole(
        512,
        424,
        3.6694757270064110e+02,
        3.6479117165721783e+02,
        2.4298551682775121e+02,
        2.0769853575457685e+02,
    )
    .with_distortion(Distortion::BrownConrady([
        9.6558110377123016e-02,
        -2.8298244017989416e-01,
        1.5889951609432634e-04,
        -5.0751483524871712e-04,
        1.0523948765859192e-01,
    ]))
}

/// The colour sensor of the same device (`calib_color.yaml`), 1920×1080, scaled to
/// `width` (× 9/16 high). Scaling keeps the pixel-centre convention: a pixel centre `u`
/// at full resolution lies at `(u + 0.5)·s − 0.5` in the scaled image.
pub fn kinect_v2_color(width: u32) -> Intrinsics {
    let s = f64::from(width) / 1920.0;
    let height = (f64::from(width) * 9.0 / 16.0).round() as u32;
    Intrinsics::pinhole(
        width,
        height,
        1.0599465578241038e+03 * s,
        1.0539326808799726e+03 * s,
        (9.5488326677588441e+02 + 0.5) * s - 0.5,
        (5.2373858291060583e+02 + 0.5) * s - 0.5,
    )
    .with_distortion(Distortion::BrownConrady([
        5.6268441170930321e-02,
        -7.4199141308694802e-02,
        1.4250797540545752e-03,
        -1.6951722389720336e-03,
        2.4107681263086548e-02,
    ]))
}

/// The device's colour-from-depth extrinsic (`calib_pose.yaml`: X_c = R·X_ir + T, 5.2 cm
/// baseline).
pub fn kinect_v2_color_from_depth() -> Pose {
    // The file's rotation is orthonormal to ~1e-9 but not exactly: re-orthonormalise so
    // it passes `Pose` validation regardless of the tolerance.
    let r = orthonormalize([
        [
            9.9979883926593693e-01,
            -1.6871335541758126e-02,
            -1.0846153213119176e-02,
        ],
        [
            1.6891097527572209e-02,
            9.9985583336600126e-01,
            1.7330055664057141e-03,
        ],
        [
            1.0815351441312036e-02,
            -1.9158603854556545e-03,
            9.9993967700666042e-01,
        ],
    ]);
    let t = [
        -5.2052476112081990e-02,
        -4.6313865353939110e-04,
        8.8806735554907584e-04,
    ];
    Pose::from_rotation_translation(r, t).unwrap_or_default()
}

/// Gram-Schmidt on the rows.
fn orthonormalize(r: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let unit = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let x = unit(r[0]);
    let d = dot(r[1], x);
    let y = unit([r[1][0] - d * x[0], r[1][1] - d * x[1], r[1][2] - d * x[2]]);
    let z = [
        x[1] * y[2] - x[2] * y[1],
        x[2] * y[0] - x[0] * y[2],
        x[0] * y[1] - x[1] * y[0],
    ];
    [x, y, z]
}

/// Where camera `i` sits: centre (world, metres).
fn placements(config: &RigConfig) -> Vec<[f64; 3]> {
    if !config.placements.is_empty() {
        return config
            .placements
            .iter()
            .map(|p| {
                let a = p.azimuth_deg.to_radians();
                [p.distance_m * a.cos(), p.distance_m * a.sin(), p.height_m]
            })
            .collect();
    }
    let n = config.cameras as usize;
    (0..n)
        .map(|i| {
            let a = (config.first_azimuth_deg + 360.0 * i as f64 / n as f64).to_radians();
            let f = if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.5
            };
            let h = config.height_m[0] + (config.height_m[1] - config.height_m[0]) * f;
            [config.distance_m * a.cos(), config.distance_m * a.sin(), h]
        })
        .collect()
}

/// `world_from_camera` of an OpenCV optical frame at `eye` looking at `target` with world
/// z up (x right, y down in the image).
pub fn look_at(eye: [f64; 3], target: [f64; 3]) -> Result<Pose, SynthError> {
    let unit = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let z = unit([target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]]);
    let side = cross(z, [0.0, 0.0, 1.0]);
    if (side[0] * side[0] + side[1] * side[1] + side[2] * side[2]) < 1e-12 {
        return Err(SynthError::Invalid {
            field: "rig".into(),
            reason: "a camera looks straight up or down (place it beside the workspace)".into(),
        });
    }
    let x = unit(side);
    let y = cross(z, x);
    // Columns are the camera axes in world coordinates.
    let r = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]];
    Pose::from_rotation_translation(r, eye).map_err(|e| SynthError::Invalid {
        field: "rig".into(),
        reason: e.to_string(),
    })
}

/// The true rig: Kinect v2 cameras (`cam0`, `cam1`, …) placed by `config`, depth sensor
/// looking at the workspace centre at `look_at_height_m`.
pub fn true_rig(config: &RigConfig) -> Result<Rig, SynthError> {
    let target = [0.0, 0.0, config.look_at_height_m];
    let cameras = placements(config)
        .into_iter()
        .enumerate()
        .map(|(i, eye)| {
            let mut camera = RgbdCamera::new(
                format!("cam{i}"),
                kinect_v2_depth(),
                kinect_v2_color(config.color_width),
            );
            camera.color_from_depth = kinect_v2_color_from_depth();
            camera.world_from_depth = look_at(eye, target)?;
            Ok(camera)
        })
        .collect::<Result<Vec<_>, SynthError>>()?;
    Ok(Rig { cameras })
}

/// A rotation of `angle_rad` about a random axis and a translation of `length_m` in a
/// random direction.
fn random_error(rng: &mut ChaCha8Rng, angle_rad: f64, length_m: f64) -> Pose {
    let mut unit = || loop {
        let v: [f64; 3] = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let n: f64 = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.1 && n <= 1.0 {
            return [v[0] / n, v[1] / n, v[2] / n];
        }
    };
    let k = unit();
    let t = unit();
    let (s, c) = angle_rad.sin_cos();
    let v = 1.0 - c;
    // Rodrigues' formula.
    let r = [
        [
            c + k[0] * k[0] * v,
            k[0] * k[1] * v - k[2] * s,
            k[0] * k[2] * v + k[1] * s,
        ],
        [
            k[1] * k[0] * v + k[2] * s,
            c + k[1] * k[1] * v,
            k[1] * k[2] * v - k[0] * s,
        ],
        [
            k[2] * k[0] * v - k[1] * s,
            k[2] * k[1] * v + k[0] * s,
            c + k[2] * k[2] * v,
        ],
    ];
    Pose::from_rotation_translation(r, [t[0] * length_m, t[1] * length_m, t[2] * length_m])
        .unwrap_or_default()
}

/// The rig written to the recording: the true rig with the calibration error of `dsa`
/// (a random axis and direction per camera, fixed magnitudes; deterministic in `seed`).
/// With zero error it equals the true rig.
pub fn written_rig(truth: &Rig, dsa: &DsaConfig, seed: u64) -> Rig {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_CA11_B000_0001);
    let mut rig = truth.clone();
    for camera in &mut rig.cameras {
        let cfd = random_error(
            &mut rng,
            dsa.color_from_depth_rotation_deg.to_radians(),
            dsa.color_from_depth_translation_m,
        );
        let wfd = random_error(
            &mut rng,
            dsa.world_from_depth_rotation_deg.to_radians(),
            dsa.world_from_depth_translation_m,
        );
        if dsa.color_from_depth_rotation_deg > 0.0 || dsa.color_from_depth_translation_m > 0.0 {
            camera.color_from_depth = cfd.compose(&camera.color_from_depth);
        }
        if dsa.world_from_depth_rotation_deg > 0.0 || dsa.world_from_depth_translation_m > 0.0 {
            // Error applied in the depth frame: the camera seems moved about its own centre.
            camera.world_from_depth = camera.world_from_depth.compose(&wfd);
        }
    }
    rig
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cameras_look_at_the_centre_from_their_ring() {
        let config = RigConfig::default();
        let rig = true_rig(&config).expect("rig");
        assert_eq!(rig.cameras.len(), 3);
        rig.validate().expect("valid rig");
        for camera in &rig.cameras {
            let w = camera.world_from_depth;
            let eye = w.translation_m();
            let horizontal = (eye[0] * eye[0] + eye[1] * eye[1]).sqrt();
            assert!((horizontal - config.distance_m).abs() < 1e-9);
            assert!(eye[2] >= 1.8 - 1e-9 && eye[2] <= 2.5 + 1e-9);
            // The workspace centre projects near the depth image centre.
            let centre_cam = w
                .inverse()
                .transform_point([0.0, 0.0, config.look_at_height_m]);
            assert!(centre_cam[0].abs() < 1e-9 && centre_cam[1].abs() < 1e-9);
            assert!(centre_cam[2] > 0.0);
        }
    }

    #[test]
    fn scaled_color_keeps_the_field_of_view() {
        let full = kinect_v2_color(1920);
        let half = kinect_v2_color(960);
        assert_eq!((half.width, half.height), (960, 540));
        // The same ray lands on corresponding pixel centres.
        let p = [0.3, -0.2, 1.7];
        let a = full.project(p).expect("in front");
        let b = half.project(p).expect("in front");
        assert!(((a[0] + 0.5) * 0.5 - 0.5 - b[0]).abs() < 1e-9);
        assert!(((a[1] + 0.5) * 0.5 - 0.5 - b[1]).abs() < 1e-9);
    }

    #[test]
    fn written_rig_error_has_the_configured_size() {
        let truth = true_rig(&RigConfig::default()).expect("rig");
        assert_eq!(written_rig(&truth, &DsaConfig::default(), 1), truth);
        let dsa = DsaConfig {
            color_from_depth_rotation_deg: 1.0,
            color_from_depth_translation_m: 0.01,
            ..DsaConfig::default()
        };
        let wrong = written_rig(&truth, &dsa, 1);
        for (a, b) in truth.cameras.iter().zip(&wrong.cameras) {
            let delta = b.color_from_depth.compose(&a.color_from_depth.inverse());
            let r = delta.rotation();
            let angle = ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0)
                .clamp(-1.0, 1.0)
                .acos();
            assert!((angle.to_degrees() - 1.0).abs() < 1e-6, "{angle}");
            let t = delta.translation_m();
            let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            assert!((len - 0.01).abs() < 1e-9, "{len}");
            assert_eq!(a.world_from_depth, b.world_from_depth);
        }
        assert_ne!(written_rig(&truth, &dsa, 2), wrong);
    }
}
