//! Ray casting against a frame's primitives: exact nearest hit, its normal and owner.
//!
//! Cost control: primitives are grouped (one group per person or object) and each group's
//! world AABB is projected once per camera and frame onto the camera's normalised image
//! plane (undistorted `x/z, y/z`). A pixel's ray only tests the groups whose projected
//! rectangle holds the pixel's own undistorted ray; that bound is exact (a ray through the
//! box passes through its projection, which lies in the corners' bounding rectangle), so
//! culling never changes a hit. Floor and walls are analytic planes.

use crate::geometry::{
    Material, Owner, Primitive, Shape, V3, add, cross, dot, normalize, scale, sub,
};

/// Height of the walls, metres.
pub const WALL_HEIGHT_M: f32 = 3.0;

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray, metres.
    pub t: f32,
    /// Unit surface normal, facing the ray's origin.
    pub normal: V3,
    /// Ground truth of the surface.
    pub owner: Owner,
    /// How it looks.
    pub material: Material,
}

/// The analytic room: a floor at z = 0 and four walls at `|x| = half`, `|y| = half`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Room {
    /// Floor material, `None` = no floor.
    pub floor: Option<Material>,
    /// Wall material, `None` = no walls.
    pub walls: Option<Material>,
    /// Half side of the square room, metres.
    pub half_m: f32,
}

/// A contiguous run of primitives with their common AABB.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Group {
    lo: V3,
    hi: V3,
    start: usize,
    end: usize,
}

/// The world of one instant: room plus grouped primitives.
#[derive(Clone, Debug, Default)]
pub struct World {
    prims: Vec<Primitive>,
    groups: Vec<Group>,
    room: Option<Room>,
}

impl World {
    /// An empty world with `room`.
    pub fn new(room: Option<Room>) -> Self {
        World {
            prims: Vec::new(),
            groups: Vec::new(),
            room,
        }
    }

    /// Adds a group of primitives (one person, one object) culled together.
    pub fn add_group(&mut self, prims: &[Primitive]) {
        if prims.is_empty() {
            return;
        }
        let start = self.prims.len();
        let (mut lo, mut hi) = prims[0].shape.aabb();
        for p in prims {
            let (l, h) = p.shape.aabb();
            for i in 0..3 {
                lo[i] = lo[i].min(l[i]);
                hi[i] = hi[i].max(h[i]);
            }
        }
        self.prims.extend_from_slice(prims);
        self.groups.push(Group {
            lo,
            hi,
            start,
            end: self.prims.len(),
        });
    }

    /// Every primitive, in insertion order.
    pub fn primitives(&self) -> &[Primitive] {
        &self.prims
    }

    /// The room, if any.
    pub fn room(&self) -> Option<Room> {
        self.room
    }

    /// For one camera at `origin` with world-to-camera rotation `camera_from_world`
    /// (rows = camera axes in world coordinates): per group and per primitive, the
    /// rectangle of its AABB on the normalised image plane.
    pub fn cull_rects(&self, origin: V3, camera_from_world: [V3; 3]) -> CullRects {
        CullRects {
            groups: self
                .groups
                .iter()
                .map(|g| image_rect(g.lo, g.hi, origin, camera_from_world))
                .collect(),
            prims: self
                .prims
                .iter()
                .map(|p| {
                    let (lo, hi) = p.shape.aabb();
                    image_rect(lo, hi, origin, camera_from_world)
                })
                .collect(),
        }
    }

    /// The nearest hit of the ray `origin + t·dir` (`dir` unit), `t > 0`; `image_xy` is the
    /// ray's undistorted normalised image coordinate, tested against `rects` (from
    /// [`World::cull_rects`] for the same camera).
    pub fn cast(&self, origin: V3, dir: V3, image_xy: [f32; 2], rects: &CullRects) -> Option<Hit> {
        let [x, y] = image_xy;
        let mut candidates = Vec::new();
        self.candidates(rects, [x, x, y, y], &mut candidates);
        self.cast_among(origin, dir, image_xy, rects, &candidates)
    }

    /// The primitives whose rectangle overlaps `bound` (`[x_min, x_max, y_min, y_max]`
    /// on the same camera's normalised image plane), into `out` (cleared first): the
    /// only ones a ray through `bound` can hit. Renderers compute them once per span of
    /// pixels.
    pub fn candidates(&self, rects: &CullRects, bound: [f32; 4], out: &mut Vec<u32>) {
        out.clear();
        let overlaps = |r: &[f32; 4]| {
            r[0] <= bound[1] && r[1] >= bound[0] && r[2] <= bound[3] && r[3] >= bound[2]
        };
        for (g, r) in self.groups.iter().zip(&rects.groups) {
            if !overlaps(r) {
                continue;
            }
            for i in g.start..g.end {
                if overlaps(&rects.prims[i]) {
                    out.push(i as u32);
                }
            }
        }
    }

    /// [`World::cast`] testing only `candidates` (from [`World::candidates`] for a bound
    /// that holds `image_xy`): the same hit, fewer tests.
    pub fn cast_among(
        &self,
        origin: V3,
        dir: V3,
        image_xy: [f32; 2],
        rects: &CullRects,
        candidates: &[u32],
    ) -> Option<Hit> {
        let mut best_t = f32::INFINITY;
        let mut best: Option<(usize, f32)> = None;
        let [x, y] = image_xy;
        for &i in candidates {
            let i = i as usize;
            let r = &rects.prims[i];
            if x < r[0] || x > r[1] || y < r[2] || y > r[3] {
                continue;
            }
            if let Some(t) = intersect(&self.prims[i].shape, origin, dir)
                && t < best_t
            {
                best_t = t;
                best = Some((i, t));
            }
        }
        let room_hit = self
            .room
            .and_then(|room| cast_room(&room, origin, dir, best_t));
        if let Some(hit) = room_hit {
            return Some(hit);
        }
        let (i, t) = best?;
        let prim = &self.prims[i];
        let p = add(origin, scale(dir, t));
        let mut normal = shape_normal(&prim.shape, p);
        if dot(normal, dir) > 0.0 {
            normal = scale(normal, -1.0);
        }
        Some(Hit {
            t,
            normal,
            owner: prim.owner,
            material: prim.material,
        })
    }
}

/// Per group and per primitive of a [`World`], its rectangle
/// `[x_min, x_max, y_min, y_max]` on one camera's normalised image plane.
#[derive(Clone, Debug, PartialEq)]
pub struct CullRects {
    groups: Vec<[f32; 4]>,
    prims: Vec<[f32; 4]>,
}

impl CullRects {
    /// Rectangles that cull nothing, for `world` (tests, references).
    pub fn unbounded(world: &World) -> Self {
        let all = [
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
        ];
        CullRects {
            groups: vec![all; world.groups.len()],
            prims: vec![all; world.prims.len()],
        }
    }
}

/// The bounding rectangle of the box `[lo, hi]` on the normalised image plane of a
/// camera; unbounded when a corner is behind or near the camera.
fn image_rect(lo: V3, hi: V3, origin: V3, camera_from_world: [V3; 3]) -> [f32; 4] {
    let mut r = [
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    for c in 0..8 {
        let p = [
            if c & 1 == 0 { lo[0] } else { hi[0] },
            if c & 2 == 0 { lo[1] } else { hi[1] },
            if c & 4 == 0 { lo[2] } else { hi[2] },
        ];
        let d = sub(p, origin);
        let z = dot(camera_from_world[2], d);
        if z < 0.05 {
            return [
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
            ];
        }
        let x = dot(camera_from_world[0], d) / z;
        let y = dot(camera_from_world[1], d) / z;
        r[0] = r[0].min(x);
        r[1] = r[1].max(x);
        r[2] = r[2].min(y);
        r[3] = r[3].max(y);
    }
    // Widen by a small margin so that rounding never culls a grazing hit.
    let pad = 1e-4;
    [r[0] - pad, r[1] + pad, r[2] - pad, r[3] + pad]
}

/// Nearest floor or wall hit closer than `t_max`.
fn cast_room(room: &Room, o: V3, d: V3, t_max: f32) -> Option<Hit> {
    let h = room.half_m;
    let mut best: Option<Hit> = None;
    let mut best_t = t_max;
    if let Some(material) = room.floor
        && d[2] < 0.0
    {
        let t = -o[2] / d[2];
        if t > 0.0 && t < best_t {
            let p = add(o, scale(d, t));
            if p[0].abs() <= h && p[1].abs() <= h {
                best_t = t;
                best = Some(Hit {
                    t,
                    normal: [0.0, 0.0, 1.0],
                    owner: Owner::Scene,
                    material,
                });
            }
        }
    }
    if let Some(material) = room.walls {
        for axis in 0..2 {
            if d[axis] == 0.0 {
                continue;
            }
            let wall = if d[axis] > 0.0 { h } else { -h };
            let t = (wall - o[axis]) / d[axis];
            if t > 0.0 && t < best_t {
                let p = add(o, scale(d, t));
                if p[1 - axis].abs() <= h && p[2] >= 0.0 && p[2] <= WALL_HEIGHT_M {
                    best_t = t;
                    let mut normal = [0.0; 3];
                    normal[axis] = -d[axis].signum();
                    best = Some(Hit {
                        t,
                        normal,
                        owner: Owner::Scene,
                        material,
                    });
                }
            }
        }
    }
    best
}

/// Smallest positive ray parameter where the unit ray `o + t·d` enters `shape`.
/// Rays starting inside a shape (never the case for cameras) report no hit.
pub fn intersect(shape: &Shape, o: V3, d: V3) -> Option<f32> {
    const T_MIN: f32 = 1e-4;
    let t = match *shape {
        Shape::Capsule { a, b, radius } => capsule(o, d, a, b, radius),
        Shape::Cylinder { a, b, radius } => cylinder(o, d, a, b, radius),
        Shape::Ellipsoid {
            center,
            axes,
            radii,
        } => ellipsoid(o, d, center, axes, radii),
        Shape::Box { center, axes, half } => oriented_box(o, d, center, axes, half),
    }?;
    (t > T_MIN && t.is_finite()).then_some(t)
}

// Capsule: the classic quadratic for the infinite cylinder, then the two end spheres
// (Inigo Quilez's formulation).
fn capsule(o: V3, d: V3, a: V3, b: V3, r: f32) -> Option<f32> {
    let (oa, baba, bard, baoa) = axis_terms(o, d, a, b);
    let rdoa = dot(d, oa);
    let oaoa = dot(oa, oa);
    let qa = baba - bard * bard;
    let qb = baba * rdoa - baoa * bard;
    let qc = baba * oaoa - baoa * baoa - r * r * baba;
    let h = qb * qb - qa * qc;
    if h < 0.0 {
        return None;
    }
    if qa > 1e-12 {
        let t = (-qb - h.sqrt()) / qa;
        let y = baoa + t * bard;
        if y > 0.0 && y < baba {
            return Some(t);
        }
        let oc = if y <= 0.0 { oa } else { sub(o, b) };
        return sphere(oc, d, r);
    }
    // Ray parallel to the axis: only the caps can be hit first.
    let ta = sphere(oa, d, r);
    let tb = sphere(sub(o, b), d, r);
    match (ta, tb) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}

/// Entry of the unit ray into the sphere of radius `r` centred at the origin, with the
/// ray origin given relative to the centre.
fn sphere(oc: V3, d: V3, r: f32) -> Option<f32> {
    let b = dot(oc, d);
    let c = dot(oc, oc) - r * r;
    let h = b * b - c;
    if h < 0.0 {
        return None;
    }
    Some(-b - h.sqrt())
}

/// What the capsule and the cylinder tests start from, for the axis `ba = b − a`: the ray
/// origin relative to `a` (`oa`), and `ba·ba`, `ba·d`, `ba·oa`.
fn axis_terms(o: V3, d: V3, a: V3, b: V3) -> (V3, f32, f32, f32) {
    let ba = sub(b, a);
    let oa = sub(o, a);
    (oa, dot(ba, ba), dot(ba, d), dot(ba, oa))
}

fn cylinder(o: V3, d: V3, a: V3, b: V3, r: f32) -> Option<f32> {
    let (oc, baba, bard, baoc) = axis_terms(o, d, a, b);
    let k2 = baba - bard * bard;
    let k1 = baba * dot(oc, d) - baoc * bard;
    let k0 = baba * dot(oc, oc) - baoc * baoc - r * r * baba;
    if k2.abs() > 1e-12 {
        let h = k1 * k1 - k2 * k0;
        if h < 0.0 {
            return None;
        }
        let h = h.sqrt();
        let t = (-k1 - h) / k2;
        let y = baoc + t * bard;
        if y > 0.0 && y < baba {
            return Some(t);
        }
        if bard == 0.0 {
            return None;
        }
        let t = (if y < 0.0 { 0.0 } else { baba } - baoc) / bard;
        if (k1 + k2 * t).abs() < h {
            return Some(t);
        }
        return None;
    }
    // Ray parallel to the axis: hits a cap if it runs inside the radius.
    if k0 > 0.0 || bard == 0.0 {
        return None;
    }
    let t0 = (0.0 - baoc) / bard;
    let t1 = (baba - baoc) / bard;
    Some(t0.min(t1))
}

fn ellipsoid(o: V3, d: V3, c: V3, axes: [V3; 3], radii: V3) -> Option<f32> {
    let oc = sub(o, c);
    let mut ol = [0.0; 3];
    let mut dl = [0.0; 3];
    for i in 0..3 {
        ol[i] = dot(oc, axes[i]) / radii[i];
        dl[i] = dot(d, axes[i]) / radii[i];
    }
    let a = dot(dl, dl);
    let b = dot(ol, dl);
    let cc = dot(ol, ol) - 1.0;
    let h = b * b - a * cc;
    if h < 0.0 {
        return None;
    }
    Some((-b - h.sqrt()) / a)
}

fn oriented_box(o: V3, d: V3, c: V3, axes: [V3; 3], half: V3) -> Option<f32> {
    let oc = sub(o, c);
    let mut t_near = f32::NEG_INFINITY;
    let mut t_far = f32::INFINITY;
    for i in 0..3 {
        let ol = dot(oc, axes[i]);
        let dl = dot(d, axes[i]);
        if dl.abs() < 1e-12 {
            if ol.abs() > half[i] {
                return None;
            }
            continue;
        }
        let t1 = (-half[i] - ol) / dl;
        let t2 = (half[i] - ol) / dl;
        t_near = t_near.max(t1.min(t2));
        t_far = t_far.min(t1.max(t2));
    }
    if t_near > t_far || t_far < 0.0 {
        return None;
    }
    Some(t_near)
}

/// Outward unit normal of `shape` at a surface point `p`.
pub fn shape_normal(shape: &Shape, p: V3) -> V3 {
    match *shape {
        Shape::Capsule { a, b, .. } => {
            let ba = sub(b, a);
            let pa = sub(p, a);
            let h = (dot(pa, ba) / dot(ba, ba).max(1e-12)).clamp(0.0, 1.0);
            normalize(sub(pa, scale(ba, h)))
        }
        Shape::Cylinder { a, b, radius } => {
            let ba = sub(b, a);
            let baba = dot(ba, ba).max(1e-12);
            let pa = sub(p, a);
            let y = dot(pa, ba) / baba;
            let radial = sub(pa, scale(ba, y));
            // The surface point is on whichever face it is closest to: the side at the
            // radius or a cap at an axis end.
            let side_dist = (dot(radial, radial).sqrt() - radius).abs();
            let cap_dist = y.min(1.0 - y).abs() * baba.sqrt();
            if cap_dist < side_dist {
                let n = normalize(ba);
                if y < 0.5 { scale(n, -1.0) } else { n }
            } else {
                normalize(radial)
            }
        }
        Shape::Ellipsoid {
            center,
            axes,
            radii,
        } => {
            let pc = sub(p, center);
            let mut n = [0.0; 3];
            for i in 0..3 {
                let l = dot(pc, axes[i]) / (radii[i] * radii[i]);
                n = add(n, scale(axes[i], l));
            }
            normalize(n)
        }
        Shape::Box { center, axes, half } => {
            let pc = sub(p, center);
            let mut best = 0;
            let mut best_ratio = f32::NEG_INFINITY;
            let mut sign = 1.0;
            for i in 0..3 {
                let l = dot(pc, axes[i]);
                let ratio = l.abs() / half[i].max(1e-9);
                if ratio > best_ratio {
                    best_ratio = ratio;
                    best = i;
                    sign = l.signum();
                }
            }
            scale(axes[best], sign)
        }
    }
}

/// Signed distance from `p` to the surface of `shape` (negative inside), metres; exact
/// for capsules, cylinders and boxes, a first-order estimate for ellipsoids. Used by the
/// tests that check the truth lies on the labelled surface.
pub fn surface_distance(shape: &Shape, p: V3) -> f32 {
    match *shape {
        Shape::Capsule { a, b, radius } => {
            let ba = sub(b, a);
            let pa = sub(p, a);
            let h = (dot(pa, ba) / dot(ba, ba).max(1e-12)).clamp(0.0, 1.0);
            let q = sub(pa, scale(ba, h));
            dot(q, q).sqrt() - radius
        }
        Shape::Cylinder { a, b, radius } => {
            let ba = sub(b, a);
            let len = dot(ba, ba).sqrt().max(1e-9);
            let axis = scale(ba, 1.0 / len);
            let pa = sub(p, a);
            let y = dot(pa, axis);
            let radial = norm3(sub(pa, scale(axis, y)));
            let dr = radial - radius;
            let dy = (y - len * 0.5).abs() - len * 0.5;
            let outside = (dr.max(0.0).powi(2) + dy.max(0.0).powi(2)).sqrt();
            outside + dr.max(dy).min(0.0)
        }
        Shape::Ellipsoid {
            center,
            axes,
            radii,
        } => {
            let pc = sub(p, center);
            let mut k0 = 0.0;
            let mut k1 = 0.0;
            for i in 0..3 {
                let l = dot(pc, axes[i]);
                k0 += (l / radii[i]).powi(2);
                k1 += (l / (radii[i] * radii[i])).powi(2);
            }
            let k0 = k0.sqrt();
            let k1 = k1.sqrt().max(1e-12);
            k0 * (k0 - 1.0) / k1
        }
        Shape::Box { center, axes, half } => {
            let pc = sub(p, center);
            let mut q = [0.0; 3];
            for i in 0..3 {
                q[i] = dot(pc, axes[i]).abs() - half[i];
            }
            let outside = norm3([q[0].max(0.0), q[1].max(0.0), q[2].max(0.0)]);
            outside + q[0].max(q[1]).max(q[2]).min(0.0)
        }
    }
}

fn norm3(v: V3) -> f32 {
    dot(v, v).sqrt()
}

/// `camera_from_world` rows from a `world_from_camera` rotation (row-major f64), and the
/// camera centre, in `f32`.
pub fn camera_frame(world_from_camera: [[f64; 3]; 3], translation_m: [f64; 3]) -> (V3, [V3; 3]) {
    let mut rows = [[0.0f32; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            // Row i of camera_from_world = column i of world_from_camera.
            rows[i][j] = world_from_camera[j][i] as f32;
        }
    }
    let origin = [
        translation_m[0] as f32,
        translation_m[1] as f32,
        translation_m[2] as f32,
    ];
    (origin, rows)
}

/// A unit vector perpendicular to `v` (for random rotation axes).
pub fn any_perpendicular(v: V3) -> V3 {
    let helper = if v[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    normalize(cross(v, helper))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::frame_from_axis;

    fn shapes() -> Vec<Shape> {
        let axes = frame_from_axis([0.3, 0.2, 1.0]);
        vec![
            Shape::Capsule {
                a: [0.0, 0.0, 0.0],
                b: [0.1, 0.2, 0.5],
                radius: 0.07,
            },
            Shape::Cylinder {
                a: [0.0, 0.0, 0.0],
                b: [0.0, 0.1, 0.4],
                radius: 0.1,
            },
            Shape::Ellipsoid {
                center: [0.0, 0.0, 0.2],
                axes,
                radii: [0.1, 0.15, 0.25],
            },
            Shape::Box {
                center: [0.0, 0.0, 0.2],
                axes,
                half: [0.1, 0.2, 0.05],
            },
        ]
    }

    /// Every hit found by a dense fan of rays lies on the surface (|signed distance| ≤
    /// 0.1 mm, f32 rounding at ~2 m), points just before the hit are outside, and the
    /// normal is unit and faces the ray.
    #[test]
    fn hits_lie_on_the_surface_and_nothing_is_missed_before_them() {
        let origin = [1.5, -1.2, 0.9];
        for shape in shapes() {
            let mut hits = 0;
            for i in 0..60 {
                for j in 0..60 {
                    let target = [
                        -0.3 + 0.6 * i as f32 / 59.0,
                        -0.3 + 0.6 * j as f32 / 59.0,
                        -0.1 + 0.7 * ((i * 7 + j * 13) % 60) as f32 / 59.0,
                    ];
                    let d = normalize(sub(target, origin));
                    let Some(t) = intersect(&shape, origin, d) else {
                        // A miss: march along the ray and check we never enter the shape.
                        for k in 0..400 {
                            let p = add(origin, scale(d, k as f32 * 0.01));
                            assert!(
                                surface_distance(&shape, p) > -1e-3,
                                "{shape:?}: ray {d:?} missed but enters at step {k}"
                            );
                        }
                        continue;
                    };
                    hits += 1;
                    let p = add(origin, scale(d, t));
                    let dist = surface_distance(&shape, p);
                    assert!(
                        dist.abs() < 1e-4,
                        "{shape:?}: hit {p:?} is {dist} m off the surface"
                    );
                    let before = add(origin, scale(d, t - 0.002));
                    assert!(
                        surface_distance(&shape, before) > 0.0,
                        "{shape:?}: inside before the hit"
                    );
                    let n = shape_normal(&shape, p);
                    assert!((dot(n, n) - 1.0).abs() < 1e-4);
                }
            }
            assert!(hits > 100, "{shape:?}: only {hits} hits");
        }
    }

    #[test]
    fn culling_never_changes_a_hit() {
        let mut world = World::new(None);
        let prims: Vec<Primitive> = shapes()
            .into_iter()
            .enumerate()
            .map(|(i, shape)| Primitive {
                shape,
                owner: Owner::Scene,
                material: Material::plain([i as f32 / 4.0; 3]),
            })
            .collect();
        world.add_group(&prims[..2]);
        world.add_group(&prims[2..]);
        let origin = [1.5, -1.2, 0.9];
        let look = normalize(sub([0.0, 0.0, 0.2], origin));
        let right = normalize(cross(look, [0.0, 0.0, 1.0]));
        let down = cross(look, right);
        let rows = [right, down, look];
        let rects = world.cull_rects(origin, rows);
        let all = CullRects::unbounded(&world);
        let mut hits = 0;
        for i in 0..80 {
            for j in 0..80 {
                let x = -0.4 + 0.8 * i as f32 / 79.0;
                let y = -0.4 + 0.8 * j as f32 / 79.0;
                let d = normalize(add(add(scale(right, x), scale(down, y)), look));
                let a = world.cast(origin, d, [x, y], &rects);
                let b = world.cast(origin, d, [x, y], &all);
                assert_eq!(a, b);
                // Candidates of a span that holds the ray give the same hit.
                let mut span = Vec::new();
                world.candidates(&rects, [x - 0.05, x + 0.01, y - 0.002, y + 0.03], &mut span);
                assert_eq!(world.cast_among(origin, d, [x, y], &rects, &span), a);
                hits += usize::from(a.is_some());
            }
        }
        assert!(hits > 200);
    }

    #[test]
    fn room_floor_and_walls() {
        let room = Room {
            floor: Some(Material::plain([0.5; 3])),
            walls: Some(Material::plain([0.7; 3])),
            half_m: 3.0,
        };
        let world = World::new(Some(room));
        let o = [0.0, 0.0, 2.0];
        let down = world
            .cast(
                o,
                [0.0, 0.0, -1.0],
                [0.0, 0.0],
                &CullRects::unbounded(&world),
            )
            .expect("floor");
        assert!((down.t - 2.0).abs() < 1e-6);
        assert_eq!(down.normal, [0.0, 0.0, 1.0]);
        let side = world
            .cast(
                o,
                [1.0, 0.0, 0.0],
                [0.0, 0.0],
                &CullRects::unbounded(&world),
            )
            .expect("wall");
        assert!((side.t - 3.0).abs() < 1e-6);
        assert_eq!(side.normal, [-1.0, 0.0, 0.0]);
        // Above the walls: nothing.
        let up = normalize([1.0, 0.0, 1.0]);
        assert!(
            world
                .cast(o, up, [0.0, 0.0], &CullRects::unbounded(&world))
                .is_none()
        );
    }
}
