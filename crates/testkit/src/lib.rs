//! bodyseg-testkit: seeded generators of labelled test scenes for tests and benches.
//!
//! Place in the workspace: a dev-dependency only. It stands in for `bodyseg-synth` (the
//! full renderer) where a test needs a human-shaped labelled cloud fast and without cameras:
//! points are sampled on the surfaces of capsules forming a body, ground truth is exact, and
//! the "predicted" labels carry the errors that 2D parsing plus projection make (ALGORITHM.md
//! §3): shifted part boundaries, small wrongly labelled blobs, flying pixels, a detached
//! ghost blob, unknown points, depth noise.
//!
//! # Conventions
//! World frame, metres, z up, floor at z = 0; the person stands at `(x, y)` facing +y.
//! The same seed gives the same cloud on every machine (ChaCha8).

use bodyseg_core::math::{Vec3, add, dist2, dot, frame_around_unit_axis, scale, sub};
use bodyseg_core::{Class, Label, LabeledCloud, PersonBox, PointOrigin};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A capsule body segment: axis from `a` to `b`, radius, class.
#[derive(Clone, Copy, Debug)]
pub struct Capsule {
    /// Axis start, metres.
    pub a: Vec3,
    /// Axis end, metres.
    pub b: Vec3,
    /// Radius, metres.
    pub radius_m: f32,
    /// The class its surface belongs to.
    pub class: Class,
}

impl Capsule {
    /// Signed distance from `p` to the capsule surface (negative inside), metres.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        let ab = sub(self.b, self.a);
        let ap = sub(p, self.a);
        let len2 = dot(ab, ab).max(1e-12);
        let t = (dot(ap, ab) / len2).clamp(0.0, 1.0);
        let q = add(self.a, scale(ab, t));
        dist2(p, q).sqrt() - self.radius_m
    }

    fn area(&self) -> f32 {
        let l = dist2(self.a, self.b).sqrt();
        2.0 * std::f32::consts::PI * self.radius_m * l
            + 4.0 * std::f32::consts::PI * self.radius_m * self.radius_m
    }
}

/// A synthetic person: the predicted cloud, its exact truth, and a box around it.
#[derive(Clone, Debug)]
pub struct SyntheticPerson {
    /// Points with predicted labels (with errors); origins are (camera 0, point index).
    pub cloud: LabeledCloud,
    /// The true label of every point (background for floor and flying pixels off the body).
    pub truth: Vec<Label>,
    /// A box holding the whole person plus a margin.
    pub person_box: PersonBox,
    /// The capsules the body was made of.
    pub segments: Vec<Capsule>,
}

/// Fractions of the points given to each kind of sample.
const FLOOR_FRACTION: f32 = 0.08;
const FLYING_FRACTION: f32 = 0.02;
const GHOST_FRACTION: f32 = 0.005;
const UNKNOWN_FRACTION: f32 = 0.01;
/// Depth noise, metres (one sigma), as a Kinect v2 at ~2 m.
const DEPTH_NOISE_M: f32 = 0.003;
/// Width of the band at part boundaries where labels are shuffled, metres.
const BOUNDARY_BAND_M: f32 = 0.025;

/// A standing person (height ≈ 1.75 m · `scale`) at `(x, y)` with seeded arm poses.
pub fn body_segments(rng: &mut ChaCha8Rng, x: f32, y: f32, scale_h: f32) -> Vec<Capsule> {
    let s = scale_h;
    let p = |px: f32, py: f32, pz: f32| [x + px * s, y + py * s, pz * s];
    let mut segs = Vec::new();
    let mut seg = |a: Vec3, b: Vec3, r: f32, class| {
        segs.push(Capsule {
            a,
            b,
            radius_m: r * s,
            class,
        })
    };
    seg(p(0.0, 0.0, 1.62), p(0.0, 0.0, 1.64), 0.105, Class::Head);
    seg(p(0.0, 0.0, 1.44), p(0.0, 0.0, 1.53), 0.055, Class::Head);
    seg(p(-0.05, 0.0, 0.98), p(0.05, 0.0, 1.30), 0.16, Class::Torso);
    for side in [-1.0f32, 1.0] {
        // Arm pose: forward reach and sideways lift, per arm.
        let fwd: f32 = rng.random_range(-0.05..0.35);
        let lift: f32 = rng.random_range(0.0..0.12);
        let sh = p(side * 0.21, 0.0, 1.38);
        let el = p(side * (0.25 + lift), 0.04 + fwd * 0.4, 1.10 + fwd * 0.1);
        let wr = p(side * (0.27 + lift), 0.06 + fwd, 0.88 + fwd * 0.4);
        let ha = [wr[0] + side * 0.01 * s, wr[1] + 0.07 * s, wr[2] - 0.05 * s];
        seg(sh, el, 0.046, Class::UpperArms);
        seg(el, wr, 0.038, Class::LowerArms);
        seg(wr, ha, 0.036, Class::LowerArms);
        let hip = p(side * 0.095, 0.0, 0.90);
        let knee = p(side * 0.11, rng.random_range(-0.03..0.08), 0.50);
        let ankle = p(side * 0.11, 0.0, 0.09);
        let toe = p(side * 0.12, 0.17, 0.04);
        seg(hip, knee, 0.078, Class::UpperLegs);
        seg(knee, ankle, 0.052, Class::LowerLegs);
        seg(ankle, toe, 0.042, Class::LowerLegs);
    }
    segs
}

/// One person of `n_points` points (all kinds together) from `seed`, standing at the origin.
pub fn human_cloud(n_points: usize, seed: u64) -> SyntheticPerson {
    people_cloud(n_points, 1, seed).remove(0)
}

/// `people` persons of `n_points` points each, standing side by side 0.75 m apart (close
/// enough for their boxes to overlap), each returned with its own points; concatenate
/// them with [`concat`] for a scene.
pub fn people_cloud(n_points: usize, people: usize, seed: u64) -> Vec<SyntheticPerson> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..people)
        .map(|k| {
            let x = k as f32 * 0.75;
            let h = rng.random_range(0.88..1.1);
            let segments = body_segments(&mut rng, x, 0.0, h);
            sample_person(&mut rng, segments, n_points, [x, 0.0], h)
        })
        .collect()
}

/// Concatenates people into one scene cloud with its truth (origins renumbered in order).
pub fn concat(people: &[SyntheticPerson]) -> (LabeledCloud, Vec<Label>) {
    let mut cloud = LabeledCloud::default();
    let mut truth = Vec::new();
    for p in people {
        cloud.positions_m.extend_from_slice(&p.cloud.positions_m);
        cloud.labels.extend_from_slice(&p.cloud.labels);
        truth.extend_from_slice(&p.truth);
    }
    cloud.origins = (0..cloud.positions_m.len() as u32)
        .map(|pixel| PointOrigin { camera: 0, pixel })
        .collect();
    (cloud, truth)
}

fn sample_person(
    rng: &mut ChaCha8Rng,
    segments: Vec<Capsule>,
    n_points: usize,
    at: [f32; 2],
    h: f32,
) -> SyntheticPerson {
    let n_floor = (n_points as f32 * FLOOR_FRACTION) as usize;
    let n_fly = (n_points as f32 * FLYING_FRACTION) as usize;
    let n_ghost = (n_points as f32 * GHOST_FRACTION) as usize;
    let n_body = n_points.saturating_sub(n_floor + n_fly + n_ghost);
    let mut pos = Vec::with_capacity(n_points);
    let mut truth = Vec::with_capacity(n_points);
    let mut pred = Vec::with_capacity(n_points);

    // Body surface, uniform by area, hidden (inside another capsule) samples rejected.
    let areas: Vec<f32> = segments.iter().map(Capsule::area).collect();
    let total: f32 = areas.iter().sum();
    let mut tries = 0usize;
    while pos.len() < n_body && tries < n_body * 20 {
        tries += 1;
        let mut pick = rng.random_range(0.0..total);
        let mut si = 0;
        while si + 1 < areas.len() && pick > areas[si] {
            pick -= areas[si];
            si += 1;
        }
        let p = sample_capsule(rng, &segments[si]);
        if segments
            .iter()
            .enumerate()
            .any(|(j, s)| j != si && s.signed_distance(p) < -0.004)
        {
            continue;
        }
        let class = segments[si].class;
        // Boundary band: near another part, the parser picks either side.
        let mut label = Label::from(class);
        for s in &segments {
            if s.class != class
                && s.signed_distance(p) < BOUNDARY_BAND_M
                && rng.random::<f32>() < 0.45
            {
                label = Label::from(s.class);
            }
        }
        pos.push(jitter(rng, p));
        truth.push(Label::from(class));
        pred.push(label);
    }
    // Small wrongly labelled blobs (parser over-segmentation), 2.5–5 cm.
    let n_blobs = 6;
    for _ in 0..n_blobs {
        if pos.is_empty() {
            break;
        }
        let c = pos[rng.random_range(0..pos.len())];
        let r2 = rng.random_range(0.025f32..0.05).powi(2);
        let wrong = Label::from(Class::BODY[rng.random_range(0..6)]);
        for (p, l) in pos.iter().zip(pred.iter_mut()) {
            if dist2(*p, c) < r2 {
                *l = wrong;
            }
        }
    }
    // Floor disc around the feet, background, with a few foot-coloured floor pixels.
    for _ in 0..n_floor {
        let r = 0.55 * rng.random::<f32>().sqrt();
        let a = rng.random_range(0.0..std::f32::consts::TAU);
        let p = [at[0] + r * a.cos(), at[1] + r * a.sin(), 0.0];
        let near_foot = segments
            .iter()
            .any(|s| s.class == Class::LowerLegs && s.signed_distance(p) < 0.03);
        pos.push(jitter(rng, p));
        truth.push(Label::BACKGROUND);
        pred.push(if near_foot && rng.random::<f32>() < 0.6 {
            Label::from(Class::LowerLegs)
        } else {
            Label::BACKGROUND
        });
    }
    // Flying pixels: body points pushed 5–40 cm along a view ray from a camera in front.
    let eye = [at[0], at[1] + 3.0, 1.5 * h];
    for _ in 0..n_fly {
        if n_body == 0 {
            break;
        }
        let k = rng.random_range(0..n_body.min(pos.len()));
        let (p, l) = (pos[k], pred[k]);
        let dir = sub(p, eye);
        let len = dot(dir, dir).sqrt().max(1e-6);
        let d = rng.random_range(0.05..0.4);
        pos.push(add(p, scale(dir, d / len)));
        truth.push(Label::BACKGROUND);
        pred.push(l);
    }
    // A detached ghost blob 0.45 m beside the head, labelled head (an R-step target).
    let ghost = [at[0] + 0.45, at[1] - 0.1, 1.55 * h];
    for _ in 0..n_ghost {
        let p = [
            ghost[0] + rng.random_range(-0.04..0.04),
            ghost[1] + rng.random_range(-0.04..0.04),
            ghost[2] + rng.random_range(-0.04..0.04),
        ];
        pos.push(p);
        truth.push(Label::BACKGROUND);
        pred.push(Label::from(Class::Head));
    }
    // Unknown labels (projection found no reliable label).
    for l in pred.iter_mut() {
        if rng.random::<f32>() < UNKNOWN_FRACTION {
            *l = Label::UNKNOWN;
        }
    }
    let origins = (0..pos.len() as u32)
        .map(|pixel| PointOrigin { camera: 0, pixel })
        .collect();
    let person_box = PersonBox {
        id: 0,
        center_m: [at[0], at[1] + 0.05, 0.95 * h],
        half_extents_m: [0.55, 0.55, 0.95 * h + 0.05],
        yaw_rad: 0.0,
    };
    SyntheticPerson {
        cloud: LabeledCloud {
            positions_m: pos,
            labels: pred,
            colors: None,
            origins,
        },
        truth,
        person_box,
        segments,
    }
}

fn sample_capsule(rng: &mut ChaCha8Rng, s: &Capsule) -> Vec3 {
    let ab = sub(s.b, s.a);
    let l = dot(ab, ab).sqrt();
    let axis = if l > 1e-6 {
        scale(ab, 1.0 / l)
    } else {
        [0.0, 0.0, 1.0]
    };
    // Orthonormal frame around the axis; x and y negated (exactly) keep the points these
    // clouds have always had (they were drawn with u = axis × helper).
    let [x, y, _] = frame_around_unit_axis(axis);
    let (u, v) = (scale(x, -1.0), scale(y, -1.0));
    let cyl = 2.0 * std::f32::consts::PI * s.radius_m * l;
    let caps = 4.0 * std::f32::consts::PI * s.radius_m * s.radius_m;
    if rng.random_range(0.0..cyl + caps) < cyl {
        let t = rng.random_range(0.0..l);
        let a = rng.random_range(0.0..std::f32::consts::TAU);
        let dir = add(scale(u, a.cos()), scale(v, a.sin()));
        add(add(s.a, scale(axis, t)), scale(dir, s.radius_m))
    } else {
        // Uniform direction on the sphere; the hemisphere picks the cap.
        let z: f32 = rng.random_range(-1.0..1.0);
        let a = rng.random_range(0.0..std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let dir = add(
            add(scale(u, r * a.cos()), scale(v, r * a.sin())),
            scale(axis, z),
        );
        let centre = if z >= 0.0 { s.b } else { s.a };
        add(centre, scale(dir, s.radius_m))
    }
}

/// Adds Gaussian depth noise (Box-Muller) to each coordinate.
fn jitter(rng: &mut ChaCha8Rng, p: Vec3) -> Vec3 {
    let mut q = p;
    for c in &mut q {
        let u1: f32 = rng.random_range(1e-7..1.0);
        let u2: f32 = rng.random();
        *c += DEPTH_NOISE_M * (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
    }
    q
}

/// `n` points uniform in a cube of side `side_m`, with labels drawn from `labels` and a
/// share of exact duplicates: the random cases of the DBSCAN property tests.
pub fn random_cloud(
    rng: &mut ChaCha8Rng,
    n: usize,
    side_m: f32,
    labels: &[Label],
    duplicate_fraction: f32,
) -> (Vec<Vec3>, Vec<Label>) {
    let mut pos: Vec<Vec3> = Vec::with_capacity(n);
    let mut lab = Vec::with_capacity(n);
    for _ in 0..n {
        if !pos.is_empty() && rng.random::<f32>() < duplicate_fraction {
            let k = rng.random_range(0..pos.len());
            pos.push(pos[k]);
            lab.push(if rng.random::<bool>() {
                lab[k]
            } else {
                labels[rng.random_range(0..labels.len())]
            });
        } else {
            pos.push([
                rng.random_range(0.0..side_m),
                rng.random_range(0.0..side_m),
                rng.random_range(0.0..side_m),
            ]);
            lab.push(labels[rng.random_range(0..labels.len())]);
        }
    }
    (pos, lab)
}

/// A seeded RNG (ChaCha8), so tests need not depend on rand themselves.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_cloud_is_seeded_and_labelled() {
        let a = human_cloud(5000, 7);
        let b = human_cloud(5000, 7);
        assert_eq!(a.cloud.positions_m, b.cloud.positions_m);
        assert!(a.cloud.validate().is_ok());
        assert!((4900..=5000).contains(&a.cloud.len()));
        // Every body class present in the truth, and predictions differ somewhere.
        for c in Class::BODY {
            assert!(a.truth.contains(&Label::from(c)), "{c} missing");
        }
        let wrong = Label::count_differing(&a.truth, &a.cloud.labels);
        assert!(wrong > 100 && wrong < 2000, "{wrong} wrong labels");
        let inside = a
            .cloud
            .positions_m
            .iter()
            .filter(|&&p| a.person_box.contains(p))
            .count();
        assert!(inside as f32 > 0.97 * a.cloud.len() as f32);
    }
}
