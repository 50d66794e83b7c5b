//! Runs [`FrameProjector::project_frame`] on the frame of the `project` bench (same rig,
//! depth and label images), for profiles with stable instruction counts:
//!
//! ```text
//! THREADS=1 valgrind --tool=callgrind --toggle-collect='*run_frame*' \
//!     target/release/examples/profile_frame dsa 3
//! ```
//!
//! Arguments: mode (`naive` | `dsa`, default `dsa`), frames (default 1); `THREADS` sets
//! the rayon pool (default 2), `REUSE=1` reuses the output cloud between frames
//! ([`FrameProjector::project_frame_into`]), `DUMP=path` writes the last frame's labels, positions and
//! origins (`path`, `path.pos`, `path.org`) to compare two builds bit for bit.

use std::hint::black_box;
use std::path::Path;

use bodyseg_calib::{BackProjectOptions, CloudFrame, Pose, RgbdCamera, Rig, read_iai_kinect2};
use bodyseg_core::{Label, LabelImage};
use bodyseg_project::{CameraImages, FrameProjector, ProjectConfig};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Fixed seed of the hole pattern.
const SEED: u64 = 0x00B0_D15E_6BEC_0001;

/// The box's depth pixels (u range, v range) in every camera's depth image.
const BOX_U: std::ops::Range<u32> = 180..330;
const BOX_V: std::ops::Range<u32> = 140..320;

fn kinect() -> RgbdCamera {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/iai_kinect2/196605135147");
    read_iai_kinect2(&dir).unwrap_or_else(|e| panic!("bench data: {e}"))
}

/// Three cameras 2.2 m up on a circle of radius 3 m around the world origin, looking at
/// it 30° down.
fn rig() -> Rig {
    let base = kinect();
    let cameras = (0..3)
        .map(|i| {
            let yaw = f64::from(i) * 120f64.to_radians();
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
            cam.world_from_depth =
                Pose::from_rotation_translation(rotation, [3.0 * cy, 3.0 * sy, 2.2])
                    .expect("an orthonormal rotation");
            cam
        })
        .collect();
    Rig { cameras }
}

/// A depth image (mm) of a slanted plane with a box in front of it; ~15% of the pixels
/// are holes (0), as on a real Kinect v2 frame (edges, dark and shiny surfaces).
fn depth_image(width: u32, height: u32, seed: u64) -> Vec<u16> {
    let mut state = seed.max(1);
    let mut unit = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = Vec::with_capacity((width * height) as usize);
    for v in 0..height {
        for u in 0..width {
            let in_box = BOX_U.contains(&u) && BOX_V.contains(&v);
            let z_mm = if in_box {
                2000.0 + 0.8 * f64::from(u - BOX_U.start)
            } else {
                // Floor seen from above: farther towards the top of the image.
                4500.0 - 6.0 * f64::from(v)
            };
            let hole = unit() < 0.15;
            out.push(if hole { 0 } else { z_mm as u16 });
        }
    }
    out
}

/// The colour camera's label image of the truth: every depth point of the box splatted
/// (5×5 colour pixels, closing the gaps between depth samples) with its part (upper half
/// of the box class 1, lower half class 2), background elsewhere.
fn label_image(camera: &RgbdCamera, depth_raw: &[u16]) -> LabelImage {
    let opts = BackProjectOptions {
        frame: CloudFrame::Depth,
        ..Default::default()
    };
    let cloud = bodyseg_calib::back_project(depth_raw, camera, 0, &opts).expect("bench depth");
    let (w, h) = (camera.color.width as i64, camera.color.height as i64);
    let mut image = LabelImage::filled(camera.color.width, camera.color.height, Label::BACKGROUND);
    let depth_w = camera.depth.width;
    let split_v = (BOX_V.start + BOX_V.end) / 2;
    for (p, o) in cloud.points_m.iter().zip(&cloud.origins) {
        let (u, v) = (o.pixel % depth_w, o.pixel / depth_w);
        if !(BOX_U.contains(&u) && BOX_V.contains(&v)) {
            continue;
        }
        let part = Label::from_id(if v < split_v { 1 } else { 2 }).expect("a class id");
        let p_color = camera.color_from_depth.transform_point(p.map(f64::from));
        let Some(uv) = camera.color.project(p_color) else {
            continue;
        };
        let (uc, vc) = (uv[0].round() as i64, uv[1].round() as i64);
        for vn in (vc - 2).max(0)..=(vc + 2).min(h - 1) {
            for un in (uc - 2).max(0)..=(uc + 2).min(w - 1) {
                image.labels[(vn * w + un) as usize] = part;
            }
        }
    }
    image
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "dsa".into());
    let n: usize = std::env::args()
        .nth(2)
        .map_or(1, |s| s.parse().expect("count"));
    let rig = rig();
    let projector = FrameProjector::new(&rig).expect("a valid rig");
    let depths: Vec<Vec<u16>> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(i, cam)| depth_image(cam.depth.width, cam.depth.height, SEED + i as u64))
        .collect();
    let labels: Vec<LabelImage> = rig
        .cameras
        .iter()
        .zip(&depths)
        .map(|(cam, d)| label_image(cam, d))
        .collect();
    let images: Vec<CameraImages<'_>> = depths
        .iter()
        .zip(&labels)
        .map(|(d, l)| CameraImages {
            depth_raw: d,
            labels: l,
        })
        .collect();
    let opts = BackProjectOptions::default();
    let cfg = if mode == "naive" {
        ProjectConfig::naive()
    } else {
        ProjectConfig::default()
    };
    let threads = std::env::var("THREADS").map_or(2, |s| s.parse().expect("threads"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    // A checksum of the output, so that the work cannot be optimised away.
    let mut sum = 0usize;
    let t = std::time::Instant::now();
    let reuse = std::env::var("REUSE").is_ok();
    let mut cloud = bodyseg_core::LabeledCloud::default();
    for _ in 0..n {
        if reuse {
            pool.install(|| run_frame_into(&projector, &images, &opts, &cfg, &mut cloud));
        } else {
            cloud = pool.install(|| run_frame(&projector, &images, &opts, &cfg));
        }
        sum += cloud.labels.iter().map(|l| l.id() as usize).sum::<usize>() + cloud.len();
        if let Ok(d) = std::env::var("DUMP") {
            let bytes: Vec<u8> = cloud.labels.iter().map(|l| l.id()).collect();
            std::fs::write(&d, bytes).expect("dump");
            let pos: Vec<u8> = cloud
                .positions_m
                .iter()
                .flatten()
                .flat_map(|c| c.to_le_bytes())
                .collect();
            std::fs::write(format!("{d}.pos"), pos).expect("dump");
            let org: Vec<u8> = cloud
                .origins
                .iter()
                .flat_map(|o| o.pixel.to_le_bytes())
                .collect();
            std::fs::write(format!("{d}.org"), org).expect("dump");
        }
    }
    eprintln!(
        "{mode}: {:.2} ms/frame, checksum {sum}",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
}

#[inline(never)]
fn run_frame_into(
    p: &FrameProjector,
    images: &[CameraImages<'_>],
    opts: &BackProjectOptions,
    cfg: &ProjectConfig,
    out: &mut bodyseg_core::LabeledCloud,
) {
    p.project_frame_into(black_box(images), opts, cfg, out)
        .expect("ok")
}

#[inline(never)]
fn run_frame(
    p: &FrameProjector,
    images: &[CameraImages<'_>],
    opts: &BackProjectOptions,
    cfg: &ProjectConfig,
) -> bodyseg_core::LabeledCloud {
    p.project_frame(black_box(images), opts, cfg).expect("ok")
}
