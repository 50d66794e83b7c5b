//! Fixtures shared by the workspace's tests and benches (hidden from the documentation):
//! the Kinect v2 test camera of `shared/data/iai_kinect2/196605135147` and a ring rig
//! built from it. Not for production code.

use crate::{CalibError, Distortion, Pose, RgbdCamera, Rig, read_iai_kinect2};
use std::path::PathBuf;

/// The iai_kinect2 folder of the test camera: `shared/` beside the repository
/// (`shared/data/iai_kinect2/196605135147`).
pub fn kinect_v2_test_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/iai_kinect2/196605135147")
}

/// The Kinect v2 test camera (serial 196605135147, distortion included), read from
/// [`kinect_v2_test_dir`]; the error names the folder when `shared/` is missing.
pub fn kinect_v2_test_camera() -> Result<RgbdCamera, CalibError> {
    read_iai_kinect2(&kinect_v2_test_dir())
}

/// `n` copies of `base` named `cam0`.. placed 2.2 m up on a circle of radius 3 m around
/// the world origin, evenly spaced in yaw, each looking at the origin 30° down.
pub fn ring_rig(base: &RgbdCamera, n: usize) -> Rig {
    let cameras = (0..n)
        .map(|i| {
            let yaw = i as f64 * (360.0 / n as f64).to_radians();
            let (sy, cy) = yaw.sin_cos();
            let (st, ct) = 30f64.to_radians().sin_cos();
            // Optical axes in world coordinates: z forward (towards the centre, tilted
            // down), x right (horizontal), y down = z × x.
            let fwd = [-cy * ct, -sy * ct, -st];
            let right = [sy, -cy, 0.0];
            let down = [
                fwd[1] * right[2] - fwd[2] * right[1],
                fwd[2] * right[0] - fwd[0] * right[2],
                fwd[0] * right[1] - fwd[1] * right[0],
            ];
            let rotation = std::array::from_fn(|r| [right[r], down[r], fwd[r]]);
            let mut cam = base.clone();
            cam.name = format!("cam{i}");
            // An orthonormal rotation by construction; identity only if that ever fails.
            cam.world_from_depth =
                Pose::from_rotation_translation(rotation, [3.0 * cy, 3.0 * sy, 2.2])
                    .unwrap_or_else(|_| Pose::identity());
            cam
        })
        .collect();
    Rig { cameras }
}

/// Depth pixels (u range, v range) of the box in [`plane_and_box_depth_mm`].
pub const TEST_BOX_U: std::ops::Range<u32> = 180..330;
/// See [`TEST_BOX_U`].
pub const TEST_BOX_V: std::ops::Range<u32> = 140..320;

/// A depth image (mm, row-major) of a slanted plane with a box in front of it
/// ([`TEST_BOX_U`] × [`TEST_BOX_V`]); ~15% of the pixels are holes (0), as on a real
/// Kinect v2 frame (edges, dark and shiny surfaces); the holes are drawn from `seed`.
pub fn plane_and_box_depth_mm(width: u32, height: u32, seed: u64) -> Vec<u16> {
    let mut rng = bodyseg_core::rng::XorShift64Star::new(seed);
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for v in 0..height {
        for u in 0..width {
            let in_box = TEST_BOX_U.contains(&u) && TEST_BOX_V.contains(&v);
            let z_mm = if in_box {
                2000.0 + 0.8 * f64::from(u - TEST_BOX_U.start)
            } else {
                // Floor seen from above: farther towards the top of the image.
                4500.0 - 6.0 * f64::from(v)
            };
            let hole = rng.unit_f64() < 0.15;
            out.push(if hole { 0 } else { z_mm as u16 });
        }
    }
    out
}

/// Fixed seed of the benches' hole pattern (camera `i` uses `BENCH_SEED + i`).
pub const BENCH_SEED: u64 = 0x00B0_D15E_6BEC_0001;

/// The benches' rig: three copies of the Kinect v2 test camera on [`ring_rig`]'s circle.
/// Panics naming the error when `shared/` is missing (benches only).
pub fn bench_ring_rig() -> Rig {
    let kinect = kinect_v2_test_camera().unwrap_or_else(|e| panic!("bench data: {e}"));
    ring_rig(&kinect, 3)
}

/// The benches' name of a frame of `rig`: cameras × depth width × height (`3x512x424`),
/// from the first camera's depth sensor.
pub fn bench_frame_size(rig: &Rig) -> String {
    let (w, h) = rig
        .cameras
        .first()
        .map_or((0, 0), |c| (c.depth.width, c.depth.height));
    format!("{}x{w}x{h}", rig.cameras.len())
}

/// A rayon pool of 2 threads: the per-frame budget's machine (issue 4) has 2 cores.
pub fn two_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("a 2-thread pool")
}

/// One [`plane_and_box_depth_mm`] image per camera of `rig`, camera `i` with holes drawn
/// from `BENCH_SEED + i`.
pub fn bench_depth_images(rig: &Rig) -> Vec<Vec<u16>> {
    rig.cameras
        .iter()
        .enumerate()
        .map(|(i, cam)| {
            plane_and_box_depth_mm(cam.depth.width, cam.depth.height, BENCH_SEED + i as u64)
        })
        .collect()
}

/// The colour sensor's rational distortion of Azure Kinect 001514394512
/// (`tests/fixtures/calib/azure_kinect/pyk4a_calibration.json`, `ModelParameters` 4..13
/// in OpenCV's order k1 k2 p1 p2 k3 k4 k5 k6).
#[allow(clippy::excessive_precision)]
pub const AZURE_COLOR_DISTORTION: Distortion = Distortion::Rational([
    0.33012130856513977,
    -2.489396572113037,
    -0.00016178244550246745,
    -0.00012944525224156678,
    1.453670859336853,
    0.20891207456588745,
    -2.302915096282959,
    1.3751275539398193,
]);

/// The depth sensor's rational distortion of the same Azure Kinect (pyk4a's
/// `tests/assets/calibration.json`, device 001514394512) in OpenCV's order.
#[allow(clippy::excessive_precision)]
pub const AZURE_DEPTH_DISTORTION: Distortion = Distortion::Rational([
    0.5479397773742676,
    -0.020971370860934258,
    2.0557534298859537e-05,
    -7.210415787994862e-05,
    -0.002652231603860855,
    0.8896790742874146,
    0.08613020926713943,
    -0.013910384848713875,
]);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_rig_cameras_look_at_the_origin_from_2_2_m() {
        let optics = crate::Intrinsics::pinhole(4, 4, 2.0, 2.0, 2.0, 2.0);
        let base = RgbdCamera::new("k", optics, optics);
        let rig = ring_rig(&base, 3);
        assert_eq!(rig.cameras.len(), 3);
        for (i, cam) in rig.cameras.iter().enumerate() {
            assert_eq!(cam.name, format!("cam{i}"));
            let c = cam.world_from_depth.transform_point([0.0, 0.0, 0.0]);
            assert!((c[2] - 2.2).abs() < 1e-12 && (c[0].hypot(c[1]) - 3.0).abs() < 1e-12);
            // The optical axis (depth frame +z) passes near the origin's direction.
            let ahead = cam.world_from_depth.transform_point([0.0, 0.0, 1.0]);
            let axis = [ahead[0] - c[0], ahead[1] - c[1], ahead[2] - c[2]];
            let to_origin = [-c[0], -c[1], -c[2]];
            let cos = (axis[0] * to_origin[0] + axis[1] * to_origin[1] + axis[2] * to_origin[2])
                / (to_origin[0].hypot(to_origin[1]).hypot(to_origin[2]));
            assert!(cos > 0.99, "camera {i}: cos {cos}");
        }
    }

    #[test]
    fn plane_and_box_has_the_box_nearer_and_about_15_percent_holes() {
        let d = plane_and_box_depth_mm(512, 424, 7);
        assert_eq!(d.len(), 512 * 424);
        assert_eq!(d, plane_and_box_depth_mm(512, 424, 7));
        let holes = d.iter().filter(|&&z| z == 0).count() as f64 / d.len() as f64;
        assert!((0.13..0.17).contains(&holes), "{holes}");
        let at = |u: usize, v: usize| d[v * 512 + u];
        let (boxed, floor) = (0..20)
            .map(|k| (at(200 + k, 200), at(20 + k, 200)))
            .find(|&(b, f)| b > 0 && f > 0)
            .unwrap_or((0, 0));
        assert!(boxed > 0 && boxed < floor, "{boxed} {floor}");
    }
}
