//! The generator: a seeded sequence of synthetic RGB-D frames with exact ground truth.
//!
//! Per frame and camera it ray-casts the depth image (with Kinect-v2-like faults) at the
//! frame's time and the colour image at that time plus the colour exposure offset, and
//! derives the truth (2D labels, per-depth-pixel labels and person ids, person boxes) and
//! the simulated parser's prediction. Everything is a pure function of (config, seed,
//! frame index): frames can be rendered in any order and in parallel.

use crate::config::{SceneConfig, SynthError};
use crate::geometry::{Owner, Primitive, V3, dot};
use crate::hash::{gaussian, hash, unit};
use crate::parser_mistakes::{TruthView, predict_labels};
use crate::people::{Person, handover_object, make_people};
use crate::render::{World, camera_frame};
use crate::rig::{true_rig, written_rig};
use crate::scene::StaticScene;
use crate::shade::{encode, sensor_noise, shade};
use bodyseg_calib::{BackProjectOptions, CloudFrame, DepthBackProjector, Intrinsics, Pose, Rig};
use bodyseg_core::{Label, LabeledCloud, PersonBox, PersonBoxes};
use rayon::prelude::*;

/// Label written where a depth pixel's ray hits nothing (no surface, no truth).
pub const NO_SURFACE: u8 = 255;

/// Margin added around a person's exact extent for the true box, metres: depth noise at
/// 4 m is σ ≈ 16 mm with the default faults (σ₁·z², σ₁ = 1 mm), so 0.05 m keeps ≥ 99% of
/// the person's noisy points inside.
pub const BOX_MARGIN_M: f32 = 0.05;

/// One camera's images of one frame, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraFrame {
    /// Colour image, RGB8, colour sensor size.
    pub color: Vec<u8>,
    /// Exact 2D labels of the colour image (class ids).
    pub labels: Vec<u8>,
    /// The simulated parser's prediction (class ids).
    pub parsing: Vec<u8>,
    /// Person id seen at each colour pixel (0 = none).
    pub color_person: Vec<u8>,
    /// Body segment seen at each colour pixel ([`crate::geometry::Segment::id`], 0 = none).
    pub color_segment: Vec<u8>,
    /// Depth, millimetres, 0 = no measurement (depth sensor size).
    pub depth_mm: Vec<u16>,
    /// The class of the surface each depth pixel's ray hit ([`NO_SURFACE`] when none).
    pub depth_labels: Vec<u8>,
    /// The person each depth pixel's ray hit (0 = none).
    pub depth_person: Vec<u8>,
    /// Depth pixels turned into flying pixels (their depth lies between two surfaces).
    pub flying: Vec<bool>,
}

/// One synthetic frame: every camera's images and the true person boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthFrame {
    /// Frame index in the sequence.
    pub index: usize,
    /// Time of the depth exposure, seconds from the first frame.
    pub time_s: f64,
    /// Per camera, rig order.
    pub cameras: Vec<CameraFrame>,
    /// The true person boxes (id = the person id of `depth_person`).
    pub boxes: PersonBoxes,
}

impl SynthFrame {
    /// The frame's file stem (`000012`).
    pub fn stem(&self) -> String {
        frame_stem(self.index)
    }
}

/// The file stem of frame `index`.
pub fn frame_stem(index: usize) -> String {
    format!("{index:06}")
}

/// One pixel's ray, precomputed per camera.
#[derive(Clone, Copy, Debug)]
struct PixelRay {
    /// Unit direction, world frame.
    dir: V3,
    /// Undistorted normalised image coordinate (for culling).
    xy: [f32; 2],
    /// Depth (z in the sensor frame) per metre along the ray; 0 = no ray (undistortion
    /// failed).
    z_per_t: f32,
}

/// Pixels per span of a row: the renderers find the primitives a span's rays can hit
/// once per span, then test only those per pixel.
const SPAN_PX: usize = 16;

#[derive(Clone, Debug)]
struct SensorRays {
    intrinsics: Intrinsics,
    origin: V3,
    rows: [V3; 3],
    rays: Vec<PixelRay>,
    /// Per row and span of [`SPAN_PX`] pixels, the bounding rectangle of its rays'
    /// normalised image coordinates (empty when no ray is valid).
    spans: Vec<[f32; 4]>,
}

impl SensorRays {
    fn new(intrinsics: &Intrinsics, world_from_sensor: &Pose) -> Self {
        let (origin, rows) = camera_frame(
            world_from_sensor.rotation(),
            world_from_sensor.translation_m(),
        );
        let r = world_from_sensor.rotation();
        let rays: Vec<PixelRay> = (0..intrinsics.height)
            .into_par_iter()
            .flat_map_iter(|v| {
                (0..intrinsics.width).map(move |u| {
                    match intrinsics.unproject(f64::from(u), f64::from(v)) {
                        Some([x, y, _]) => {
                            let n = (x * x + y * y + 1.0).sqrt();
                            let d = [x / n, y / n, 1.0 / n];
                            let w = [
                                r[0][0] * d[0] + r[0][1] * d[1] + r[0][2] * d[2],
                                r[1][0] * d[0] + r[1][1] * d[1] + r[1][2] * d[2],
                                r[2][0] * d[0] + r[2][1] * d[1] + r[2][2] * d[2],
                            ];
                            PixelRay {
                                dir: [w[0] as f32, w[1] as f32, w[2] as f32],
                                xy: [x as f32, y as f32],
                                z_per_t: (1.0 / n) as f32,
                            }
                        }
                        None => PixelRay {
                            dir: [0.0, 0.0, 1.0],
                            xy: [0.0, 0.0],
                            z_per_t: 0.0,
                        },
                    }
                })
            })
            .collect();
        let w = intrinsics.width as usize;
        let spans_per_row = w.div_ceil(SPAN_PX);
        let mut spans = Vec::with_capacity(spans_per_row * intrinsics.height as usize);
        for row in rays.chunks(w.max(1)) {
            for span in row.chunks(SPAN_PX) {
                let mut b = [
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                ];
                for r in span.iter().filter(|r| r.z_per_t > 0.0) {
                    b = [
                        b[0].min(r.xy[0]),
                        b[1].max(r.xy[0]),
                        b[2].min(r.xy[1]),
                        b[3].max(r.xy[1]),
                    ];
                }
                spans.push(b);
            }
        }
        SensorRays {
            intrinsics: *intrinsics,
            origin,
            rows,
            rays,
            spans,
        }
    }

    /// The bound of the span holding pixel (u, v).
    fn span_bound(&self, v: usize, u: usize) -> [f32; 4] {
        let per_row = (self.intrinsics.width as usize).div_ceil(SPAN_PX);
        self.spans[v * per_row + u / SPAN_PX]
    }
}

/// The seeded generator of one sequence.
#[derive(Clone, Debug)]
pub struct Synth {
    config: SceneConfig,
    seed: u64,
    true_rig: Rig,
    written_rig: Rig,
    people: Vec<Person>,
    scene: StaticScene,
    depth_rays: Vec<SensorRays>,
    color_rays: Vec<SensorRays>,
}

impl Synth {
    /// Validates `config` and prepares the sequence of `seed`: rig, people, scene and
    /// every pixel's ray.
    pub fn new(config: SceneConfig, seed: u64) -> Result<Self, SynthError> {
        config.validate()?;
        let true_rig = true_rig(&config.rig)?;
        let written_rig = written_rig(&true_rig, &config.dsa, seed);
        let scene = StaticScene::new(&config.scene, seed);
        let people = make_people(&config.people, seed, scene.obstacles());
        let depth_rays = true_rig
            .cameras
            .iter()
            .map(|c| SensorRays::new(&c.depth, &c.world_from_depth))
            .collect();
        let color_rays = true_rig
            .cameras
            .iter()
            .map(|c| {
                SensorRays::new(
                    &c.color,
                    &c.world_from_depth.compose(&c.color_from_depth.inverse()),
                )
            })
            .collect();
        Ok(Synth {
            config,
            seed,
            true_rig,
            written_rig,
            people,
            scene,
            depth_rays,
            color_rays,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The rig the images were rendered with.
    pub fn true_rig(&self) -> &Rig {
        &self.true_rig
    }

    /// The rig written for the pipeline (the true one plus the configured calibration
    /// error).
    pub fn written_rig(&self) -> &Rig {
        &self.written_rig
    }

    /// The people of the sequence.
    pub fn people(&self) -> &[Person] {
        &self.people
    }

    /// Time of frame `index`'s depth exposure, seconds.
    pub fn time_s(&self, index: usize) -> f64 {
        index as f64 / self.config.fps
    }

    /// Each person's primitives at `t_s` (person `i` of [`Synth::people`] at index `i`).
    pub fn person_primitives_at(&self, t_s: f64) -> Vec<Vec<Primitive>> {
        self.people
            .iter()
            .map(|p| {
                let mut prims = Vec::new();
                p.primitives_at(t_s, &mut prims);
                prims
            })
            .collect()
    }

    /// Everything the cameras can see at `t_s`.
    pub fn world_at(&self, t_s: f64) -> World {
        let mut world = World::new(self.scene.room());
        for group in self.scene.groups_at(t_s) {
            world.add_group(&group);
        }
        for prims in self.person_primitives_at(t_s) {
            world.add_group(&prims);
        }
        if let Some(object) = handover_object(&self.people, &self.config.people, t_s) {
            world.add_group(&[object]);
        }
        world
    }

    /// Renders frame `index` of the sequence.
    pub fn frame(&self, index: usize) -> SynthFrame {
        let t = self.time_s(index);
        let depth_world = self.world_at(t);
        let color_t = t + self.config.dsa.color_time_offset_s;
        let color_world = if self.config.dsa.color_time_offset_s == 0.0 {
            None
        } else {
            Some(self.world_at(color_t))
        };
        let cameras = (0..self.true_rig.cameras.len())
            .map(|c| {
                let (depth_mm, depth_labels, depth_person, flying) =
                    self.render_depth(&depth_world, c, index);
                let (color, labels, color_person, color_segment) =
                    self.render_color(color_world.as_ref().unwrap_or(&depth_world), c, index);
                let intrinsics = &self.color_rays[c].intrinsics;
                let truth = TruthView {
                    width: intrinsics.width,
                    height: intrinsics.height,
                    labels: &labels,
                    person: &color_person,
                    segment: &color_segment,
                };
                let parsing = predict_labels(
                    &truth,
                    &self.config.parsing,
                    hash(self.seed, index as u64, c as u64, 0xFA45E),
                );
                CameraFrame {
                    color,
                    labels,
                    parsing,
                    color_person,
                    color_segment,
                    depth_mm,
                    depth_labels,
                    depth_person,
                    flying,
                }
            })
            .collect();
        SynthFrame {
            index,
            time_s: t,
            cameras,
            boxes: PersonBoxes {
                frame: frame_stem(index),
                boxes: self.true_boxes(t),
                world_from_cloud: None,
            },
        }
    }

    /// The exact labelled cloud of `frame`: every valid depth pixel of every camera
    /// back-projected into the world frame with the true rig and labelled with the class
    /// of the surface its ray hit (cameras in rig order, pixels row-major, origins kept),
    /// the cloud a perfect parser and projection would give.
    pub fn truth_cloud(&self, frame: &SynthFrame) -> Result<LabeledCloud, SynthError> {
        let opts = BackProjectOptions {
            frame: CloudFrame::World,
            ..BackProjectOptions::default()
        };
        let calib = |e: bodyseg_calib::CalibError| SynthError::Invalid {
            field: "rig".into(),
            reason: e.to_string(),
        };
        let mut cloud = LabeledCloud::default();
        for (c, (camera, images)) in self.true_rig.cameras.iter().zip(&frame.cameras).enumerate() {
            let points = DepthBackProjector::new(camera, c as u8)
                .map_err(calib)?
                .back_project(&images.depth_mm, &opts)
                .map_err(calib)?;
            cloud.labels.extend(points.origins.iter().map(|o| {
                Label::from_id(images.depth_labels[o.pixel as usize]).unwrap_or(Label::UNKNOWN)
            }));
            cloud.positions_m.extend(points.points_m);
            cloud.origins.extend(points.origins);
        }
        Ok(cloud)
    }

    /// The true box of every person at `t_s`: the exact extent of its primitives along
    /// its facing direction, its side and z, from the floor up, plus [`BOX_MARGIN_M`].
    pub fn true_boxes(&self, t_s: f64) -> Vec<PersonBox> {
        self.people
            .iter()
            .zip(self.person_primitives_at(t_s))
            .map(|(person, prims)| {
                let yaw = person.yaw_rad_at(t_s);
                let (s, c) = yaw.sin_cos();
                let axes = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
                let mut lo = [f32::INFINITY; 3];
                let mut hi = [f32::NEG_INFINITY; 3];
                for p in &prims {
                    for (i, u) in axes.iter().enumerate() {
                        let (a, b) = p.shape.extent_along(*u);
                        lo[i] = lo[i].min(a);
                        hi[i] = hi[i].max(b);
                    }
                }
                lo[2] = 0.0_f32.min(lo[2]);
                let mut center_local = [0.0; 3];
                let mut half = [0.0; 3];
                for i in 0..3 {
                    center_local[i] = (lo[i] + hi[i]) / 2.0;
                    half[i] = (hi[i] - lo[i]) / 2.0 + BOX_MARGIN_M;
                }
                // z from the floor: the margin goes on top only.
                half[2] -= BOX_MARGIN_M / 2.0;
                center_local[2] += BOX_MARGIN_M / 2.0;
                let center = [
                    c * center_local[0] - s * center_local[1],
                    s * center_local[0] + c * center_local[1],
                    center_local[2],
                ];
                PersonBox {
                    id: u32::from(person.id),
                    center_m: center,
                    half_extents_m: half,
                    yaw_rad: yaw,
                }
            })
            .collect()
    }

    fn render_depth(
        &self,
        world: &World,
        camera: usize,
        index: usize,
    ) -> (Vec<u16>, Vec<u8>, Vec<u8>, Vec<bool>) {
        let sensor = &self.depth_rays[camera];
        let w = sensor.intrinsics.width as usize;
        let rects = world.cull_rects(sensor.origin, sensor.rows);
        // Exact depth (0 = nothing measurable), truth, and the cosine to the normal.
        let mut z_true = vec![0.0f32; sensor.rays.len()];
        let mut labels = vec![NO_SURFACE; sensor.rays.len()];
        let mut person = vec![0u8; sensor.rays.len()];
        let mut grazing = vec![false; sensor.rays.len()];
        let cos_limit = (self.config.depth.grazing_angle_deg as f32)
            .to_radians()
            .cos();
        z_true
            .par_chunks_mut(w)
            .zip(labels.par_chunks_mut(w))
            .zip(person.par_chunks_mut(w))
            .zip(grazing.par_chunks_mut(w))
            .enumerate()
            .for_each(|(v, (((z_row, l_row), p_row), g_row))| {
                let mut candidates = Vec::new();
                for u in 0..w {
                    if u % SPAN_PX == 0 {
                        world.candidates(&rects, sensor.span_bound(v, u), &mut candidates);
                    }
                    let ray = sensor.rays[v * w + u];
                    if ray.z_per_t == 0.0 {
                        continue;
                    }
                    if let Some(hit) =
                        world.cast_among(sensor.origin, ray.dir, ray.xy, &rects, &candidates)
                    {
                        z_row[u] = hit.t * ray.z_per_t;
                        l_row[u] = hit.owner.class_id();
                        p_row[u] = hit.owner.person_id();
                        g_row[u] = -dot(hit.normal, ray.dir) < cos_limit;
                    }
                }
            });
        let depth = &self.config.depth;
        let seed = hash(self.seed, index as u64, camera as u64, 0xDE97);
        let h = sensor.intrinsics.height as usize;
        let (z_min, z_max) = (depth.range_m[0] as f32, depth.range_m[1] as f32);
        let sigma_1m = depth.noise_mm_at_1m as f32 / 1000.0;
        let ratio = depth.edge_jump_ratio as f32;
        let fly_p = depth.flying_pixel_prob as f32;
        let dropout = depth.dropout as f32;
        let mut flying = vec![false; z_true.len()];
        let mut depth_mm = vec![0u16; z_true.len()];
        depth_mm
            .par_chunks_mut(w)
            .zip(flying.par_chunks_mut(w))
            .enumerate()
            .for_each(|(v, (d_row, f_row))| {
                for u in 0..w {
                    let i = v * w + u;
                    let z = z_true[i];
                    if z == 0.0 || grazing[i] {
                        continue;
                    }
                    let pixel = i as u64;
                    // Flying pixel: on a depth discontinuity, the sensor mixes the two
                    // surfaces' returns; its depth lies somewhere between them.
                    let mut z_meas = z;
                    if fly_p > 0.0 {
                        let mut far = z;
                        for (du, dv) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                            let (nu, nv) = (u as i64 + du, v as i64 + dv);
                            if nu < 0 || nv < 0 || nu >= w as i64 || nv >= h as i64 {
                                continue;
                            }
                            let zn = z_true[nv as usize * w + nu as usize];
                            if zn > 0.0
                                && (zn - z).abs() > ratio * z.min(zn)
                                && (zn - z).abs() > (far - z).abs()
                            {
                                far = zn;
                            }
                        }
                        if far != z && unit(hash(seed, pixel, 1, 0)) < fly_p {
                            let mix = 0.15 + 0.7 * unit(hash(seed, pixel, 2, 0));
                            z_meas = z + mix * (far - z);
                            f_row[u] = true;
                        }
                    }
                    z_meas += gaussian(hash(seed, pixel, 3, 0)) * sigma_1m * z * z;
                    if z_meas < z_min || z_meas > z_max {
                        f_row[u] = false;
                        continue;
                    }
                    if dropout > 0.0 && unit(hash(seed, pixel, 4, 0)) < dropout {
                        f_row[u] = false;
                        continue;
                    }
                    d_row[u] = (z_meas * 1000.0).round().clamp(1.0, 65535.0) as u16;
                }
            });
        (depth_mm, labels, person, flying)
    }

    fn render_color(
        &self,
        world: &World,
        camera: usize,
        index: usize,
    ) -> (Vec<u8>, Vec<u8>, Vec<u8>, Vec<u8>) {
        let sensor = &self.color_rays[camera];
        let w = sensor.intrinsics.width as usize;
        let n = sensor.rays.len();
        let rects = world.cull_rects(sensor.origin, sensor.rows);
        let seed = hash(self.seed, index as u64, camera as u64, 0xC0102);
        let mut color = vec![0u8; n * 3];
        let mut labels = vec![0u8; n];
        let mut person = vec![0u8; n];
        let mut segment = vec![0u8; n];
        color
            .par_chunks_mut(w * 3)
            .zip(labels.par_chunks_mut(w))
            .zip(person.par_chunks_mut(w))
            .zip(segment.par_chunks_mut(w))
            .enumerate()
            .for_each(|(v, (((c_row, l_row), p_row), s_row))| {
                let mut candidates = Vec::new();
                for u in 0..w {
                    if u % SPAN_PX == 0 {
                        world.candidates(&rects, sensor.span_bound(v, u), &mut candidates);
                    }
                    let i = v * w + u;
                    let ray = sensor.rays[i];
                    // Far background where nothing is hit: a dim grey.
                    let mut rgb = [0.05f32, 0.05, 0.06];
                    if ray.z_per_t > 0.0
                        && let Some(hit) =
                            world.cast_among(sensor.origin, ray.dir, ray.xy, &rects, &candidates)
                    {
                        let p = crate::geometry::add(
                            sensor.origin,
                            crate::geometry::scale(ray.dir, hit.t),
                        );
                        rgb = shade(&hit.material, p, hit.normal, ray.dir);
                        l_row[u] = hit.owner.class_id();
                        p_row[u] = hit.owner.person_id();
                        if let Owner::Person { segment, .. } = hit.owner {
                            s_row[u] = segment.id();
                        }
                    }
                    let noise = sensor_noise(seed, i as u64);
                    for ch in 0..3 {
                        c_row[u * 3 + ch] = encode(rgb[ch], noise[ch]);
                    }
                }
            });
        (color, labels, person, segment)
    }
}
