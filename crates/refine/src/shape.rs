//! The limb shape prior (`shape = "limbs"`): after the steps, each limb of the body tree is
//! fitted with a cylinder (axis, radius, axial extent) and points are moved between
//! adjacent parts by how well they fit those cylinders.
//!
//! Why: the remaining errors after M, R and N are bands along the boundaries of adjacent
//! parts (an arm's points labelled torso where the arm lies in front of or beside the torso
//! in the image, an elbow boundary shifted along the arm). Such a band is part of a big
//! cluster of the wrong label, so clustering cannot fix it; the limb's surface can, since a
//! limb is roughly a cylinder and depth cameras see its surface (distance to the axis ≈
//! radius). Nothing here knows a body's dimensions beyond generic bounds on a limb's radius
//! ([`MIN_RADIUS_M`], [`MAX_RADIUS_M`]).
//!
//! Two moves per round, each decided from the labels the round started with (no order
//! dependence within a round):
//! - *capture*: a torso point on the surface of an upper limb's cylinder (radial residual
//!   within tolerance, inside the limb's fitted axial extent, not on the side of the limb
//!   that faces the torso's axis, where the torso's own surface touches the cylinder)
//!   takes the limb's label;
//! - *joint*: where an upper and a lower limb of one chain are both fitted and bent (axes
//!   at least [`MIN_BEND_RAD`] apart), their axes meet at the joint; points of either label
//!   near it take the label of the side of the bisecting plane they lie on, when they fit
//!   that side's cylinder. (A straight limb's joint is not located by its shape: nothing
//!   moves there.)
//!
//! A limb is fitted on its tree node's points (and, in later rounds, the points it
//! captured) with a trimmed fit; a fit most of whose points do not lie on it (a cluster
//! holding both legs, a forearm with the hand bent off) is not used.
//!
//! [`floor_contact`] is a separate prior (`floor_contact_m`): lower-leg points on the floor
//! are the floor.
//!
//! Honesty note: the synthetic people of `bodyseg-synth` are built from capsules and
//! ellipsoids, so a cylinder prior fits them unusually well. Real limbs are roughly
//! cylindrical too, and nothing here uses synth's shapes or sizes (only generic radius
//! bounds), but expect a smaller effect on real bodies and loose clothing.

use crate::dbscan::Clustering;
use crate::graph::{BodyTree, TEMPLATE};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label};

/// Smallest plausible limb radius, metres (a thin forearm is ~3 cm); fits below it are
/// rejected as degenerate.
pub const MIN_RADIUS_M: f64 = 0.015;
/// Largest plausible limb radius, metres (a thick thigh is ~10 cm).
pub const MAX_RADIUS_M: f64 = 0.15;
/// Fewest points a limb cluster needs to be fitted.
pub const MIN_FIT_POINTS: usize = 40;
/// Smallest bend between an upper and a lower limb's axes for their joint to be located
/// (a straight limb's joint is not determined by its shape), radians (25°).
pub const MIN_BEND_RAD: f64 = 0.436;

/// A fitted limb: a cylinder of `radius_m` around the line `origin + t · dir`, holding its
/// points between `t_lo` and `t_hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimbFit {
    /// A point of the axis, metres, the cloud's frame.
    pub origin_m: [f64; 3],
    /// Unit direction of the axis.
    pub dir: [f64; 3],
    /// Radius, metres.
    pub radius_m: f64,
    /// Axial extent of the fitted points (trimmed quantiles), metres along `dir`.
    pub t_lo_m: f64,
    /// See `t_lo_m`.
    pub t_hi_m: f64,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    (n > 1e-12).then(|| scale(a, 1.0 / n))
}
fn f64v(p: Vec3) -> [f64; 3] {
    [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
}

impl LimbFit {
    /// Axial coordinate and distance to the axis of `p`, and the unit vector from the axis
    /// to `p` (`None` on the axis).
    pub fn locate(&self, p: [f64; 3]) -> (f64, f64, Option<[f64; 3]>) {
        let v = sub(p, self.origin_m);
        let t = dot(v, self.dir);
        let radial = sub(v, scale(self.dir, t));
        let rho = norm(radial);
        (t, rho, unit(radial))
    }

    /// The point of the axis at `t`.
    pub fn at(&self, t: f64) -> [f64; 3] {
        add(self.origin_m, scale(self.dir, t))
    }
}

/// Mean and principal direction (largest eigenvector of the covariance, by power
/// iteration from the axis of largest variance) of `pts`.
fn principal_axis(pts: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let n = pts.len() as f64;
    if pts.len() < 3 {
        return None;
    }
    let mut c = [0.0; 3];
    for p in pts {
        c = add(c, *p);
    }
    c = scale(c, 1.0 / n);
    let mut m = [[0.0; 3]; 3];
    for p in pts {
        let d = sub(*p, c);
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += d[i] * d[j];
            }
        }
    }
    let start = (0..3)
        .max_by(|&a, &b| m[a][a].total_cmp(&m[b][b]))
        .unwrap_or(0);
    let mut v = [0.0; 3];
    v[start] = 1.0;
    for _ in 0..50 {
        let w = [dot(m[0], v), dot(m[1], v), dot(m[2], v)];
        v = unit(w)?;
    }
    Some((c, v))
}

/// Circle through 2D points by the algebraic (Kåsa) least-squares fit: centre and radius.
fn fit_circle(xy: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    // Minimise Σ (x² + y² + D x + E y + F)²: normal equations of a 3×3 system.
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for &[x, y] in xy {
        let row = [x, y, 1.0];
        let z = -(x * x + y * y);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * z;
        }
    }
    let s = solve3(a, b)?;
    let (cx, cy) = (-s[0] / 2.0, -s[1] / 2.0);
    let r2 = cx * cx + cy * cy - s[2];
    (r2 > 0.0).then(|| ([cx, cy], r2.sqrt()))
}

/// Solves `a x = b` by Cramer's rule; `None` when (nearly) singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = dot(a[0], cross(a[1], a[2]));
    let scale_ = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if det.abs() <= 1e-12 * scale_.powi(3) || scale_ == 0.0 {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        *xk = dot(m[0], cross(m[1], m[2])) / det;
    }
    Some(x)
}

/// Value at quantile `q` in [0, 1] of `v` (reorders `v`).
fn quantile(v: &mut [f64], q: f64) -> f64 {
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Fits a cylinder to a limb's surface points: the axis direction by PCA, the cross-section
/// by a circle fit in the plane perpendicular to it, then refitted (direction and circle)
/// on the `params.keep` fraction of points with the smallest radial residual, twice, so that
/// a band of another part's surface inside the cluster does not bias it. `None` when too
/// few points, not elongated (axial extent under 2 radii: the direction is meaningless), a
/// radius outside [`MIN_RADIUS_M`, `MAX_RADIUS_M`], or fewer than `params.min_within` of the
/// points within the radial tolerance of the surface.
pub fn fit_limb(points_m: &[Vec3], params: &ShapeParams) -> Option<LimbFit> {
    let keep = params.keep;
    if points_m.len() < MIN_FIT_POINTS {
        return None;
    }
    let all: Vec<[f64; 3]> = points_m.iter().map(|&p| f64v(p)).collect();
    let mut inliers = all.clone();
    let mut fit = None;
    for round in 0..3 {
        let (c, dir) = principal_axis(&inliers)?;
        // A basis of the cross-section plane.
        let helper = if dir[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let e1 = unit(cross(dir, helper))?;
        let e2 = cross(dir, e1);
        let xy: Vec<[f64; 2]> = inliers
            .iter()
            .map(|p| {
                let d = sub(*p, c);
                [dot(d, e1), dot(d, e2)]
            })
            .collect();
        let (centre, radius) = fit_circle(&xy)?;
        let origin = add(c, add(scale(e1, centre[0]), scale(e2, centre[1])));
        let f = LimbFit {
            origin_m: origin,
            dir,
            radius_m: radius,
            t_lo_m: 0.0,
            t_hi_m: 0.0,
        };
        fit = Some(f);
        if round == 2 {
            break;
        }
        // Keep the points nearest the fitted surface.
        let mut by_residual: Vec<(f64, [f64; 3])> = all
            .iter()
            .map(|&p| ((f.locate(p).1 - radius).abs(), p))
            .collect();
        let n_keep = ((all.len() as f64 * keep).ceil() as usize).clamp(3, all.len());
        by_residual.select_nth_unstable_by(n_keep - 1, |a, b| a.0.total_cmp(&b.0));
        inliers = by_residual[..n_keep].iter().map(|x| x.1).collect();
    }
    let mut f = fit?;
    if !(MIN_RADIUS_M..=MAX_RADIUS_M).contains(&f.radius_m) {
        return None;
    }
    let tol = (params.tol_ratio * f.radius_m).max(params.min_tol_m);
    let within = all
        .iter()
        .filter(|&&p| (f.locate(p).1 - f.radius_m).abs() <= tol)
        .count();
    if (within as f64) < params.min_within * all.len() as f64 {
        return None;
    }
    let mut ts: Vec<f64> = inliers.iter().map(|&p| f.locate(p).0).collect();
    f.t_lo_m = quantile(&mut ts, 0.02);
    f.t_hi_m = quantile(&mut ts, 0.98);
    if f.t_hi_m - f.t_lo_m < 2.0 * f.radius_m {
        return None;
    }
    Some(f)
}

/// Knobs of the shape prior (from [`crate::RefineConfig`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeParams {
    /// A point fits a limb when its distance to the axis is within this fraction of the
    /// radius of it (at least `min_tol_m`).
    pub tol_ratio: f64,
    /// Floor of the radial tolerance, metres (depth noise).
    pub min_tol_m: f64,
    /// Fraction of a limb's points kept by the trimmed fit.
    pub keep: f64,
    /// Radius of the joint zone, in radii of the upper limb.
    pub joint_zone: f64,
    /// A fit is kept only when at least this fraction of its points lie on its surface
    /// (within the radial tolerance): a cluster that is no single limb (both legs, a limb
    /// with a hand or foot bent off it) fits no cylinder well.
    pub min_within: f64,
    /// A torso point is not captured when the direction from the limb's axis to it lies
    /// within this cosine of the direction to the torso's axis.
    pub facing_cos: f64,
    /// Fit → move rounds.
    pub rounds: usize,
}

impl Default for ShapeParams {
    fn default() -> Self {
        ShapeParams {
            tol_ratio: 0.25,
            min_tol_m: 0.01,
            keep: 0.7,
            joint_zone: 3.0,
            min_within: 0.6,
            facing_cos: 0.5,
            rounds: 2,
        }
    }
}

/// Whether slot `s` of [`TEMPLATE`] is a limb (the head slot 0 is not).
fn is_limb_slot(s: usize) -> bool {
    s > 0
}

/// The limb shape prior on one person's final labels (see the module docs): returns the
/// new labels. `clustering` and `tree` give each limb's points to start from (the tree
/// node's cluster); each round refits every limb on its points (those it started with that
/// kept its label, and those it captured) and moves points again.
pub fn limb_shape_prior(
    positions_m: &[Vec3],
    labels: &[Label],
    clustering: &Clustering,
    tree: &BodyTree,
    params: &ShapeParams,
) -> Vec<Label> {
    let mut out = labels.to_vec();
    let Some(root) = tree.root else {
        return out;
    };
    // Per point, the tree slot it belongs to (`ROOT` for the torso root's points).
    const ROOT: u8 = u8::MAX - 1;
    const NONE: u8 = u8::MAX;
    let mut slot_of_cluster = vec![NONE; clustering.num_clusters()];
    slot_of_cluster[root as usize] = ROOT;
    for (s, c) in tree.slots.iter().enumerate() {
        if let Some(c) = *c {
            slot_of_cluster[c as usize] = s as u8;
        }
    }
    let mut owner: Vec<u8> = clustering
        .cluster_of
        .iter()
        .map(|c| c.map_or(NONE, |c| slot_of_cluster[c as usize]))
        .collect();
    let torso_pts: Vec<[f64; 3]> = owner
        .iter()
        .zip(positions_m)
        .filter(|(o, _)| **o == ROOT)
        .map(|(_, &p)| f64v(p))
        .collect();
    let Some((torso_c, torso_dir)) = principal_axis(&torso_pts) else {
        return out;
    };
    let torso = Label::from(Class::Torso);
    let tol = |f: &LimbFit| (params.tol_ratio * f.radius_m).max(params.min_tol_m);
    for _ in 0..params.rounds {
        let before = out.clone();
        let mut fits: [Option<LimbFit>; 9] = [None; 9];
        for (s, fit) in fits.iter_mut().enumerate() {
            if !is_limb_slot(s) || tree.slots[s].is_none() {
                continue;
            }
            let want = Label::from(TEMPLATE[s].class);
            let pts: Vec<Vec3> = owner
                .iter()
                .zip(positions_m)
                .zip(&before)
                .filter(|((o, _), l)| usize::from(**o) == s && **l == want)
                .map(|((_, &p), _)| p)
                .collect();
            *fit = fit_limb(&pts, params);
        }

        // Capture: torso points on an upper limb's surface.
        for (s, slot) in TEMPLATE.iter().enumerate() {
            let Some(f) = fits[s] else { continue };
            if slot.parent.is_some() {
                continue;
            }
            let limb = Label::from(slot.class);
            let t = tol(&f);
            for (i, &l) in before.iter().enumerate() {
                if l != torso || out[i] != torso {
                    continue;
                }
                let p = f64v(positions_m[i]);
                let (ti, rho, u) = f.locate(p);
                if ti < f.t_lo_m || ti > f.t_hi_m || (rho - f.radius_m).abs() > t {
                    continue;
                }
                // Not the side of the limb facing the torso's axis (there the torso's own
                // surface touches the limb's cylinder).
                let a = f.at(ti);
                let to_axis = sub(torso_c, a);
                let to_axis = sub(to_axis, scale(torso_dir, dot(to_axis, torso_dir)));
                let to_axis = sub(to_axis, scale(f.dir, dot(to_axis, f.dir)));
                if let (Some(u), Some(w)) = (u, unit(to_axis))
                    && dot(u, w) > params.facing_cos
                {
                    continue;
                }
                out[i] = limb;
                owner[i] = s as u8;
            }
        }

        // Joints: an upper and a lower limb of one chain, bent.
        for (s, slot) in TEMPLATE.iter().enumerate() {
            let Some(parent) = slot.parent else { continue };
            let (Some(fu), Some(fl)) = (fits[parent], fits[s]) else {
                continue;
            };
            let upper = Label::from(TEMPLATE[parent].class);
            let lower = Label::from(slot.class);
            let Some((joint, n)) = joint_of(&fu, &fl) else {
                continue;
            };
            let zone = params.joint_zone * fu.radius_m;
            for (i, &l) in before.iter().enumerate() {
                let o = usize::from(owner[i]);
                if !((l == upper && o == parent) || (l == lower && o == s)) {
                    continue;
                }
                let p = f64v(positions_m[i]);
                if norm(sub(p, joint)) > zone {
                    continue;
                }
                let (want, to, f) = if dot(sub(p, joint), n) > 0.0 {
                    (lower, s, &fl)
                } else {
                    (upper, parent, &fu)
                };
                if want == l {
                    continue;
                }
                let (_, rho, _) = f.locate(p);
                if (rho - f.radius_m).abs() <= tol(f) {
                    out[i] = want;
                    owner[i] = to as u8;
                }
            }
        }
    }
    out
}

/// Where the axes of a bent upper limb `fu` and its lower limb `fl` meet: the joint and
/// the normal of the plane bisecting the bend (pointing to the lower limb). `None` when
/// the limb is nearly straight (bend under [`MIN_BEND_RAD`]: the shape does not locate the
/// joint) or the axes pass far from each other.
fn joint_of(fu: &LimbFit, fl: &LimbFit) -> Option<([f64; 3], [f64; 3])> {
    // Orient both axes away from the torso: the upper towards the lower limb, the lower
    // away from the upper.
    let mid = |f: &LimbFit| f.at(0.5 * (f.t_lo_m + f.t_hi_m));
    let along = sub(mid(fl), mid(fu));
    let orient = |d: [f64; 3]| {
        if dot(along, d) >= 0.0 {
            d
        } else {
            scale(d, -1.0)
        }
    };
    let (du, dl) = (orient(fu.dir), orient(fl.dir));
    let b = dot(du, dl).clamp(-1.0, 1.0);
    if b.acos() < MIN_BEND_RAD {
        return None;
    }
    // Closest points of the two axes: the joint is their midpoint.
    let w0 = sub(fu.origin_m, fl.origin_m);
    let (d, e) = (dot(du, w0), dot(dl, w0));
    let den = 1.0 - b * b;
    let su = (b * e - d) / den;
    let sl = (e - b * d) / den;
    let pu = add(fu.origin_m, scale(du, su));
    let pl = add(fl.origin_m, scale(dl, sl));
    if norm(sub(pu, pl)) > 2.0 * fu.radius_m.max(fl.radius_m) {
        return None;
    }
    let joint = scale(add(pu, pl), 0.5);
    // The joint must lie near an end of each limb (within two radii and half the limb's
    // length: the labels' boundary may be shifted from the joint by that much), not far
    // along the axes' lines.
    let (tu, _, _) = fu.locate(joint);
    let (tl, _, _) = fl.locate(joint);
    let near_end = |f: &LimbFit, t: f64| {
        let m = 2.0 * f.radius_m + 0.5 * (f.t_hi_m - f.t_lo_m);
        (t - f.t_lo_m).abs().min((t - f.t_hi_m).abs()) <= m
    };
    if !(near_end(fu, tu) && near_end(fl, tl)) {
        return None;
    }
    Some((joint, unit(add(du, dl))?))
}

/// Lower-leg points lying on the floor become background: a foot's visible surface is
/// above the floor (its sole faces down), so a lower-leg point within `floor_tol_m` of the
/// floor is the floor around the foot, which the 2D parser's leg label bleeds onto. The
/// floor height is the median height of the person's background points lying no higher
/// than [`FLOOR_BAND_M`] above its lowest body points (the [`LOW_BODY_QUANTILE`] of the body
/// points' heights, so that a stray point below the floor does not set it); without
/// [`MIN_FLOOR_POINTS`] of them nothing changes. World z is up (ALGORITHM.md §0).
pub fn floor_contact(positions_m: &[Vec3], labels: &[Label], floor_tol_m: f32) -> Vec<Label> {
    let mut out = labels.to_vec();
    let mut body_z: Vec<f64> = positions_m
        .iter()
        .zip(labels)
        .filter(|(_, l)| l.is_body())
        .map(|(p, _)| f64::from(p[2]))
        .collect();
    if body_z.is_empty() {
        return out;
    }
    let lowest_body = quantile(&mut body_z, LOW_BODY_QUANTILE) as f32;
    let mut floor: Vec<f64> = positions_m
        .iter()
        .zip(labels)
        .filter(|(p, l)| **l == Label::BACKGROUND && p[2] <= lowest_body + FLOOR_BAND_M)
        .map(|(p, _)| f64::from(p[2]))
        .collect();
    if floor.len() < MIN_FLOOR_POINTS {
        return out;
    }
    let floor_z = quantile(&mut floor, 0.5) as f32;
    let lower_legs = Label::from(Class::LowerLegs);
    for (l, p) in out.iter_mut().zip(positions_m) {
        if *l == lower_legs && p[2] <= floor_z + floor_tol_m {
            *l = Label::BACKGROUND;
        }
    }
    out
}

/// Floor contact: the quantile of the body points' heights taken as the person's lowest.
pub const LOW_BODY_QUANTILE: f64 = 0.005;
/// Floor contact: background points at most this far above the person's lowest body points
/// are taken as the floor, metres.
pub const FLOOR_BAND_M: f32 = 0.05;
/// Floor contact: fewest floor points for a floor height.
pub const MIN_FLOOR_POINTS: usize = 50;

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a cylinder's surface around the z axis through `base`.
    fn cylinder(base: Vec3, radius: f32, len: f32, pitch: f32) -> Vec<Vec3> {
        let mut out = Vec::new();
        let steps = (len / pitch) as i32;
        let around = ((std::f32::consts::TAU * radius) / pitch) as i32;
        for i in 0..=steps {
            for j in 0..around {
                let a = j as f32 / around as f32 * std::f32::consts::TAU;
                out.push([
                    base[0] + radius * a.cos(),
                    base[1] + radius * a.sin(),
                    base[2] + i as f32 * pitch,
                ]);
            }
        }
        out
    }

    #[test]
    fn the_floor_height_comes_from_the_persons_background_points() {
        // A floor at z = 0.1 m (not 0: it is measured), a stray body point far below it,
        // and two lower-leg points: 3 mm and 3 cm above the floor.
        let mut pos: Vec<Vec3> = (0..100).map(|i| [i as f32 * 0.01, 0.0, 0.1]).collect();
        let mut lab = vec![Label::BACKGROUND; pos.len()];
        let leg = Label::from(Class::LowerLegs);
        pos.extend([[0.0, 0.1, -0.5], [0.0, 0.2, 0.103], [0.0, 0.3, 0.13]]);
        lab.extend([leg; 3]);
        // More body points, so that the stray one is below the low quantile.
        pos.extend((0..400).map(|i| [0.5, 0.5, 0.2 + i as f32 * 0.002]));
        lab.extend(vec![leg; 400]);
        let out = floor_contact(&pos, &lab, 0.006);
        assert_eq!(out[101], Label::BACKGROUND, "3 mm above the floor");
        assert_eq!(out[102], leg, "3 cm above the floor");
        assert!(out[103..].iter().all(|&l| l == leg));
    }

    #[test]
    fn a_cylinder_fits_its_axis_and_radius() {
        let pts = cylinder([0.3, -0.2, 1.0], 0.05, 0.3, 0.01);
        let f = fit_limb(&pts, &ShapeParams::default()).expect("a fit");
        // Exact data: the fit is exact up to float rounding (1 mm).
        assert!((f.radius_m - 0.05).abs() < 1e-3, "{f:?}");
        assert!(f.dir[2].abs() > 0.999, "{f:?}");
        let (_, rho, _) = f.locate([0.3, -0.2, 1.1]);
        assert!(rho < 1e-3, "{f:?}");
    }
}
