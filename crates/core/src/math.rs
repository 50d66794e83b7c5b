//! Small geometric helpers shared by the stages (parry's single `math` module idea).
//! Points are plain `[f32; 3]` in metres so that clouds stay flat arrays.

/// A 3D point or vector, metres, in the frame its name says.
pub type Vec3 = [f32; 3];

/// Squared Euclidean distance, m². Every stage that compares a distance to a radius uses
/// this one function, so brute-force references and fast paths round identically.
#[inline]
pub fn dist2(a: Vec3, b: Vec3) -> f32 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    let dz = a[2] - b[2];
    dx * dx + dy * dy + dz * dz
}

/// Euclidean distance, m.
#[inline]
pub fn dist(a: Vec3, b: Vec3) -> f32 {
    dist2(a, b).sqrt()
}

/// True when all three coordinates are finite. `&`, not `&&`: no branch, so scans over
/// whole clouds (`LabeledCloud::validate`) vectorise.
#[inline]
pub fn is_finite(p: Vec3) -> bool {
    p[0].is_finite() & p[1].is_finite() & p[2].is_finite()
}
