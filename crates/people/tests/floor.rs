//! The floor in any orientation ([`bodyseg_people::find_floor`]): synthetic rooms turned
//! every which way (seeded; `BODYSEG_FLOOR_SEED=N` runs one seed), a wall larger than the
//! floor, a corridor with a ceiling, the hints, and clouds without a floor.

use bodyseg_core::math::Vec3;
use bodyseg_people::{FloorHint, FloorSource, Up, find_floor};

/// splitmix64, for the test scenes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
}

/// Unit vectors along the axes, for [`rect`]'s sides.
const X: Vec3 = [1.0, 0.0, 0.0];
const Y: Vec3 = [0.0, 1.0, 0.0];
const Z: Vec3 = [0.0, 0.0, 1.0];

/// Depth noise of [`rect`]'s surfaces, metres (±1 cm, as a depth camera at a few metres).
const RECT_NOISE_M: f32 = 0.01;

/// Points every `step_m` on the rectangle `origin + s·a + t·b`, s in [0, la], t in
/// [0, lb], with ±[`RECT_NOISE_M`] along `normal`.
fn rect(
    rng: &mut Rng,
    origin: Vec3,
    (a, la): (Vec3, f32),
    (b, lb): (Vec3, f32),
    out: &mut Vec<Vec3>,
) {
    let normal = cross(a, b);
    let step = 0.02;
    let (ns, nt) = ((la / step) as usize, (lb / step) as usize);
    for i in 0..=ns {
        for j in 0..=nt {
            let (s, t) = (i as f32 * step, j as f32 * step);
            let e = rng.uniform(-RECT_NOISE_M, RECT_NOISE_M);
            out.push(std::array::from_fn(|k| {
                origin[k] + s * a[k] + t * b[k] + e * normal[k]
            }));
        }
    }
}

/// A person-sized cylinder (radius 0.2 m ± 1 cm of noise, 1.7 m tall) standing on
/// z = 0 at (x, y), its bottom `gap_m` above the floor (a depth camera loses the feet).
fn person(rng: &mut Rng, x: f32, y: f32, gap_m: f32, out: &mut Vec<Vec3>) {
    for k in 0..63 {
        let phi = k as f32 / 63.0 * std::f32::consts::TAU;
        for h in 0..85 {
            let z = gap_m + h as f32 * 0.02;
            let r = 0.2 + rng.uniform(-0.01, 0.01);
            out.push([x + r * phi.cos(), y + r * phi.sin(), z]);
        }
    }
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A random rotation (a unit quaternion from three uniforms, Shoemake 1992) and a
/// translation within ±5 m.
fn random_pose(rng: &mut Rng) -> ([[f32; 3]; 3], Vec3) {
    let (u1, u2, u3) = (
        rng.uniform(0.0, 1.0),
        rng.uniform(0.0, 1.0),
        rng.uniform(0.0, 1.0),
    );
    let tau = std::f32::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let q = [
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    ];
    let r = bodyseg_calib::Pose::from_quaternion_wxyz(q.map(f64::from), [0.0; 3])
        .expect("a unit quaternion")
        .rotation()
        .map(|row| row.map(|v| v as f32));
    let t = [0; 3].map(|_| rng.uniform(-5.0, 5.0));
    (r, t)
}

fn apply(r: &[[f32; 3]; 3], t: Vec3, p: Vec3) -> Vec3 {
    std::array::from_fn(|i| dot(r[i], p) + t[i])
}

/// A room in a z-up frame with the floor at z = 0 (4 m × 4 m, ±1 cm of depth noise),
/// one wall along its back edge (4 m × 2.5 m, larger than most of the floor a camera
/// sees) and three people standing on the floor.
fn room(rng: &mut Rng) -> Vec<Vec3> {
    let mut pts = Vec::new();
    rect(rng, [-2.0, -2.0, 0.0], (X, 4.0), (Y, 4.0), &mut pts);
    rect(rng, [-2.0, 2.0, 0.0], (X, 4.0), (Z, 2.5), &mut pts);
    for (x, y) in [(-1.0, 0.0), (0.2, 0.5), (1.2, -0.8)] {
        person(rng, x, y, 0.05, &mut pts);
    }
    pts
}

/// Angle between two unit vectors, degrees.
fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    dot(a, b).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn a_room_turned_any_way_gives_its_floor_within_1_degree_and_1_cm() {
    let seeds: Vec<u64> = match std::env::var("BODYSEG_FLOOR_SEED") {
        Ok(s) => vec![s.parse().expect("BODYSEG_FLOOR_SEED is a number")],
        Err(_) => (1..=12).collect(),
    };
    for seed in seeds {
        let mut rng = Rng(seed);
        let local = room(&mut rng);
        let (r, t) = random_pose(&mut rng);
        let cloud: Vec<Vec3> = local.iter().map(|&p| apply(&r, t, p)).collect();
        let floor = find_floor(&cloud, &FloorHint::default())
            .expect("no hint to refuse")
            .unwrap_or_else(|| panic!("seed {seed}: no floor found"));
        assert_eq!(floor.source, FloorSource::Found);
        // The true up is the rotated +z; the floor passes through the rotated origin.
        let up = apply(&r, [0.0; 3], [0.0, 0.0, 1.0]);
        let tilt = angle_deg(floor.normal, up);
        assert!(
            tilt < 1.0,
            "seed {seed}: normal {:?} is {tilt}° from up {up:?}",
            floor.normal
        );
        // Heights of floor corners and of a point 1 m above the floor: within 1 cm.
        for (p, want) in [
            ([-2.0, -2.0, 0.0], 0.0),
            ([2.0, 1.5, 0.0], 0.0),
            ([0.0, 0.0, 1.0], 1.0),
        ] {
            let h = floor.height(apply(&r, t, p));
            assert!(
                (h - want).abs() < 0.01,
                "seed {seed}: {p:?} at {h} m, want {want}"
            );
        }
        // The world frame puts the floor at z = 0 with z up.
        let w = floor.world_from_cloud();
        let top = w.apply(apply(&r, t, [0.3, 0.4, 1.7]));
        assert!((top[2] - 1.7).abs() < 0.02, "seed {seed}: {top:?}");
        // Deterministic.
        assert_eq!(
            find_floor(&cloud, &FloorHint::default()).expect("no hint"),
            Some(floor),
            "seed {seed}"
        );
    }
}

#[test]
fn a_wall_larger_than_the_floor_loses_because_nobody_stands_on_it() {
    // A camera's view of a narrow strip of floor (6 m × 1.2 m) in front of a tall wall
    // (6 m × 3 m, 2.5 times the floor's area), four people on the strip 0.6 m from the
    // wall, and the camera's own frame (y down, z forward).
    let mut rng = Rng(7);
    let mut local = Vec::new();
    rect(&mut rng, [-3.0, 0.8, 0.0], (X, 6.0), (Y, 1.2), &mut local);
    rect(&mut rng, [-3.0, 2.0, 0.0], (X, 6.0), (Z, 3.0), &mut local);
    for x in [-2.0, -0.7, 0.6, 1.9] {
        person(&mut rng, x, 1.4, 0.1, &mut local);
    }
    // World (z up) → camera (x right, y down, z forward), camera 1.5 m up at y = -2.
    let cam = |p: Vec3| [p[0], 1.5 - p[2], p[1] + 2.0];
    let cloud: Vec<Vec3> = local.into_iter().map(cam).collect();
    let floor = find_floor(&cloud, &FloorHint::default())
        .expect("no hint")
        .expect("a floor");
    assert!(
        angle_deg(floor.normal, [0.0, -1.0, 0.0]) < 1.0,
        "the wall's normal (0, 0, -1) won: {floor:?}"
    );
    assert!((floor.offset_m - 1.5).abs() < 0.01, "{floor:?}");
    // Up the camera's -y axis (x right, y forward, z up in the floor's frame).
    let w = floor.world_from_cloud();
    let head = w.apply(cam([0.6, 1.4, 1.8]));
    assert!(
        (head[0] - 0.6).abs() < 0.02 && (head[2] - 1.8).abs() < 0.02,
        "{head:?}"
    );
}

#[test]
fn in_a_corridor_the_floor_beats_walls_and_ceiling() {
    // Floor 3 m wide, 8 m long; walls 2.8 m high; a ceiling; five people walking.
    let mut rng = Rng(11);
    let mut pts = Vec::new();
    let along = (Y, 8.0);
    rect(&mut rng, [-1.5, 0.0, 0.0], (X, 3.0), along, &mut pts);
    rect(&mut rng, [-1.5, 0.0, 2.8], (X, 3.0), along, &mut pts);
    for x in [-1.5, 1.5] {
        rect(&mut rng, [x, 0.0, 0.0], (Z, 2.8), along, &mut pts);
    }
    for (x, y) in [(-0.9, 2.0), (-0.3, 2.5), (0.3, 3.2), (0.9, 2.2), (0.0, 4.5)] {
        person(&mut rng, x, y, 0.1, &mut pts);
    }
    let floor = find_floor(&pts, &FloorHint::default())
        .expect("no hint")
        .expect("a floor");
    assert!(angle_deg(floor.normal, [0.0, 0.0, 1.0]) < 1.0, "{floor:?}");
    assert!(floor.offset_m.abs() < 0.01, "{floor:?}");
}

#[test]
fn hints_give_the_plane_or_the_axis() {
    let mut rng = Rng(3);
    let pts = room(&mut rng);
    // A given plane, its normal turned to the points (PCL's coefficients may point down).
    let down = [0.0, 0.0, -2.0, 0.2]; // z = 0.1, normal -z scaled by 2
    let hint = FloorHint {
        ground: Some(down),
        up: None,
    };
    let floor = find_floor(&pts, &hint).expect("a plane").expect("given");
    assert_eq!(floor.source, FloorSource::Given);
    assert_eq!(floor.normal, [0.0, 0.0, 1.0]);
    assert!((floor.offset_m + 0.1).abs() < 1e-6, "{floor:?}");
    // ... or turned along --up.
    let floor = find_floor(
        &pts,
        &FloorHint {
            ground: Some(down),
            up: Some(Up::NegZ),
        },
    )
    .expect("a plane")
    .expect("given");
    assert_eq!(floor.normal, [0.0, 0.0, -1.0]);
    // Not a plane.
    let zero = FloorHint {
        ground: Some([0.0, 0.0, 0.0, 1.0]),
        up: None,
    };
    assert!(find_floor(&pts, &zero).is_err());
    // --up y: only planes within 45° of +y; the wall (normal -y towards the room) is
    // the one along the axis, whatever stands on the floor.
    let wall = find_floor(
        &pts,
        &FloorHint {
            ground: None,
            up: Some(Up::NegY),
        },
    )
    .expect("no plane given")
    .expect("the wall");
    assert!(angle_deg(wall.normal, [0.0, -1.0, 0.0]) < 1.0, "{wall:?}");
    // --up x: no plane along x; the level of the lowest points along +x.
    let lowest = find_floor(
        &pts,
        &FloorHint {
            ground: None,
            up: Some(Up::X),
        },
    )
    .expect("no plane given")
    .expect("the lowest level");
    assert_eq!(lowest.source, FloorSource::Lowest, "{lowest:?}");
    assert_eq!(lowest.normal, [1.0, 0.0, 0.0]);
    assert!((lowest.height([-2.0, 0.0, 0.0])).abs() < 0.05, "{lowest:?}");
}

#[test]
fn no_floor_in_people_alone_or_in_millimetres() {
    let mut rng = Rng(9);
    let mut pts = Vec::new();
    for (x, y) in [(-1.0, 0.0), (0.0, 0.8), (1.0, 1.5)] {
        person(&mut rng, x, y, 0.0, &mut pts);
    }
    assert_eq!(
        find_floor(&pts, &FloorHint::default()).expect("no hint"),
        None
    );
    assert_eq!(
        find_floor(&[], &FloorHint::default()).expect("no hint"),
        None
    );
    // The room in millimetres: its voxels hold one point each, no plane of 5 cm voxels.
    let mm: Vec<Vec3> = room(&mut rng)
        .into_iter()
        .map(|p| p.map(|v| v * 1000.0))
        .collect();
    assert_eq!(
        find_floor(&mm, &FloorHint::default()).expect("no hint"),
        None
    );
}
