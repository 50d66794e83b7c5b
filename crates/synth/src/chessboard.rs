//! Chessboard views for calibration (issue 9): a board held at random poses in front of
//! each camera, seen by its colour and IR (depth) sensors at the same instant, and one
//! board lying on the floor seen by every camera at once. The images are rendered with
//! 4×4 supersampling through the sensors' distortion, so corners have the sub-pixel
//! accuracy a calibration needs, plus sensor noise.
//!
//! Board frame (OpenCV's object points): inner corner `(i, j)` is at
//! `(i·square, j·square, 0)`, `i < inner_corners[0]`, `j < inner_corners[1]`, z = x × y. The
//! square whose far corner is inner corner (0, 0) is black. The floor board defines the
//! world: its frame is the world frame (its first inner corner at the origin, x and y
//! along world x and y, z up), and the rig's cameras look at the room centre as usual.

use crate::config::{RigConfig, SynthError};
use crate::hash::{gaussian, hash};
use crate::rig::true_rig;
use bodyseg_calib::{Intrinsics, Pose, Rig};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How the calibration views are made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChessboardConfig {
    /// Inner corners along the board's x and y (OpenCV's pattern size), e.g. 9×6.
    pub inner_corners: [u32; 2],
    /// Side of a square of the hand-held board, metres.
    pub square_m: f64,
    /// Side of a square of the floor board (larger: it is seen from 3 m), metres.
    pub floor_square_m: f64,
    /// Hand-held views per camera.
    pub views: u32,
    /// Distance of the hand-held board from the depth sensor, metres.
    pub distance_m: [f64; 2],
    /// Largest tilt of the hand-held board away from facing the camera, degrees.
    pub max_tilt_deg: f64,
    /// Gaussian image noise, 8-bit grey levels.
    pub noise_levels: f64,
}

impl Default for ChessboardConfig {
    fn default() -> Self {
        ChessboardConfig {
            inner_corners: [9, 6],
            square_m: 0.04,
            floor_square_m: 0.1,
            views: 15,
            distance_m: [0.7, 1.3],
            max_tilt_deg: 35.0,
            noise_levels: 2.0,
        }
    }
}

impl ChessboardConfig {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), SynthError> {
        let bad = |field: &str, reason: String| {
            Err(SynthError::Invalid {
                field: format!("chessboard.{field}"),
                reason,
            })
        };
        if self.inner_corners[0] < 2 || self.inner_corners[1] < 2 {
            return bad(
                "inner_corners",
                format!("must be at least [2, 2], got {:?}", self.inner_corners),
            );
        }
        for (field, v) in [
            ("square_m", self.square_m),
            ("floor_square_m", self.floor_square_m),
        ] {
            if !(v > 0.0 && v < 1.0) {
                return bad(field, format!("must be in (0, 1) m, got {v}"));
            }
        }
        if self.views == 0 || self.views > 1000 {
            return bad("views", format!("must be in 1..=1000, got {}", self.views));
        }
        let [lo, hi] = self.distance_m;
        if !(lo > 0.2 && lo <= hi && hi < 10.0) {
            return bad(
                "distance_m",
                format!(
                    "must be [min, max] within (0.2, 10) m, got {:?}",
                    self.distance_m
                ),
            );
        }
        if !(0.0..=70.0).contains(&self.max_tilt_deg) {
            return bad(
                "max_tilt_deg",
                format!("must be in [0, 70], got {}", self.max_tilt_deg),
            );
        }
        if !(0.0..=50.0).contains(&self.noise_levels) {
            return bad(
                "noise_levels",
                format!("must be in [0, 50], got {}", self.noise_levels),
            );
        }
        Ok(())
    }
}

/// One instant seen by one camera's two sensors.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorImages {
    /// Colour image, RGB8, colour sensor size.
    pub color: Vec<u8>,
    /// IR image, 8-bit grey, depth sensor size.
    pub ir: Vec<u8>,
}

/// A hand-held board view of one camera.
#[derive(Clone, Debug, PartialEq)]
pub struct ChessboardView {
    /// Camera index in rig order.
    pub camera: usize,
    /// The true board pose in the depth sensor frame.
    pub depth_from_board: Pose,
    /// What the sensors saw.
    pub images: SensorImages,
}

/// A whole calibration set.
#[derive(Clone, Debug, PartialEq)]
pub struct ChessboardSet {
    /// The true rig; its world frame is the floor board's frame.
    pub rig: Rig,
    /// `views` hand-held views per camera, camera by camera.
    pub views: Vec<ChessboardView>,
    /// Per camera, the simultaneous view of the floor board.
    pub floor: Vec<SensorImages>,
}

/// Renders the calibration set of the rig of `rig_config`, deterministic in `seed`.
pub fn chessboard_set(
    rig_config: &RigConfig,
    config: &ChessboardConfig,
    seed: u64,
) -> Result<ChessboardSet, SynthError> {
    config.validate()?;
    let rig = true_rig(rig_config)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xC4E5_5B0A_0000_0001);
    // Each sensor's undistorted rays, once: every view of the sensor reuses them.
    let tables: Vec<[RayTable; 2]> = rig
        .cameras
        .iter()
        .map(|camera| [RayTable::new(&camera.color), RayTable::new(&camera.depth)])
        .collect();
    let mut views = Vec::new();
    for (c, camera) in rig.cameras.iter().enumerate() {
        for v in 0..config.views {
            let depth_from_board = board_pose(
                &mut rng,
                config,
                &camera.depth,
                &camera.color,
                &camera.color_from_depth,
            )?;
            let images = board_images(
                camera,
                &tables[c],
                &depth_from_board,
                config.square_m,
                config,
                hash(seed, c as u64, u64::from(v), 0xB0A2D),
            );
            views.push(ChessboardView {
                camera: c,
                depth_from_board,
                images,
            });
        }
    }
    let floor = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(c, camera)| {
            // World = floor board frame.
            board_images(
                camera,
                &tables[c],
                &camera.world_from_depth.inverse(),
                config.floor_square_m,
                config,
                hash(seed, c as u64, 0xF100, 0xB0A2D),
            )
        })
        .collect();
    Ok(ChessboardSet { rig, views, floor })
}

/// A random pose of the hand-held board in the depth frame with every inner corner
/// inside both images (8 px margin).
fn board_pose(
    rng: &mut ChaCha8Rng,
    config: &ChessboardConfig,
    depth: &Intrinsics,
    color: &Intrinsics,
    color_from_depth: &Pose,
) -> Result<Pose, SynthError> {
    let s = config.square_m;
    let (nx, ny) = (config.inner_corners[0], config.inner_corners[1]);
    let (w, h) = (f64::from(nx - 1) * s, f64::from(ny - 1) * s);
    for _ in 0..10_000 {
        let d = rng.random_range(config.distance_m[0]..=config.distance_m[1]);
        // Board centre anywhere in the central 80% of the depth image.
        let x = rng.random_range(-0.45..0.45) * f64::from(depth.width) / depth.fx;
        let y = rng.random_range(-0.4..0.4) * f64::from(depth.height) / depth.fy;
        let centre = [x * d, y * d, d];
        let tilt = config.max_tilt_deg.to_radians();
        let (ax, ay, az) = (
            rng.random_range(-tilt..=tilt),
            rng.random_range(-tilt..=tilt),
            rng.random_range(-0.35..0.35f64),
        );
        // Board facing the camera (board z along camera z, away from it: OpenCV's
        // convention for a board seen from its printed side), then tilted.
        let r = mat_mul(mat_mul(rot_x(ax), rot_y(ay)), rot_z(az));
        // Board origin so that the board centre lands on `centre`.
        let half = [w / 2.0, h / 2.0, 0.0];
        let rh = mat_vec(r, half);
        let t = [centre[0] - rh[0], centre[1] - rh[1], centre[2] - rh[2]];
        let Ok(pose) = Pose::from_rotation_translation(r, t) else {
            continue;
        };
        let visible = (0..ny).all(|j| {
            (0..nx).all(|i| {
                let p = pose.transform_point([f64::from(i) * s, f64::from(j) * s, 0.0]);
                inside(depth, p) && inside(color, color_from_depth.transform_point(p))
            })
        });
        if visible {
            return Ok(pose);
        }
    }
    Err(SynthError::Invalid {
        field: "chessboard.distance_m".into(),
        reason: "no board pose shows every corner to both sensors; bring the board closer or make it smaller".into(),
    })
}

fn inside(intrinsics: &Intrinsics, p: [f64; 3]) -> bool {
    const MARGIN_PX: f64 = 8.0;
    intrinsics.project(p).is_some_and(|[u, v]| {
        u >= MARGIN_PX
            && v >= MARGIN_PX
            && u <= f64::from(intrinsics.width) - 1.0 - MARGIN_PX
            && v <= f64::from(intrinsics.height) - 1.0 - MARGIN_PX
    })
}

type M3 = [[f64; 3]; 3];

fn rot_x(a: f64) -> M3 {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn rot_y(a: f64) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

fn rot_z(a: f64) -> M3 {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn mat_mul(a: M3, b: M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn mat_vec(a: M3, v: [f64; 3]) -> [f64; 3] {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

/// Both sensors' images of the board at `depth_from_board` (squares of `square_m`).
fn board_images(
    camera: &bodyseg_calib::RgbdCamera,
    tables: &[RayTable; 2],
    depth_from_board: &Pose,
    square_m: f64,
    config: &ChessboardConfig,
    noise_seed: u64,
) -> SensorImages {
    let color_from_board = camera.color_from_depth.compose(depth_from_board);
    let board = (square_m, config.inner_corners, config.noise_levels);
    SensorImages {
        color: render(
            &tables[0],
            &color_from_board,
            board,
            noise_seed,
            Channel::Rgb,
        ),
        ir: render(
            &tables[1],
            depth_from_board,
            board,
            noise_seed ^ 1,
            Channel::Ir,
        ),
    }
}

/// Undistorted normalised rays of a sensor's pixel centres, row-major; NaN where the
/// undistortion fails.
struct RayTable {
    width: usize,
    height: usize,
    rays: Vec<[f64; 2]>,
}

impl RayTable {
    fn new(intrinsics: &Intrinsics) -> Self {
        let (w, h) = (intrinsics.width as usize, intrinsics.height as usize);
        let rays = (0..h)
            .into_par_iter()
            .flat_map_iter(|v| {
                (0..w).map(move |u| {
                    intrinsics
                        .unproject(u as f64, v as f64)
                        .map_or([f64::NAN; 2], |r| [r[0], r[1]])
                })
            })
            .collect();
        RayTable {
            width: w,
            height: h,
            rays,
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Channel {
    Rgb,
    Ir,
}

/// Renders the board (square side, inner corners, noise levels) at `sensor_from_board`
/// into an image of the sensor of `table`: RGB8 or grey. Sub-pixel rays are interpolated
/// bilinearly between the table's pixel-centre rays (the undistortion is smooth: its
/// error over one pixel is far below the 0.01 px a corner detector resolves).
fn render(
    table: &RayTable,
    sensor_from_board: &Pose,
    (square_m, inner, noise_levels): (f64, [u32; 2], f64),
    noise_seed: u64,
    channel: Channel,
) -> Vec<u8> {
    const SUB: usize = 4;
    let (w, h, rays) = (table.width, table.height, &table.rays);
    // Plane of the board in the sensor frame: points p with n·(p − o) = 0.
    let board_from_sensor = sensor_from_board.inverse();
    let r = board_from_sensor.rotation();
    let t = board_from_sensor.translation_m();
    let (nx, ny) = (f64::from(inner[0]), f64::from(inner[1]));
    // Printed area: the squares around the inner corners plus a white border.
    let (x0, x1) = (-1.5 * square_m, (nx + 0.5) * square_m);
    let (y0, y1) = (-1.5 * square_m, (ny + 0.5) * square_m);
    let sample = |x: f64, y: f64| -> Option<f64> {
        // Ray (x, y, 1) from the sensor origin into the board frame: o_b + s·d_b.
        let d = [
            r[0][0] * x + r[0][1] * y + r[0][2],
            r[1][0] * x + r[1][1] * y + r[1][2],
            r[2][0] * x + r[2][1] * y + r[2][2],
        ];
        if d[2].abs() < 1e-12 {
            return None;
        }
        let s = -t[2] / d[2];
        if s <= 0.0 {
            return None;
        }
        let (bx, by) = (t[0] + s * d[0], t[1] + s * d[1]);
        if bx < x0 || bx > x1 || by < y0 || by > y1 {
            return None;
        }
        let (a, b) = (
            (bx / square_m).floor() as i64,
            (by / square_m).floor() as i64,
        );
        let in_squares = a >= -1 && a < inner[0] as i64 && b >= -1 && b < inner[1] as i64;
        // Square (a, b) covers [a·s, (a+1)·s) × [b·s, (b+1)·s); the one ending at inner
        // corner (0, 0) is (−1, −1): black when a + b is even.
        Some(if in_squares && (a + b).rem_euclid(2) == 0 {
            0.08
        } else {
            0.85
        })
    };
    let bytes_per_px = if channel == Channel::Rgb { 3 } else { 1 };
    let mut out = vec![0u8; w * h * bytes_per_px];
    out.par_chunks_mut(w * bytes_per_px)
        .enumerate()
        .for_each(|(v, row)| {
            for u in 0..w {
                let mut acc = 0.0;
                let mut background = 0usize;
                for sy in 0..SUB {
                    for sx in 0..SUB {
                        let fu = u as f64 + (sx as f64 + 0.5) / SUB as f64 - 0.5;
                        let fv = v as f64 + (sy as f64 + 0.5) / SUB as f64 - 0.5;
                        match interpolate(rays, w, h, fu, fv).and_then(|[x, y]| sample(x, y)) {
                            Some(value) => acc += value,
                            None => background += 1,
                        }
                    }
                }
                // Background: a dim grey with a smooth gradient (a wall behind the board;
                // nothing a corner detector could take for a board corner).
                let bg = 0.25 + 0.1 * (u as f64 / w as f64) + 0.05 * (v as f64 / h as f64);
                let value = (acc + background as f64 * bg) / (SUB * SUB) as f64;
                let i = v * w + u;
                let g = f64::from(gaussian(hash(noise_seed, i as u64, 0, 0)));
                let level = (value * 255.0 + g * noise_levels).round().clamp(0.0, 255.0) as u8;
                if channel == Channel::Rgb {
                    row[u * 3..u * 3 + 3].copy_from_slice(&[level, level, level]);
                } else {
                    row[u] = level;
                }
            }
        });
    out
}

/// Bilinear interpolation of the ray table at fractional pixel (fu, fv), clamped to the
/// image; `None` where a neighbouring ray is missing.
fn interpolate(rays: &[[f64; 2]], w: usize, h: usize, fu: f64, fv: f64) -> Option<[f64; 2]> {
    let fu = fu.clamp(0.0, (w - 1) as f64);
    let fv = fv.clamp(0.0, (h - 1) as f64);
    let (u0, v0) = (fu.floor() as usize, fv.floor() as usize);
    let (u1, v1) = ((u0 + 1).min(w - 1), (v0 + 1).min(h - 1));
    let (a, b) = (fu - u0 as f64, fv - v0 as f64);
    let p = |u: usize, v: usize| rays[v * w + u];
    let (p00, p10, p01, p11) = (p(u0, v0), p(u1, v0), p(u0, v1), p(u1, v1));
    let mut out = [0.0; 2];
    for k in 0..2 {
        out[k] = (1.0 - a) * (1.0 - b) * p00[k]
            + a * (1.0 - b) * p10[k]
            + (1.0 - a) * b * p01[k]
            + a * b * p11[k];
    }
    out.iter().all(|x| x.is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every inner corner projects to a pixel where the image has a saddle: the 4 pixels
    /// diagonally around it alternate dark / bright.
    #[test]
    fn corners_are_where_the_true_pose_projects_them() {
        let config = ChessboardConfig {
            views: 2,
            noise_levels: 0.0,
            ..ChessboardConfig::default()
        };
        let rig_config = RigConfig {
            cameras: 1,
            ..RigConfig::default()
        };
        let set = chessboard_set(&rig_config, &config, 3).expect("set");
        assert_eq!(set.views.len(), 2);
        assert_eq!(set.floor.len(), 1);
        let camera = &set.rig.cameras[0];
        let mut views: Vec<(&Intrinsics, Pose, &Vec<u8>, usize, f64)> = Vec::new();
        for v in &set.views {
            views.push((
                &camera.depth,
                v.depth_from_board,
                &v.images.ir,
                1,
                config.square_m,
            ));
            let color_from_board = camera.color_from_depth.compose(&v.depth_from_board);
            views.push((
                &camera.color,
                color_from_board,
                &v.images.color,
                3,
                config.square_m,
            ));
        }
        let floor_depth = camera.world_from_depth.inverse();
        views.push((
            &camera.depth,
            floor_depth,
            &set.floor[0].ir,
            1,
            config.floor_square_m,
        ));
        for (intrinsics, pose, image, bpp, s) in views {
            let w = intrinsics.width as usize;
            let at = |u: usize, v: usize| i32::from(image[(v * w + u) * bpp]);
            for j in 0..config.inner_corners[1] {
                for i in 0..config.inner_corners[0] {
                    let p = pose.transform_point([f64::from(i) * s, f64::from(j) * s, 0.0]);
                    let [u, v] = intrinsics.project(p).expect("in front");
                    let (u, v) = (u.round() as usize, v.round() as usize);
                    let d = 2;
                    let (a, b) = (
                        at(u - d, v - d) + at(u + d, v + d),
                        at(u + d, v - d) + at(u - d, v + d),
                    );
                    assert!(
                        (a - b).abs() > 150,
                        "corner ({i},{j}) at ({u},{v}): {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn bad_board_configs_name_the_field() {
        let e = ChessboardConfig {
            inner_corners: [1, 6],
            ..ChessboardConfig::default()
        }
        .validate()
        .expect_err("1 corner");
        assert!(e.to_string().contains("chessboard.inner_corners"), "{e}");
        let e = ChessboardConfig {
            square_m: -0.1,
            ..ChessboardConfig::default()
        }
        .validate()
        .expect_err("negative");
        assert!(e.to_string().contains("chessboard.square_m"), "{e}");
    }
}
