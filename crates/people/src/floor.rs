//! The floor of a cloud in any orientation, and the world frame it gives: which way is up
//! in a camera's frame, a scanner's, or any other (ALGORITHM.md §4 needs a z-up frame).
//!
//! [`find_floor`]: the cloud is averaged into voxels; planes are found one after the other
//! by RANSAC over all orientations (Fischler & Bolles 1981; seeded, so deterministic),
//! each refined by least squares and its voxels set aside before the next is searched. A
//! candidate must bound the scene: almost every voxel off it (95%) lies on one side, and its
//! normal is turned towards that side. Floors, walls and ceilings all do that; the floor
//! is the one **the points stand on**: the objects left when every candidate plane is
//! removed (people, furniture) are clustered, and a cluster stands on a plane when its
//! lowest voxel along that plane's normal is within [`CONTACT_M`] of it and beside its
//! voxels, and its highest voxel rises at least [`MIN_RISE_M`] above it. The floor is the
//! candidate the most object voxels stand on; when nothing stands on any (a bare room),
//! the candidate with the most voxels, if it holds more than half of all voxels. A wall larger than the floor
//! loses because people do not lean on it; the ceiling because nothing hangs from it.
//!
//! [`FloorHint`] overrides the search: a plane given as `a·x + b·y + c·z + d = 0` (as
//! PCL's ground-based people detector takes it), or the axis of the cloud's frame that
//! points roughly up (then only planes within [`UP_HINT_CONE_DEG`] of it are candidates).
//!
//! # Conventions
//! - Positions in metres, in the cloud's own frame; the floor's normal points up (to the
//!   side the points are on), `height(p) = n·p + d`.
//! - [`Floor::world_from_cloud`]: z along the normal, the floor at z = 0, x along the
//!   cloud's x axis projected onto the floor (its y axis when x is nearly vertical), the
//!   origin below the cloud's origin. For a camera's optical frame (x right, y down, z
//!   forward) that is x right, y forward, z up.

use crate::voxel::{VoxelGraph, voxelize};
use bodyseg_core::math::{RigidTransform, Vec3};
use bodyseg_core::rng::SplitMix64;
use rustc_hash::{FxHashMap, FxHashSet};

/// Voxel edge of the search, metres: a plane's support counts voxels, i.e. area, so the
/// density of a depth camera's points (many more near it) does not favour near surfaces.
pub const FLOOR_VOXEL_M: f32 = 0.05;
/// A voxel within this distance of a plane is on it, metres: Kinect-class depth noise on
/// a floor 4–6 m away (a few centimetres; voxel centroids average some of it out).
pub const PLANE_TOL_M: f32 = 0.05;
/// At most this many candidate planes are searched: floor, ceiling, a few walls.
const MAX_PLANES: usize = 6;
/// RANSAC hypotheses per plane: half through three voxels of the whole cloud, half
/// through three voxels of one [`LOCAL_CELL_M`] cell (a small plane is hit that way).
const RANSAC_ITERATIONS: usize = 600;
/// Edge of the cells the local hypotheses are drawn in, metres.
const LOCAL_CELL_M: f32 = 1.0;
/// Hypotheses are scored on at most about this many voxels (a stride through them): the
/// count only ranks planes; the chosen one is refined on all its voxels.
const SCORE_SAMPLE: usize = 6000;
/// A candidate plane holds at least this many voxels (0.75 m² at 5 cm): a camera that
/// sees a standing person sees more floor than that; a smaller plane is a table top, a
/// box lid or the front of a person's trunk (≈ 0.4 m²).
pub const MIN_FLOOR_VOXELS: usize = 300;
/// A candidate bounds the scene: at least this fraction of the voxels farther than
/// 2 × [`PLANE_TOL_M`] from it lie on one side (the rest: depth noise below a floor,
/// what is seen through a doorway).
const MIN_ONE_SIDE: f32 = 0.95;
/// A cluster stands on a plane when its lowest voxel along the normal is at most this
/// high, metres: feet and shoes are removed with the floor or sit just above it; a
/// Kinect at 5 m may lose them up to the ankles.
pub const CONTACT_M: f32 = 0.3;
/// ... and its highest voxel rises at least this far above the plane, metres: people
/// (even seated) and furniture do; the far side of people lined up along a plane that
/// only touches their sides (a vertical plane tangent to them) does not (≈ 0.4 m, a
/// body's depth).
pub const MIN_RISE_M: f32 = 0.6;
/// ... and that lowest voxel lies within about this distance of one of the plane's own
/// voxels, metres (not beside the plane's infinite extension past a wall's end).
const BESIDE_M: f32 = 0.3;
/// Object voxels closer than this are one object, metres (two voxels apart).
const OBJECT_GAP_M: f32 = 0.1;
/// An object has at least this many voxels: flying pixels and specks are not.
const MIN_OBJECT_VOXELS: usize = 10;
/// With `--up`, a candidate's normal is within this angle of the given axis, degrees: a
/// camera pitched down by up to 45° still has its -y axis "up".
pub const UP_HINT_CONE_DEG: f32 = 45.0;

/// An axis of the cloud's frame, with its sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    /// +x.
    X,
    /// -x.
    NegX,
    /// +y.
    Y,
    /// -y (a camera's optical frame: y points down).
    NegY,
    /// +z (bodyseg's world frame).
    Z,
    /// -z.
    NegZ,
}

impl Up {
    /// The unit vector of the axis.
    pub fn axis(self) -> Vec3 {
        match self {
            Up::X => [1.0, 0.0, 0.0],
            Up::NegX => [-1.0, 0.0, 0.0],
            Up::Y => [0.0, 1.0, 0.0],
            Up::NegY => [0.0, -1.0, 0.0],
            Up::Z => [0.0, 0.0, 1.0],
            Up::NegZ => [0.0, 0.0, -1.0],
        }
    }

    /// The name used on the command line: `x`, `-x`, ..., `-z`.
    pub fn name(self) -> &'static str {
        match self {
            Up::X => "x",
            Up::NegX => "-x",
            Up::Y => "y",
            Up::NegY => "-y",
            Up::Z => "z",
            Up::NegZ => "-z",
        }
    }
}

impl std::str::FromStr for Up {
    type Err = String;

    /// `x`, `y`, `z`, optionally with a sign (`+z`, `-y`); case-insensitive.
    fn from_str(s: &str) -> Result<Up, String> {
        Ok(match s.trim().to_ascii_lowercase().as_str() {
            "x" | "+x" => Up::X,
            "-x" => Up::NegX,
            "y" | "+y" => Up::Y,
            "-y" => Up::NegY,
            "z" | "+z" => Up::Z,
            "-z" => Up::NegZ,
            other => return Err(format!("'{other}' is not an axis: x, y, z, -x, -y or -z")),
        })
    }
}

/// What the caller knows about the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FloorHint {
    /// The floor plane `a·x + b·y + c·z + d = 0` in the cloud's frame (PCL's ground
    /// coefficients), metres; its normal is turned towards `up` when given, else towards
    /// the side most points are on. `(a, b, c)` need not be unit length.
    pub ground: Option<[f32; 4]>,
    /// The axis of the cloud's frame that points (roughly, within [`UP_HINT_CONE_DEG`])
    /// up.
    pub up: Option<Up>,
}

/// How a [`Floor`] was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FloorSource {
    /// Found by [`find_floor`]'s search.
    Found,
    /// The plane of [`FloorHint::ground`].
    Given,
    /// No plane was found along [`FloorHint::up`]: the level of the lowest points (the
    /// 1st percentile along the axis) perpendicular to it.
    Lowest,
}

/// A floor plane in the cloud's frame: `height(p) = normal·p + offset_m`, zero on the
/// floor, positive above it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Floor {
    /// Unit normal, cloud frame, pointing up (to the side the points are on).
    pub normal: Vec3,
    /// Offset, metres: the height of the cloud's origin above the floor.
    pub offset_m: f32,
    /// Voxels ([`FLOOR_VOXEL_M`]) within [`PLANE_TOL_M`] of the plane.
    pub support_voxels: usize,
    /// How the plane was obtained.
    pub source: FloorSource,
}

impl Floor {
    /// Height of `p` (cloud frame) above the floor, metres.
    pub fn height(&self, p: Vec3) -> f32 {
        let n = self.normal;
        n[0] * p[0] + n[1] * p[1] + n[2] * p[2] + self.offset_m
    }

    /// Angle between the normal and the cloud's +z axis, degrees: 0 for a cloud that is
    /// already z up.
    pub fn tilt_from_z_deg(&self) -> f32 {
        self.normal[2].clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// The rigid transform from the cloud's frame into the world frame of this floor:
    /// z up along the normal, the floor at z = 0, x along the cloud's x axis projected
    /// onto the floor (its y axis when x is within ~25° of the normal), y = z × x, the
    /// origin at the foot of the cloud's origin.
    pub fn world_from_cloud(&self) -> RigidTransform {
        let n = unit(self.normal.map(f64::from)).unwrap_or([0.0, 0.0, 1.0]);
        let along = |a: [f64; 3]| {
            let k = dot(a, n);
            unit([a[0] - k * n[0], a[1] - k * n[1], a[2] - k * n[2]])
        };
        let x = along([1.0, 0.0, 0.0])
            .filter(|_| n[0].abs() < 0.9)
            .or_else(|| along([0.0, 1.0, 0.0]))
            .unwrap_or([1.0, 0.0, 0.0]);
        let y = cross(n, x);
        RigidTransform {
            rotation: [x, y, n],
            translation_m: [0.0, 0.0, f64::from(self.offset_m)],
        }
    }
}

/// Why [`find_floor`] could not use a hint.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FloorHintError {
    /// The given plane is not a plane.
    #[error("ground plane {0:?}: a, b, c must be finite and not all 0, d finite")]
    NotAPlane([f32; 4]),
}

/// The floor of `points` (metres, any frame): the given plane, or the search described
/// in the module docs. `None` when no plane bounds the scene (too few points, no plane of
/// [`MIN_FLOOR_VOXELS`], a cloud in millimetres whose voxels hold one point each) and no
/// `up` was given; with `up`, the lowest level along it instead ([`FloorSource::Lowest`]).
/// Deterministic: the same points give the same floor.
///
/// # Errors
/// [`FloorHintError::NotAPlane`] for a given plane with a zero or non-finite normal.
pub fn find_floor(points: &[Vec3], hint: &FloorHint) -> Result<Option<Floor>, FloorHintError> {
    let voxels = voxelize(
        points.iter().enumerate().map(|(i, &p)| (i, p, 0)),
        FLOOR_VOXEL_M,
    );
    let centers = &voxels.centers;
    if let Some(g) = hint.ground {
        let n = [g[0], g[1], g[2]].map(f64::from);
        let len = dot(n, n).sqrt();
        if !(len.is_finite() && len > 0.0 && g[3].is_finite()) {
            return Err(FloorHintError::NotAPlane(g));
        }
        let mut plane = Plane {
            n: n.map(|v| v / len),
            d: f64::from(g[3]) / len,
        };
        let up = match hint.up {
            Some(u) => dot(plane.n, u.axis().map(f64::from)) >= 0.0,
            None => one_side(&plane, centers).0 >= 0.5,
        };
        if !up {
            plane = plane.flipped();
        }
        let support = centers
            .iter()
            .filter(|&&p| plane.height(p).abs() <= f64::from(PLANE_TOL_M))
            .count();
        return Ok(Some(plane.floor(support, FloorSource::Given)));
    }
    let up_axis = hint.up.map(|u| u.axis().map(f64::from));
    let candidates = candidate_planes(centers, up_axis);
    let found = choose_floor(centers, &candidates);
    tracing::debug!(
        voxels = centers.len(),
        candidates = candidates.len(),
        found = found.is_some(),
        "floor search"
    );
    Ok(match (found, hint.up) {
        (Some(c), _) => Some(c.plane.floor(c.inliers.len(), FloorSource::Found)),
        (None, Some(up)) => lowest_along(centers, up),
        (None, None) => None,
    })
}

/// A plane `n·p + d = 0`, unit `n`, f64.
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: [f64; 3],
    d: f64,
}

impl Plane {
    fn height(&self, p: Vec3) -> f64 {
        self.n[0] * f64::from(p[0])
            + self.n[1] * f64::from(p[1])
            + self.n[2] * f64::from(p[2])
            + self.d
    }

    fn flipped(self) -> Plane {
        Plane {
            n: self.n.map(|v| -v),
            d: -self.d,
        }
    }

    fn floor(self, support_voxels: usize, source: FloorSource) -> Floor {
        Floor {
            normal: self.n.map(|v| v as f32),
            offset_m: self.d as f32,
            support_voxels,
            source,
        }
    }
}

/// A candidate plane and its voxels.
struct Candidate {
    plane: Plane,
    inliers: Vec<u32>,
}

/// Up to [`MAX_PLANES`] planes of at least [`MIN_FLOOR_VOXELS`] voxels, largest first,
/// each one's voxels removed before the next is searched; with `up`, only planes within
/// [`UP_HINT_CONE_DEG`] of it, their normals along it.
fn candidate_planes(centers: &[Vec3], up: Option<[f64; 3]>) -> Vec<Candidate> {
    let mut rng = SplitMix64::new(0x243F_6A88_85A3_08D3);
    let mut remaining: Vec<u32> = (0..centers.len() as u32).collect();
    let min_cos = f64::from(UP_HINT_CONE_DEG.to_radians().cos());
    let tol = f64::from(PLANE_TOL_M);
    let mut out = Vec::new();
    while out.len() < MAX_PLANES && remaining.len() >= MIN_FLOOR_VOXELS {
        let local = local_cells(centers, &remaining);
        let stride = (remaining.len() / SCORE_SAMPLE).max(1);
        let mut best: Option<(usize, Plane)> = None;
        for it in 0..RANSAC_ITERATIONS {
            let triple = if it % 2 == 0 || local.is_empty() {
                [0; 3].map(|_| remaining[rng.below(remaining.len() as u64) as usize])
            } else {
                let cell = &local[rng.below(local.len() as u64) as usize];
                [0; 3].map(|_| cell[rng.below(cell.len() as u64) as usize])
            };
            let Some(mut plane) = plane_through(triple.map(|i| centers[i as usize])) else {
                continue;
            };
            if let Some(u) = up {
                if dot(plane.n, u) < 0.0 {
                    plane = plane.flipped();
                }
                if dot(plane.n, u) < min_cos {
                    continue;
                }
            }
            let count = remaining
                .iter()
                .step_by(stride)
                .filter(|&&i| plane.height(centers[i as usize]).abs() <= tol)
                .count();
            if best.is_none_or(|(c, _)| count > c) {
                best = Some((count, plane));
            }
        }
        let Some((_, mut plane)) = best else { break };
        // Least squares on the plane's voxels, twice (the first fit can move the band).
        for _ in 0..2 {
            let on: Vec<Vec3> = remaining
                .iter()
                .map(|&i| centers[i as usize])
                .filter(|&p| plane.height(p).abs() <= tol)
                .collect();
            if let Some(mut fit) = fit_plane(&on) {
                if dot(fit.n, plane.n) < 0.0 {
                    fit = fit.flipped();
                }
                plane = fit;
            }
        }
        let (inliers, rest): (Vec<u32>, Vec<u32>) = remaining
            .iter()
            .partition(|&&i| plane.height(centers[i as usize]).abs() <= tol);
        if inliers.len() < MIN_FLOOR_VOXELS {
            break;
        }
        if let Some(u) = up
            && dot(plane.n, u) < min_cos
        {
            // The refit left the cone: not a floor along `up`; its voxels are set aside.
            remaining = rest;
            continue;
        }
        remaining = rest;
        out.push(Candidate { plane, inliers });
    }
    out
}

/// The voxels of `among` grouped by [`LOCAL_CELL_M`] cells, cells with at least 3 voxels,
/// in order of their first voxel.
fn local_cells(centers: &[Vec3], among: &[u32]) -> Vec<Vec<u32>> {
    let inv = 1.0 / LOCAL_CELL_M;
    let mut index: FxHashMap<[i32; 3], usize> = FxHashMap::default();
    let mut cells: Vec<Vec<u32>> = Vec::new();
    for &i in among {
        let p = centers[i as usize];
        let key = p.map(|v| (v * inv).floor() as i32);
        let k = *index.entry(key).or_insert_with(|| {
            cells.push(Vec::new());
            cells.len() - 1
        });
        cells[k].push(i);
    }
    cells.retain(|c| c.len() >= 3);
    cells
}

/// The candidate the points stand on (module docs), its normal turned to the points.
fn choose_floor(centers: &[Vec3], candidates: &[Candidate]) -> Option<Candidate> {
    // Each candidate turned towards the points; those that do not bound the scene dropped.
    let bounding: Vec<(usize, Plane)> = candidates
        .iter()
        .enumerate()
        .filter_map(|(k, c)| {
            let (above, beside) = one_side(&c.plane, centers);
            let plane = if above >= 0.5 {
                c.plane
            } else {
                c.plane.flipped()
            };
            let frac = above.max(1.0 - above);
            tracing::trace!(candidate = k, voxels = c.inliers.len(), frac, beside, normal = ?plane.n, "floor candidate");
            (frac >= MIN_ONE_SIDE).then_some((k, plane))
        })
        .collect();
    if bounding.is_empty() {
        return None;
    }
    // The objects: every voxel on no candidate plane, clustered.
    let mut keep = vec![true; centers.len()];
    for c in candidates {
        for &i in &c.inliers {
            keep[i as usize] = false;
        }
    }
    let graph = VoxelGraph::new(centers, OBJECT_GAP_M, &keep);
    let mut objects = graph.components(&keep);
    objects.retain(|o| o.len() >= MIN_OBJECT_VOXELS);
    let standing = |k: usize, plane: &Plane| -> usize {
        let beside = cells_of(centers, &candidates[k].inliers, BESIDE_M);
        objects
            .iter()
            .filter(|o| {
                let height = |i: &u32| plane.height(centers[*i as usize]);
                let lowest = o.iter().min_by(|a, b| height(a).total_cmp(&height(b)));
                let top = o.iter().map(height).fold(f64::NEG_INFINITY, f64::max);
                lowest.is_some_and(|i| {
                    height(i) <= f64::from(CONTACT_M)
                        && top >= f64::from(MIN_RISE_M)
                        && near_cells(&beside, centers[*i as usize], BESIDE_M)
                })
            })
            .map(Vec::len)
            .sum()
    };
    let scored: Vec<(usize, Plane, usize)> = bounding
        .into_iter()
        .map(|(k, plane)| (k, plane, standing(k, &plane)))
        .collect();
    for &(k, plane, on) in &scored {
        tracing::debug!(candidate = k, voxels = candidates[k].inliers.len(), standing = on, normal = ?plane.n, "floor candidate bounds the scene");
    }
    // Most voxels standing on it; ties (none standing anywhere): the larger plane, then
    // the earlier candidate (deterministic).
    let &(k, plane, on) = scored.iter().max_by(|a, b| {
        a.2.cmp(&b.2)
            .then(
                candidates[a.0]
                    .inliers
                    .len()
                    .cmp(&candidates[b.0].inliers.len()),
            )
            .then(b.0.cmp(&a.0))
    })?;
    // Nothing stands on any plane: a bare floor holds most of the scene's voxels; a plane
    // that does not (one touching the sides of people lined up, a wall) is no floor.
    if on == 0 && 2 * candidates[k].inliers.len() <= centers.len() {
        return None;
    }
    // The floor's voxels among all of them (a later candidate may have taken none, but
    // the count is the plane's support).
    Some(Candidate {
        plane,
        inliers: candidates[k].inliers.clone(),
    })
}

/// Of the voxels farther than 2 × [`PLANE_TOL_M`] from `plane`: the fraction on its
/// positive side, and how many there are.
fn one_side(plane: &Plane, centers: &[Vec3]) -> (f32, usize) {
    let far = 2.0 * f64::from(PLANE_TOL_M);
    let (mut above, mut below) = (0usize, 0usize);
    for &p in centers {
        let h = plane.height(p);
        if h > far {
            above += 1;
        } else if h < -far {
            below += 1;
        }
    }
    let n = above + below;
    ((above as f32) / (n.max(1) as f32), n)
}

/// The cells (edge `cell_m`) holding a voxel of `members`.
fn cells_of(centers: &[Vec3], members: &[u32], cell_m: f32) -> FxHashSet<[i32; 3]> {
    let inv = 1.0 / cell_m;
    members
        .iter()
        .map(|&i| centers[i as usize].map(|v| (v * inv).floor() as i32))
        .collect()
}

/// Whether `p`'s cell or one of its 26 neighbours is in `cells`.
fn near_cells(cells: &FxHashSet<[i32; 3]>, p: Vec3, cell_m: f32) -> bool {
    let c = p.map(|v| (v / cell_m).floor() as i32);
    (-1..=1).any(|dx| {
        (-1..=1).any(|dy| (-1..=1).any(|dz| cells.contains(&[c[0] + dx, c[1] + dy, c[2] + dz])))
    })
}

/// With no plane along `up`: the level perpendicular to it at the 1st percentile of the
/// points along it (a few points below the floor, noise, do not lower it).
fn lowest_along(centers: &[Vec3], up: Up) -> Option<Floor> {
    let u = up.axis();
    let mut along: Vec<f32> = centers
        .iter()
        .map(|p| u[0] * p[0] + u[1] * p[1] + u[2] * p[2])
        .collect();
    along.sort_by(f32::total_cmp);
    let level = *along.get(along.len() / 100)?;
    Some(Floor {
        normal: u,
        offset_m: -level,
        support_voxels: 0,
        source: FloorSource::Lowest,
    })
}

/// The plane through three points (unit normal, any sign); `None` when they are on a line.
fn plane_through([a, b, c]: [Vec3; 3]) -> Option<Plane> {
    let a = a.map(f64::from);
    let u = sub(b.map(f64::from), a);
    let w = sub(c.map(f64::from), a);
    let n = unit(cross(u, w))?;
    Some(Plane { n, d: -dot(n, a) })
}

/// The least-squares plane of `points` (the normal is the covariance's eigenvector of the
/// smallest eigenvalue); `None` for fewer than 3 points or a degenerate set.
fn fit_plane(points: &[Vec3]) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    let k = points.len() as f64;
    let mut mean = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            mean[a] += f64::from(p[a]) / k;
        }
    }
    let mut cov = [[0.0f64; 3]; 3];
    for p in points {
        let d = [0, 1, 2].map(|a| f64::from(p[a]) - mean[a]);
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j];
            }
        }
    }
    let (values, vectors) = symmetric_eigen(cov);
    let smallest = (0..3).min_by(|&a, &b| values[a].total_cmp(&values[b]))?;
    let n = unit([0, 1, 2].map(|r| vectors[r][smallest]))?;
    Some(Plane {
        n,
        d: -dot(n, mean),
    })
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 matrix, by cyclic Jacobi
/// rotations (converges in a handful of sweeps at this size).
fn symmetric_eigen(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J, V ← V J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let (vkp, vkq) = (v[k][p], v[k][q]);
                v[k][p] = c * vkp - s * vkq;
                v[k][q] = s * vkp + c * vkq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(u: [f64; 3], w: [f64; 3]) -> [f64; 3] {
    [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ]
}

/// `a` scaled to unit length; `None` when it is (nearly) zero or not finite.
fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let len = dot(a, a).sqrt();
    (len.is_finite() && len > 1e-12).then(|| a.map(|v| v / len))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_finds_the_smallest_axis_of_a_flat_covariance() {
        // Spread 4 and 1 in a plane tilted about x, 0.01 across it.
        let (s, c) = 0.3f64.sin_cos();
        let axes = [[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]];
        let spread = [4.0, 1.0, 0.01];
        let mut m = [[0.0; 3]; 3];
        for k in 0..3 {
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += spread[k] * axes[k][i] * axes[k][j];
                }
            }
        }
        let (values, vectors) = symmetric_eigen(m);
        let k = (0..3)
            .min_by(|&a, &b| values[a].total_cmp(&values[b]))
            .expect("three values");
        assert!((values[k] - 0.01).abs() < 1e-9, "{values:?}");
        let n = [0, 1, 2].map(|r| vectors[r][k]);
        assert!(dot(n, axes[2]).abs() > 1.0 - 1e-9, "{n:?}");
    }

    #[test]
    fn up_axes_parse_with_and_without_sign() {
        assert_eq!("-y".parse::<Up>(), Ok(Up::NegY));
        assert_eq!("+Z".parse::<Up>(), Ok(Up::Z));
        assert_eq!("x".parse::<Up>(), Ok(Up::X));
        assert!("up".parse::<Up>().is_err());
        for u in [Up::X, Up::NegX, Up::Y, Up::NegY, Up::Z, Up::NegZ] {
            assert_eq!(u.name().parse::<Up>(), Ok(u));
        }
    }

    #[test]
    fn a_camera_frame_floor_gives_x_right_y_forward_z_up() {
        // The floor 1.1 m below a camera's optical centre (y down): normal -y.
        let floor = Floor {
            normal: [0.0, -1.0, 0.0],
            offset_m: 1.1,
            support_voxels: 0,
            source: FloorSource::Given,
        };
        let t = floor.world_from_cloud();
        // 2 m ahead, 0.5 m right, on the floor (y = 1.1 down).
        let p = t.apply([0.5, 1.1, 2.0]);
        assert!(bodyseg_core::math::dist(p, [0.5, 2.0, 0.0]) < 1e-6, "{p:?}");
        // The camera itself stands 1.1 m above the floor's origin.
        let cam = t.apply([0.0; 3]);
        assert!(
            bodyseg_core::math::dist(cam, [0.0, 0.0, 1.1]) < 1e-6,
            "{cam:?}"
        );
        assert!((floor.tilt_from_z_deg() - 90.0).abs() < 1e-4);
    }
}
