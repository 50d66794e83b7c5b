//! Sanity warnings: inputs that are valid but implausible for people in a room (a depth
//! scale off by 1000, a cloud in millimetres, a box far from the cloud, no person at all).
//! Each is one `warning:` line (tracing's warn level, shown by the binary also with
//! `--quiet`), never an error: the command still does what it was asked.

use bodyseg_calib::Rig;
use bodyseg_core::{LabeledCloud, PersonBox};

/// Farthest plausible median distance of a frame's points from their camera, metres: a
/// room. Above it the depth scale is likely wrong (`depth_scale = 1` on millimetres: km).
pub(crate) const MAX_MEDIAN_DISTANCE_M: f32 = 20.0;
/// Nearest plausible median distance, metres (depth in metres read as millimetres).
pub(crate) const MIN_MEDIAN_DISTANCE_M: f32 = 0.2;
/// [`projected_scale_warning`] looks at every this many-th point.
const SAMPLE_STEP: usize = 16;
/// A person box taller than this, metres, is a unit error or not a person.
pub(crate) const MAX_PERSON_HEIGHT_M: f32 = 2.5;

/// The median of `values` (the upper one of an even count); `None` when empty.
fn median(mut values: Vec<f32>) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f32::total_cmp);
    Some(*m)
}

/// The warning for a frame's back-projected points when their median distance from
/// their camera is outside [[`MIN_MEDIAN_DISTANCE_M`], [`MAX_MEDIAN_DISTANCE_M`]].
pub(crate) fn projected_scale_warning(
    cloud: &LabeledCloud,
    rig: &Rig,
    what: &str,
) -> Option<String> {
    let centres: Vec<[f64; 3]> = rig
        .cameras
        .iter()
        .map(|c| c.world_from_depth.translation_m())
        .collect();
    // Every 16th point: the median of a frame's ~300k points to well within the 0.2-20 m
    // window, at a sixteenth of the cost (this runs on every frame of `run`).
    let distances: Vec<f32> = cloud
        .positions_m
        .iter()
        .zip(&cloud.origins)
        .step_by(SAMPLE_STEP)
        .filter_map(|(p, o)| {
            let c = centres.get(usize::from(o.camera))?;
            let d2: f64 = (0..3).map(|a| (f64::from(p[a]) - c[a]).powi(2)).sum();
            Some(d2.sqrt() as f32)
        })
        .collect();
    let m = median(distances)?;
    (!(MIN_MEDIAN_DISTANCE_M..=MAX_MEDIAN_DISTANCE_M).contains(&m)).then(|| {
        format!(
            "{what}: the median point is {m:.3} m from its camera, implausible for people in \
             a room ({MIN_MEDIAN_DISTANCE_M}-{MAX_MEDIAN_DISTANCE_M} m): check the depth unit \
             (rig.toml's depth_scale: raw depth units per metre, 1000 for millimetres)"
        )
    })
}

/// The warning for a cloud read from a file whose points spread implausibly far (median
/// distance from the median point above [`MAX_MEDIAN_DISTANCE_M`]: a cloud in millimetres).
pub(crate) fn cloud_scale_warning(cloud: &LabeledCloud, what: &str) -> Option<String> {
    let centre: Vec<f32> = (0..3)
        .map(|a| median(cloud.positions_m.iter().map(|p| p[a]).collect()))
        .collect::<Option<_>>()?;
    let distances = cloud
        .positions_m
        .iter()
        .map(|p| {
            (0..3)
                .map(|a| (p[a] - centre[a]).powi(2))
                .sum::<f32>()
                .sqrt()
        })
        .collect();
    let m = median(distances)?;
    (m > MAX_MEDIAN_DISTANCE_M).then(|| {
        format!(
            "{what}: half its points are more than {m:.1} m from its centre, implausible for \
             a room (at most {MAX_MEDIAN_DISTANCE_M} m): clouds are in metres (a cloud in \
             millimetres finds no person)"
        )
    })
}

/// The warnings about a frame's person boxes: none at all; a box that holds no point of
/// the cloud (refinement then turns its people's labels into background); a box taller
/// than [`MAX_PERSON_HEIGHT_M`].
pub(crate) fn boxes_warnings(boxes: &[PersonBox], cloud: &LabeledCloud, what: &str) -> Vec<String> {
    if boxes.is_empty() {
        return vec![format!("{what}: no person found")];
    }
    let mut out = Vec::new();
    for b in boxes {
        let test = b.test();
        if !cloud.positions_m.iter().any(|p| test.contains(*p)) {
            out.push(format!(
                "{what}: person box {} holds no point of the cloud (centre {:?} m): is it \
                 of another frame or in other units?",
                b.id, b.center_m
            ));
        }
        let height = 2.0 * b.half_extents_m[2];
        if height > MAX_PERSON_HEIGHT_M {
            out.push(format!(
                "{what}: person box {} is {height:.2} m tall (a person is at most \
                 {MAX_PERSON_HEIGHT_M} m): check the units",
                b.id
            ));
        }
    }
    out
}

/// Logs each warning as one `warning:` line.
pub(crate) fn warn_all(warnings: impl IntoIterator<Item = String>) {
    for w in warnings {
        tracing::warn!("{w}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::{Label, PointOrigin};

    fn cloud(points: &[[f32; 3]]) -> LabeledCloud {
        LabeledCloud {
            positions_m: points.to_vec(),
            labels: vec![Label::BACKGROUND; points.len()],
            colors: None,
            origins: (0..points.len() as u32)
                .map(|pixel| PointOrigin { camera: 0, pixel })
                .collect(),
        }
    }

    fn person(id: u32, center: [f32; 3], half: [f32; 3]) -> PersonBox {
        PersonBox::axis_aligned(id, center, half)
    }

    #[test]
    fn implausible_scales_and_boxes_are_warned_about() {
        let rig = crate::recording::tests::rig();
        let origin = rig.cameras[0].world_from_depth.translation_m();
        let at = |d: f32| {
            let o = origin.map(|v| v as f32);
            cloud(&[
                [o[0] + d, o[1], o[2]],
                [o[0], o[1] + d, o[2]],
                [o[0], o[1], o[2] + d],
            ])
        };
        assert_eq!(projected_scale_warning(&at(3.0), &rig, "f"), None);
        let w = projected_scale_warning(&at(3300.0), &rig, "frame 1").expect("km");
        assert!(
            w.starts_with("frame 1: the median point is 3300.000 m from its camera"),
            "{w}"
        );
        assert!(projected_scale_warning(&at(0.003), &rig, "f").is_some());

        let room = cloud(&[
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 1.0],
            [0.0, 3.0, 1.8],
            [1.0, 1.0, 1.0],
        ]);
        assert_eq!(cloud_scale_warning(&room, "c.ply"), None);
        let mm = cloud(&[
            [0.0, 0.0, 0.0],
            [3000.0, 0.0, 1000.0],
            [0.0, 3000.0, 1800.0],
        ]);
        let w = cloud_scale_warning(&mm, "c.ply").expect("mm");
        assert!(w.contains("clouds are in metres"), "{w}");

        assert_eq!(
            boxes_warnings(&[], &room, "frame 2"),
            ["frame 2: no person found"]
        );
        let inside = person(1, [1.0, 1.0, 0.9], [0.3, 0.3, 0.9]);
        assert!(boxes_warnings(std::slice::from_ref(&inside), &room, "f").is_empty());
        let far = person(2, [500.0, 0.0, 0.9], [0.3, 0.3, 0.9]);
        let tall = person(3, [1.0, 1.0, 900.0], [0.3, 0.3, 900.0]);
        let w = boxes_warnings(&[inside, far, tall], &room, "f");
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with("f: person box 2 holds no point of the cloud"),
            "{w:?}"
        );
        assert!(
            w[1].starts_with("f: person box 3 is 1800.00 m tall"),
            "{w:?}"
        );
    }
}
