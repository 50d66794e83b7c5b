//! Person regions for segmenters that parse one person at a time (BlazePose,
//! [`bodyseg_parsing::Segmenter::needs_regions`]): the people are found from depth before
//! parsing (geometry-mode boxes on the unlabelled cloud), and each box is projected into
//! every colour camera.
//!
//! ```text
//! depth → back-project → find_boxes (geometry) → person_regions (per camera) → parse
//! ```

use crate::config::PipelineConfig;
use anyhow::{Context, Result, bail};
use bodyseg_calib::{RgbdCamera, Rig};
use bodyseg_core::{Label, LabelImage, LabeledCloud, PersonBox, PersonBoxes, RgbImage};
use bodyseg_io::DepthImage;
use bodyseg_parsing::{PersonRegion, PixelBox};
use bodyseg_people::BoxMode;
use bodyseg_project::{CameraImages, FrameProjector, Hits, ProjectConfig};

/// Box corners closer to the colour camera than this (along its optical axis) are clipped
/// to it before projecting, metres: a box reaching behind the camera still projects to a
/// bounded region.
const NEAR_PLANE_M: f64 = 0.05;

/// The 8 corners of a person box, world frame, metres.
fn corners(b: &PersonBox) -> [[f64; 3]; 8] {
    let (sin, cos) = f64::from(b.yaw_rad).sin_cos();
    let c = b.center_m.map(f64::from);
    let h = b.half_extents_m.map(f64::from);
    let mut out = [[0.0; 3]; 8];
    for (k, corner) in out.iter_mut().enumerate() {
        let sx = if k & 1 == 0 { -h[0] } else { h[0] };
        let sy = if k & 2 == 0 { -h[1] } else { h[1] };
        let sz = if k & 4 == 0 { -h[2] } else { h[2] };
        *corner = [
            c[0] + cos * sx - sin * sy,
            c[1] + sin * sx + cos * sy,
            c[2] + sz,
        ];
    }
    out
}

/// The region of person box `b` in `camera`'s colour image: the bounding rectangle of its
/// corners projected (distortion included), edges crossing the camera's near plane clipped
/// to it, the rectangle clipped to the image; its depth is the box centre's along the
/// colour camera's optical axis. `None` when the box lies wholly behind the camera, its
/// centre is behind it, or its projection misses the image.
pub fn person_region(camera: &RgbdCamera, b: &PersonBox) -> Option<PersonRegion> {
    let color_from_world = camera
        .color_from_depth
        .compose(&camera.world_from_depth.inverse());
    let in_color: Vec<[f64; 3]> = corners(b)
        .iter()
        .map(|p| color_from_world.transform_point(*p))
        .collect();
    let centre = color_from_world.transform_point(b.center_m.map(f64::from));
    if centre[2].is_nan() || centre[2] <= 0.0 {
        return None;
    }
    // Corners in front of the near plane, and where the box's edges cross it.
    let mut front: Vec<[f64; 3]> = in_color
        .iter()
        .copied()
        .filter(|p| p[2] >= NEAR_PLANE_M)
        .collect();
    for i in 0..8 {
        for bit in [1usize, 2, 4] {
            let j = i | bit;
            if j == i {
                continue;
            }
            let (p, q) = (in_color[i], in_color[j]);
            if (p[2] >= NEAR_PLANE_M) != (q[2] >= NEAR_PLANE_M) {
                let t = (NEAR_PLANE_M - p[2]) / (q[2] - p[2]);
                front.push([
                    p[0] + t * (q[0] - p[0]),
                    p[1] + t * (q[1] - p[1]),
                    NEAR_PLANE_M,
                ]);
            }
        }
    }
    let intr = &camera.color;
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in &front {
        // Far outside the image a lens model may fold; the pinhole part bounds the box
        // well enough there.
        let uv = intr.project(*p).unwrap_or([
            intr.fx * p[0] / p[2] + intr.cx,
            intr.fy * p[1] / p[2] + intr.cy,
        ]);
        for k in 0..2 {
            lo[k] = lo[k].min(uv[k]);
            hi[k] = hi[k].max(uv[k]);
        }
    }
    let (w, h) = (f64::from(intr.width), f64::from(intr.height));
    if front.is_empty() || !(lo[0].is_finite() && hi[0].is_finite()) {
        return None;
    }
    let bounds = PixelBox {
        x0: lo[0].max(0.0),
        y0: lo[1].max(0.0),
        x1: hi[0].min(w - 1.0),
        y1: hi[1].min(h - 1.0),
    };
    (bounds.x1 >= bounds.x0 && bounds.y1 >= bounds.y0).then_some(PersonRegion {
        bounds,
        depth_m: centre[2],
    })
}

/// Every box's region in every camera of `rig` ([`person_region`]): one list per camera,
/// in rig order, boxes in their order (those a camera does not see left out).
pub fn person_regions(rig: &Rig, boxes: &[PersonBox]) -> Vec<Vec<PersonRegion>> {
    rig.cameras
        .iter()
        .map(|camera| {
            boxes
                .iter()
                .filter_map(|b| person_region(camera, b))
                .collect()
        })
        .collect()
}

/// The people of a frame found from depth alone, before parsing: the depth images
/// back-projected (naive projection of all-background label images: the labels are not
/// used), with the points' camera colours when the frame has colour images and the box
/// finder uses them, and `bodyseg_people::find_boxes` in geometry mode with the
/// configuration's `[boxes]` values.
///
/// `stem` names the frame; `depth` and `colour` are its images, in rig order.
///
/// # Errors
/// The frame has no depth images; they do not fit the rig; the box finder fails.
pub fn find_people(
    stem: &str,
    depth: &[DepthImage],
    color: Option<&[RgbImage]>,
    rig: &Rig,
    config: &PipelineConfig,
) -> Result<PersonBoxes> {
    if depth.len() != rig.cameras.len() {
        bail!(
            "frame {stem}: finding people needs the depth images of all {} cameras",
            rig.cameras.len()
        );
    }
    let blank: Vec<LabelImage> = rig
        .cameras
        .iter()
        .map(|c| LabelImage::filled(c.color.width, c.color.height, Label::BACKGROUND))
        .collect();
    let images: Vec<CameraImages<'_>> = depth
        .iter()
        .zip(&blank)
        .map(|(d, labels)| CameraImages {
            depth_raw: &d.depth_mm,
            labels,
        })
        .collect();
    let projector = FrameProjector::new(rig)?;
    let mut cloud = LabeledCloud::default();
    let mut hits = Hits::default();
    projector.project_frame_keeping_hits(
        &images,
        &config.backproject.options(),
        &ProjectConfig::naive(),
        &mut cloud,
        &mut hits,
    )?;
    let mut boxes_cfg = config.boxes.clone();
    boxes_cfg.mode = BoxMode::Geometry;
    if boxes_cfg.uses_colors()
        && let Some(color) = color
    {
        let color: Vec<&RgbImage> = color.iter().collect();
        cloud.colors = Some(hits.colors_of(&cloud, &color));
    }
    let mut boxes = bodyseg_people::find_boxes(&cloud, &boxes_cfg)
        .with_context(|| format!("frame {stem}: people from depth (geometry boxes)"))?;
    boxes.frame = stem.to_string();
    Ok(boxes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_calib::{Distortion, Intrinsics, Pose};

    /// A 640×480 camera at the world origin looking along world +y (z up): optical
    /// z = world y, optical x = world x, optical y = −world z.
    fn camera() -> RgbdCamera {
        let intr = Intrinsics::pinhole(640, 480, 500.0, 500.0, 319.5, 239.5)
            .with_distortion(Distortion::default());
        let mut cam = RgbdCamera::new("cam0", intr, intr);
        // world_from_depth: depth x → world x, depth y → world −z, depth z → world y.
        cam.world_from_depth = Pose::from_rotation_translation(
            [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
            [0.0, 0.0, 0.0],
        )
        .expect("a rotation");
        cam
    }

    fn person(x: f32, y: f32) -> PersonBox {
        PersonBox::axis_aligned(0, [x, y, 0.0], [0.3, 0.2, 0.9])
    }

    #[test]
    fn a_box_in_front_projects_to_its_rectangle() {
        let r = person_region(&camera(), &person(0.0, 3.0)).expect("in view");
        // Nearest face at y = 2.8: u = 319.5 ± 500·0.3/2.8, v = 239.5 ± 500·0.9/2.8.
        let (du, dv) = (500.0 * 0.3 / 2.8, 500.0 * 0.9 / 2.8);
        // Tolerance: the box's f32 fields (0.3f32 is 0.3 + 1.2e-8) scaled by ~180 px/m,
        // far below a pixel.
        let close = |a: f64, b: f64| (a - b).abs() < 1e-4;
        assert!(close(r.bounds.x0, 319.5 - du) && close(r.bounds.x1, 319.5 + du));
        assert!(close(r.bounds.y0, 239.5 - dv) && close(r.bounds.y1, 239.5 + dv));
        assert!(close(r.depth_m, 3.0));
    }

    #[test]
    fn a_box_behind_or_beside_the_camera_has_no_region_and_a_near_one_is_clipped() {
        assert!(
            person_region(&camera(), &person(0.0, -3.0)).is_none(),
            "behind"
        );
        assert!(
            person_region(&camera(), &person(30.0, 3.0)).is_none(),
            "far right"
        );
        // Straddling the camera: clipped to the image, not unbounded.
        let mut near = person(0.0, 0.1);
        near.half_extents_m = [0.3, 0.5, 0.9];
        let r = person_region(&camera(), &near).expect("centre in front");
        assert_eq!(
            (r.bounds.x0, r.bounds.y0, r.bounds.x1, r.bounds.y1),
            (0.0, 0.0, 639.0, 479.0)
        );
        // Partly outside: clipped at the image's edge.
        let r = person_region(&camera(), &person(2.0, 3.0)).expect("partly in view");
        assert_eq!(r.bounds.x1, 639.0);
        assert!(r.bounds.x0 > 319.5);
    }

    #[test]
    fn regions_come_per_camera_in_box_order() {
        let rig = Rig {
            cameras: vec![camera(), camera()],
        };
        let regions = person_regions(
            &rig,
            &[person(1.0, 3.0), person(0.0, -3.0), person(-1.0, 4.0)],
        );
        assert_eq!(regions.len(), 2);
        assert_eq!(regions[0].len(), 2, "the box behind is left out");
        assert!(
            regions[0][0].bounds.x0 > regions[0][1].bounds.x1,
            "order kept"
        );
        assert!(regions[0][1].depth_m > regions[0][0].depth_m);
    }
}
