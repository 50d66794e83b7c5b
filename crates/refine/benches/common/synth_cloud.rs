//! A sensor-like bench input: one person of `bodyseg synth` seen by Kinect-v2-like depth
//! cameras (ray-cast depth, depth noise, flying pixels, dropout), cropped to the person's
//! true box, with the simulated parser's label errors made on the depth images.
//!
//! Shared by `benches/refine.rs` and `examples/dbscan_cloud.rs` (`#[path]`), so that the
//! criterion figures and `scripts/bench_dbscan_peers.py` measure the same points.
//!
//! How a size is reached: the scene `single` (one person, pose `walking`, room with floor
//! and walls) is rendered by rings of three cameras (the preset's rig, 2.6 m away, heights
//! 1.8–2.5 m); one ring gives about 35k points in the box (seed 1), so enough rings at
//! evenly spread azimuths give at least `n` (30k: 3 cameras, 100k: 9, 300k: 27), and a
//! seeded choice of exactly `n` of them (cloud order kept) is the cloud: density grows with
//! `n` as in the testkit clouds, the mix of surface, floor and flying pixels stays that of
//! real views.
//!
//! Labels: each camera's per-pixel truth (the class of the surface its ray hit, so a flying
//! pixel off a silhouette keeps the person's label) passed through the simulated parser's
//! dilation and boundary jitter (`bodyseg_synth::parser_mistakes::predict_labels`, pixel sizes
//! scaled to the 512-pixel-wide depth image): label errors along part boundaries, as a
//! projection makes them.

use bodyseg_core::rng::splitmix64;
use bodyseg_core::{Label, LabeledCloud, PersonBox, PointOrigin};
use bodyseg_synth::parser_mistakes::{TruthView, predict_labels};
use bodyseg_synth::{CameraPlacement, NO_SURFACE, Synth, preset};

/// The cloud of one person and the box holding it.
pub struct SynthPersonCloud {
    /// Exactly the asked number of points, labelled as a parser and projection would.
    pub cloud: LabeledCloud,
    /// The person's true box (`bodyseg_synth::BOX_MARGIN_M` around its surfaces).
    pub person_box: PersonBox,
    /// Depth cameras rendered.
    pub cameras: usize,
    /// Points of the cloud that are flying pixels.
    pub flying: usize,
    /// Points whose label differs from the truth.
    pub mislabelled: usize,
}

/// Most cameras one scene may hold (`bodyseg_synth`'s limit).
const MAX_CAMERAS: usize = 15;

/// Renders the person with `rings` rings of three cameras and keeps the points in its box:
/// (cloud, box, flying flags, truth labels). The cameras are the preset ring's with
/// `3 × rings` cameras (azimuths evenly spread from −90°, heights evenly spread over
/// 1.8–2.5 m, 2.6 m away), rendered by scenes of at most [`MAX_CAMERAS`] (the same person:
/// it depends on the seed only).
fn render(
    rings: usize,
    seed: u64,
) -> Result<(LabeledCloud, PersonBox, Vec<bool>, Vec<Label>), String> {
    let mut scene = preset("single").map_err(|e| e.to_string())?;
    scene.people.poses = vec!["walking".into()];
    let rig = scene.rig.clone();
    let n = 3 * rings;
    let all: Vec<CameraPlacement> = (0..n)
        .map(|i| CameraPlacement {
            azimuth_deg: rig.first_azimuth_deg + 360.0 * i as f64 / n as f64,
            distance_m: rig.distance_m,
            height_m: rig.height_m[0]
                + (rig.height_m[1] - rig.height_m[0]) * i as f64 / (n - 1) as f64,
        })
        .collect();
    let mut cloud = LabeledCloud::default();
    let (mut flying, mut truth_labels) = (Vec::new(), Vec::new());
    let mut person_box = None;
    for (batch, placements) in all.chunks(MAX_CAMERAS).enumerate() {
        scene.rig.placements = placements.to_vec();
        let synth = Synth::new(scene.clone(), seed).map_err(|e| e.to_string())?;
        let frame = synth.frame(0);
        let truth = synth.truth_cloud(&frame).map_err(|e| e.to_string())?;
        let b = frame
            .boxes
            .boxes
            .first()
            .cloned()
            .ok_or("the scene has no person")?;
        let test = b.test();
        person_box = Some(b);
        // The parser's errors, made on each depth image's truth.
        let predicted: Vec<Vec<u8>> = frame
            .cameras
            .iter()
            .enumerate()
            .map(|(c, cam)| {
                let depth = &synth.true_rig().cameras[c].depth;
                let labels: Vec<u8> = cam
                    .depth_labels
                    .iter()
                    .map(|&l| if l == NO_SURFACE { 0 } else { l })
                    .collect();
                let view = TruthView {
                    width: depth.width,
                    height: depth.height,
                    labels: &labels,
                    person: &cam.depth_person,
                    // No per-pixel segments in depth: the per-limb errors are left out.
                    segment: &[],
                };
                let camera = (batch * MAX_CAMERAS + c) as u64;
                predict_labels(
                    &view,
                    &synth.config().parsing,
                    seed ^ ((camera + 1) * 0x9E37),
                )
            })
            .collect();
        for ((&p, &l), &o) in truth
            .positions_m
            .iter()
            .zip(&truth.labels)
            .zip(&truth.origins)
        {
            if !test.contains(p) {
                continue;
            }
            let cam = usize::from(o.camera);
            let px = o.pixel as usize;
            cloud.positions_m.push(p);
            cloud
                .labels
                .push(Label::from_id(predicted[cam][px]).unwrap_or(Label::UNKNOWN));
            cloud.origins.push(PointOrigin {
                camera: (batch * MAX_CAMERAS + cam) as u8,
                ..o
            });
            flying.push(frame.cameras[cam].flying[px]);
            truth_labels.push(l);
        }
    }
    let person_box = person_box.ok_or("no camera rendered")?;
    Ok((cloud, person_box, flying, truth_labels))
}

/// The person cloud of exactly `n` points (at least 1) for `seed`.
pub fn synth_person_cloud(n: usize, seed: u64) -> Result<SynthPersonCloud, String> {
    let (mut cloud, mut person_box, mut flying, mut truth) = render(1, seed)?;
    let mut rings = 1;
    while cloud.len() < n {
        let per_ring = (cloud.len() / rings).max(1);
        rings = n.div_ceil(per_ring).max(rings + 1);
        (cloud, person_box, flying, truth) = render(rings, seed)?;
    }
    // A seeded choice of n points, in cloud order (splitmix64 keys, the n smallest).
    let mut keyed: Vec<(u64, usize)> = (0..cloud.len())
        .map(|i| {
            (
                splitmix64(seed ^ (i as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)),
                i,
            )
        })
        .collect();
    keyed.select_nth_unstable(n.saturating_sub(1));
    let mut keep: Vec<usize> = keyed[..n].iter().map(|&(_, i)| i).collect();
    keep.sort_unstable();
    fn pick<T: Copy>(keep: &[usize], v: &[T]) -> Vec<T> {
        keep.iter().map(|&i| v[i]).collect()
    }
    let out = LabeledCloud {
        positions_m: pick(&keep, &cloud.positions_m),
        labels: pick(&keep, &cloud.labels),
        colors: None,
        origins: pick(&keep, &cloud.origins),
    };
    let flying = keep.iter().filter(|&&i| flying[i]).count();
    let mislabelled = keep
        .iter()
        .filter(|&&i| cloud.labels[i] != truth[i])
        .count();
    Ok(SynthPersonCloud {
        cloud: out,
        person_box,
        cameras: 3 * rings,
        flying,
        mislabelled,
    })
}
