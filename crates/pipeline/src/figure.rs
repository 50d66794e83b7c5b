//! Pictures of a run: refined labels drawn back into a colour camera's image
//! ([`LabelView`]), and the Figure-5-style panels of the paper ([`figure_image`]): the same
//! points from one fixed viewpoint, coloured by input labels, clusters, and each
//! configuration's labels.

use bodyseg_calib::{RgbdCamera, Rig};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label, LabelImage, LabeledCloud, PersonBox, RgbImage};
use bodyseg_project::{ColorProjection, Hits, NO_HIT};

/// Draws a cloud's labels into one camera's colour image: each point of that camera goes
/// through `color_from_world` and the colour intrinsics (bodyseg-project's f32
/// [`ColorProjection`], distortion included) to its nearest colour pixel and covers a
/// small square around it (the colour image is denser than the depth image), the nearest
/// point winning.
#[derive(Clone, Debug)]
pub(crate) struct LabelView {
    projection: ColorProjection,
    splat_radius_px: usize,
}

impl LabelView {
    /// The view of `camera`; `stride` is the back-projection stride (sparser points need
    /// larger squares).
    pub(crate) fn new(camera: &RgbdCamera, stride: u32) -> LabelView {
        let color_from_world = camera
            .color_from_depth
            .compose(&camera.world_from_depth.inverse());
        // Spacing of neighbouring depth points in the colour image, pixels: the focal
        // length ratio times the stride. Squares of side 2r+1 >= spacing leave no holes.
        let spacing = camera.color.fx / camera.depth.fx.max(1e-9) * f64::from(stride.max(1));
        let splat_radius_px = (((spacing - 1.0) / 2.0).ceil() as i64).clamp(1, 8) as usize;
        LabelView {
            projection: ColorProjection::from_pose(&color_from_world, &camera.color),
            splat_radius_px,
        }
    }

    /// The labels of `cloud`'s points from camera `camera` drawn into its colour image;
    /// pixels no point reaches are unknown (255).
    #[cfg(test)]
    pub(crate) fn render(&self, cloud: &LabeledCloud, camera: u8) -> LabelImage {
        let mut image = LabelImage::filled(0, 0, Label::UNKNOWN);
        self.render_into(cloud, camera, None, &mut Vec::new(), &mut image);
        image
    }

    /// [`LabelView::render`] into `image`, with `keys` as working memory (both reused
    /// from call to call: a worker drawing frame after frame allocates nothing).
    ///
    /// `hits`, when given, must be where each of `cloud`'s points landed in its own
    /// camera's colour image, in the cloud's order
    /// ([`bodyseg_project::FrameProjector::project_frame_keeping_hits`] of this very
    /// cloud, which is in projection order: cameras one after the other): the points are
    /// then not projected again. Hits from `color_from_depth` and this view's
    /// `color_from_world` are the same pixels up to f32 rounding (a point within ~1e-3 px
    /// of a half-pixel boundary may take the neighbour). Without hits, or with hits of
    /// another length, every point of the camera is projected here.
    pub(crate) fn render_into(
        &self,
        cloud: &LabeledCloud,
        camera: u8,
        hits: Option<&Hits>,
        keys: &mut Vec<u32>,
        image: &mut LabelImage,
    ) {
        let (width, height) = self.projection.size_px();
        let r = self.splat_radius_px;
        // The key buffer has a border of r pixels on every side, so that a point's
        // square never needs clipping: the inner loop has no branch.
        let (pw, ph) = (width as usize + 2 * r, height as usize + 2 * r);
        keys.clear();
        keys.resize(pw * ph, EMPTY_KEY);
        let mut splat = |u: u32, v: u32, z: f32, label: Label| {
            let key = depth_key(z, label);
            // (u, v) is the centre's pixel; in the bordered buffer the square's top-left.
            let top_left = v as usize * pw + u as usize;
            for row in keys[top_left..].chunks_mut(pw).take(2 * r + 1) {
                for k in &mut row[..=2 * r] {
                    *k = (*k).min(key);
                }
            }
        };
        match hits.filter(|h| h.len() == cloud.len()) {
            Some(hits) => {
                // The camera's points: a contiguous range in projection order.
                let first = cloud.origins.partition_point(|o| o.camera < camera);
                let end = cloud.origins.partition_point(|o| o.camera <= camera);
                let range = first..end;
                let (us, vs, zs) = (
                    &hits.columns()[range.clone()],
                    &hits.rows()[range.clone()],
                    &hits.z_color_m()[range.clone()],
                );
                for (((&u, &v), &z), &label) in us.iter().zip(vs).zip(zs).zip(&cloud.labels[range])
                {
                    if u != NO_HIT {
                        splat(u, v, z, label);
                    }
                }
            }
            None => {
                for ((p, &label), o) in cloud
                    .positions_m
                    .iter()
                    .zip(&cloud.labels)
                    .zip(&cloud.origins)
                {
                    if o.camera != camera {
                        continue;
                    }
                    if let Some((u, v, z)) = self.projection.nearest_pixel(*p) {
                        splat(u, v, z, label);
                    }
                }
            }
        }
        image.width = width;
        image.height = height;
        image.probs = None;
        image.labels.clear();
        for row in keys.chunks(pw).skip(r).take(height as usize) {
            // One row at a time: a plain map that vectorises.
            image
                .labels
                .extend(row[r..r + width as usize].iter().map(|&k| label_of_key(k)));
        }
    }
}

/// A pixel no point reaches; its low byte is [`Label::UNKNOWN_ID`].
const EMPTY_KEY: u32 = u32::MAX;

/// A point's depth and label in one `u32` whose order is the depth's (nearest = smallest):
/// a positive f32's bits order as the float does; the low 8 bits of the mantissa (a
/// relative 2⁻¹⁵, 0.1 mm at 3 m) give way to the label id, so the splat is one `min` per
/// pixel (points closer than that in depth: the smaller label id wins).
#[inline(always)]
fn depth_key(z_m: f32, label: Label) -> u32 {
    (z_m.to_bits() & !0xFF) | u32::from(label.id())
}

/// The label of a key ([`EMPTY_KEY`] → unknown).
#[inline(always)]
fn label_of_key(key: u32) -> Label {
    Label::from_id_or_unknown((key & 0xFF) as u8)
}

/// A fixed orthographic viewpoint for the panels: screen axes in the world and the part
/// of the cloud shown.
#[derive(Clone, Debug)]
pub(crate) struct PanelView {
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    /// Points shown: inside one of these boxes (grown by a margin).
    boxes: Vec<PersonBox>,
    /// Screen extent of the shown points, metres: min x, min y, max x, max y.
    extent: [f32; 4],
    /// Depth range of the shown points along `forward`, metres.
    depth: [f32; 2],
    px_per_m: f32,
}

/// Points of the cloud within this distance outside a person box are still drawn.
const VIEW_MARGIN_M: f32 = 0.05;
/// Look down by this much (degrees): a little from above, as a person would see.
const VIEW_ELEVATION_DEG: f32 = 12.0;
/// Preferred scale and the widest panel, pixels.
const PANEL_PX_PER_M: f32 = 200.0;
const PANEL_MAX_WIDTH_PX: f32 = 640.0;
/// Height of the title band, pixels.
const TITLE_PX: u32 = 26;

/// The viewpoint of a frame's figure: from the first camera's side (horizontally, looking
/// at the people), slightly from above; showing the points inside the person boxes, or
/// every body-labelled point's surroundings when there is no box.
pub(crate) fn panel_view(cloud: &LabeledCloud, boxes: &[PersonBox], rig: &Rig) -> PanelView {
    let boxes: Vec<PersonBox> = if boxes.is_empty() {
        body_box(cloud).into_iter().collect()
    } else {
        boxes.to_vec()
    };
    let centre = if boxes.is_empty() {
        [0.0, 0.0, 1.0]
    } else {
        let n = boxes.len() as f32;
        let mut c = [0.0f32; 3];
        for b in &boxes {
            for a in 0..3 {
                c[a] += b.center_m[a] / n;
            }
        }
        c
    };
    let eye = rig
        .cameras
        .first()
        .map(|c| c.world_from_depth.translation_m())
        .map_or([centre[0], centre[1] - 3.0, centre[2]], |t| {
            [t[0] as f32, t[1] as f32, t[2] as f32]
        });
    let mut d = [centre[0] - eye[0], centre[1] - eye[1]];
    let n = (d[0] * d[0] + d[1] * d[1]).sqrt();
    d = if n > 1e-6 {
        [d[0] / n, d[1] / n]
    } else {
        [0.0, 1.0]
    };
    let a = VIEW_ELEVATION_DEG.to_radians();
    let forward = [d[0] * a.cos(), d[1] * a.cos(), -a.sin()];
    let right = [d[1], -d[0], 0.0];
    let up = [d[0] * a.sin(), d[1] * a.sin(), a.cos()];
    let mut view = PanelView {
        right,
        up,
        forward,
        boxes,
        extent: [
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        ],
        depth: [f32::INFINITY, f32::NEG_INFINITY],
        px_per_m: PANEL_PX_PER_M,
    };
    for p in &cloud.positions_m {
        if view.shows(*p) {
            let [x, y, z] = view.screen(*p);
            view.extent = [
                view.extent[0].min(x),
                view.extent[1].min(y),
                view.extent[2].max(x),
                view.extent[3].max(y),
            ];
            view.depth = [view.depth[0].min(z), view.depth[1].max(z)];
        }
    }
    if !view.extent[0].is_finite() {
        view.extent = [0.0, 0.0, 1.0, 2.0];
        view.depth = [0.0, 1.0];
    }
    let width_m = view.extent[2] - view.extent[0] + 0.1;
    view.px_per_m = PANEL_PX_PER_M.min(PANEL_MAX_WIDTH_PX / width_m.max(0.1));
    view
}

impl PanelView {
    fn shows(&self, p: Vec3) -> bool {
        self.boxes.iter().any(|b| {
            let mut g = b.clone();
            for a in 0..3 {
                g.half_extents_m[a] += VIEW_MARGIN_M;
            }
            g.contains(p)
        })
    }

    /// (right, up, forward) coordinates of a world point, metres.
    fn screen(&self, p: Vec3) -> Vec3 {
        let dot = |a: Vec3| a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
        [dot(self.right), dot(self.up), dot(self.forward)]
    }

    fn size_px(&self) -> (u32, u32) {
        let w = ((self.extent[2] - self.extent[0] + 0.1) * self.px_per_m).ceil() as u32;
        let h = ((self.extent[3] - self.extent[1] + 0.1) * self.px_per_m).ceil() as u32;
        (w.max(8), h.max(8))
    }
}

/// The box around the body-labelled points, for a frame without person boxes.
fn body_box(cloud: &LabeledCloud) -> Option<PersonBox> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (p, l) in cloud.positions_m.iter().zip(&cloud.labels) {
        if l.is_body() {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
    }
    lo[0].is_finite().then(|| PersonBox {
        id: 0,
        center_m: [
            (lo[0] + hi[0]) / 2.0,
            (lo[1] + hi[1]) / 2.0,
            (lo[2] + hi[2]) / 2.0,
        ],
        half_extents_m: [
            (hi[0] - lo[0]) / 2.0,
            (hi[1] - lo[1]) / 2.0,
            (hi[2] - lo[2]) / 2.0,
        ],
        yaw_rad: 0.0,
    })
}

/// One panel of a figure.
#[derive(Debug)]
pub(crate) enum FigurePanel<'a> {
    /// Points coloured by label (the class palette; background light grey, unknown dark
    /// grey), one label per cloud point.
    Labels {
        /// Title above the panel (upper case letters, digits, `-`).
        title: String,
        /// Per point of the cloud.
        labels: &'a [Label],
    },
    /// Points coloured by cluster (a colour per (person, cluster); noise grey).
    Clusters {
        /// Title above the panel.
        title: String,
        /// Per point of the cloud: (person, cluster) or none.
        clusters: &'a [Option<(u32, u32)>],
    },
}

fn label_color(l: Label) -> [u8; 3] {
    match l.class() {
        None => [90, 90, 90],
        Some(Class::Background) => [200, 200, 200],
        Some(c) => c.color(),
    }
}

fn cluster_color(c: Option<(u32, u32)>) -> [u8; 3] {
    let Some((p, k)) = c else {
        return [170, 170, 170];
    };
    // A well-spread hue per cluster (golden-ratio steps), saturated and not too light.
    let h = ((p * 7 + k) as f32 * 0.618_034).fract() * 6.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    let s = |v: f32| (40.0 + v * 190.0) as u8;
    [s(r), s(g), s(b)]
}

/// A point's colour in a panel, by point index.
type ColorOf<'a> = Box<dyn Fn(usize) -> [u8; 3] + 'a>;

/// Renders the panels side by side from `view` (white background, title band on top,
/// nearer points drawn over farther ones and shaded a little lighter).
pub(crate) fn figure_image(
    cloud: &LabeledCloud,
    view: &PanelView,
    panels: &[FigurePanel<'_>],
) -> RgbImage {
    let (pw, ph) = view.size_px();
    const GAP: u32 = 6;
    let n = panels.len().max(1) as u32;
    let width = n * pw + (n - 1) * GAP;
    let height = ph + TITLE_PX;
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    // Screen position, depth and point index of every shown point, once for all panels.
    let shown: Vec<(u32, u32, f32, usize)> = cloud
        .positions_m
        .iter()
        .enumerate()
        .filter(|(_, p)| view.shows(**p))
        .filter_map(|(i, p)| {
            let [x, y, z] = view.screen(*p);
            let u = ((x - view.extent[0] + 0.05) * view.px_per_m) as i64;
            let v = ((view.extent[3] - y + 0.05) * view.px_per_m) as i64;
            (u >= 0 && v >= 0 && u < i64::from(pw) && v < i64::from(ph))
                .then_some((u as u32, v as u32, z, i))
        })
        .collect();
    let mut z_buffer = vec![f32::INFINITY; (pw * ph) as usize];
    let depth_span = (view.depth[1] - view.depth[0]).max(1e-3);
    for (k, panel) in panels.iter().enumerate() {
        let x0 = k as u32 * (pw + GAP);
        let (title, color): (&str, ColorOf<'_>) = match panel {
            FigurePanel::Labels { title, labels } => (
                title,
                Box::new(|i| labels.get(i).copied().map_or([0, 0, 0], label_color)),
            ),
            FigurePanel::Clusters { title, clusters } => (
                title,
                Box::new(|i| cluster_color(clusters.get(i).copied().flatten())),
            ),
        };
        z_buffer.fill(f32::INFINITY);
        for &(u, v, z, i) in &shown {
            let c = color(i);
            // Nearer is lighter: 1.0 at the front, 0.7 at the back.
            let shade = 1.0 - 0.3 * ((z - view.depth[0]) / depth_span).clamp(0.0, 1.0);
            let c = c.map(|x| (f32::from(x) * shade) as u8);
            for y in v.saturating_sub(1)..=(v + 1).min(ph - 1) {
                for x in u.saturating_sub(1)..=(u + 1).min(pw - 1) {
                    let zi = (y * pw + x) as usize;
                    if z < z_buffer[zi] {
                        z_buffer[zi] = z;
                        let o = (((y + TITLE_PX) * width + x0 + x) * 3) as usize;
                        rgb[o..o + 3].copy_from_slice(&c);
                    }
                }
            }
        }
        draw_text(&mut rgb, width, x0, pw, title);
    }
    RgbImage { width, height, rgb }
}

/// Draws `text` centred in the title band of the panel starting at column `x0`, with the
/// 8×8 font scaled 2×.
fn draw_text(rgb: &mut [u8], width: u32, x0: u32, panel_width: u32, text: &str) {
    const SCALE: u32 = 2;
    let text_w = text.chars().count() as u32 * 8 * SCALE;
    let left = x0 + panel_width.saturating_sub(text_w) / 2;
    let top = (TITLE_PX - 8 * SCALE) / 2;
    for (k, ch) in text.chars().enumerate() {
        let glyph = font8x8::legacy::BASIC_LEGACY
            .get(ch as usize)
            .copied()
            .unwrap_or([0; 8]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8u32 {
                if bits >> col & 1 == 0 {
                    continue;
                }
                for dy in 0..SCALE {
                    for dx in 0..SCALE {
                        let x = left + (k as u32 * 8 + col) * SCALE + dx;
                        let y = top + row as u32 * SCALE + dy;
                        if x < width {
                            let o = ((y * width + x) * 3) as usize;
                            if let Some(px) = rgb.get_mut(o..o + 3) {
                                px.copy_from_slice(&[20, 20, 20]);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_calib::Intrinsics;
    use bodyseg_core::PointOrigin;

    fn camera() -> RgbdCamera {
        let depth = Intrinsics::pinhole(64, 48, 50.0, 50.0, 32.0, 24.0);
        let mut color = depth;
        color.width = 128;
        color.height = 96;
        color.fx = 100.0;
        color.fy = 100.0;
        color.cx = 64.0;
        color.cy = 48.0;
        RgbdCamera::new("cam0", depth, color)
    }

    #[test]
    fn label_view_draws_the_nearest_point_at_its_pixel() {
        let view = LabelView::new(&camera(), 1);
        // Two points on the optical axis (identity poses): the nearer one wins.
        let cloud = LabeledCloud {
            positions_m: vec![[0.0, 0.0, 2.0], [0.0, 0.0, 1.0], [0.5, 0.0, 1.0]],
            labels: vec![
                Label::from(Class::Head),
                Label::from(Class::Torso),
                Label::from(Class::Head),
            ],
            colors: None,
            origins: (0..3)
                .map(|pixel| PointOrigin { camera: 0, pixel })
                .collect(),
        };
        let image = view.render(&cloud, 0);
        assert_eq!(image.get(64, 48), Some(Label::from(Class::Torso)));
        // x = 0.5 m at 1 m: 50 px right of the centre.
        assert_eq!(image.get(114, 48), Some(Label::from(Class::Head)));
        assert_eq!(image.get(10, 10), Some(Label::UNKNOWN));
        // Another camera's points are not drawn.
        let other = view.render(&cloud, 1);
        assert!(other.labels.iter().all(|l| l.is_unknown()));
    }

    #[test]
    fn label_view_from_the_projections_hits_draws_what_projecting_again_draws() {
        use bodyseg_calib::{BackProjectOptions, Pose, Rig};
        use bodyseg_project::{CameraImages, FrameProjector, ProjectConfig, ProjectMode};
        // Two cameras, the second 0.3 m to the side and turned a little: a slanted wall
        // with a nearer block in front, labels in vertical stripes.
        let mut second = camera();
        second.name = "cam1".into();
        second.world_from_depth =
            Pose::from_quaternion_wxyz([0.996, 0.0, 0.087, 0.0], [0.3, 0.0, 0.0]).expect("pose");
        let rig = Rig {
            cameras: vec![camera(), second],
        };
        let depth: Vec<u16> = (0..48u32)
            .flat_map(|v| {
                (0..64u32).map(move |u| {
                    if (20..36).contains(&u) && (14..30).contains(&v) {
                        1000
                    } else {
                        1500 + 8 * u as u16 + 3 * v as u16
                    }
                })
            })
            .collect();
        let stripes: Vec<Label> = (0..96u32)
            .flat_map(|_| (0..128u32).map(|u| Label::from(Class::ALL[(u / 9) as usize % 7])))
            .collect();
        let labels = LabelImage::new(128, 96, stripes).expect("image");
        let images = [
            CameraImages {
                depth_raw: &depth,
                labels: &labels,
            },
            CameraImages {
                depth_raw: &depth,
                labels: &labels,
            },
        ];
        let projector = FrameProjector::new(&rig).expect("rig");
        for mode in [ProjectMode::Naive, ProjectMode::Dsa] {
            let cfg = ProjectConfig {
                mode,
                ..Default::default()
            };
            let mut cloud = LabeledCloud::default();
            let mut hits = Hits::default();
            projector
                .project_frame_keeping_hits(
                    &images,
                    &BackProjectOptions::default(),
                    &cfg,
                    &mut cloud,
                    &mut hits,
                )
                .expect("project");
            assert_eq!(hits.len(), cloud.len(), "{mode:?}");
            for (c, camera) in rig.cameras.iter().enumerate() {
                let view = LabelView::new(camera, 1);
                let mut from_hits = LabelImage::filled(0, 0, Label::UNKNOWN);
                view.render_into(
                    &cloud,
                    c as u8,
                    Some(&hits),
                    &mut Vec::new(),
                    &mut from_hits,
                );
                let again = view.render(&cloud, c as u8);
                assert_eq!((from_hits.width, from_hits.height), (128, 96));
                let drawn = again.labels.iter().filter(|l| !l.is_unknown()).count();
                assert!(drawn > 128 * 96 / 2, "{mode:?} camera {c}: {drawn} pixels");
                // f32 rounding of two poses may move a point near a pixel boundary, or
                // decide between two points at the same depth (the block's front face)
                // the other way: a few pixels, against thousands for a wrong range.
                let differ = Label::count_differing(&from_hits.labels, &again.labels);
                assert!(
                    differ * 100 <= drawn,
                    "{mode:?} camera {c}: {differ} of {drawn} pixels differ"
                );
            }
            // Hits of another length (another cloud) are not used.
            let mut fewer = cloud.clone();
            fewer.positions_m.pop();
            fewer.labels.pop();
            fewer.origins.pop();
            let view = LabelView::new(&rig.cameras[0], 1);
            let mut image = LabelImage::filled(0, 0, Label::UNKNOWN);
            view.render_into(&fewer, 0, Some(&hits), &mut Vec::new(), &mut image);
            assert_eq!(image, view.render(&fewer, 0));
        }
    }
}
