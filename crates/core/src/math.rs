//! Small geometric helpers shared by the stages (parry's single `math` module idea).
//! Points are plain `[f32; 3]` in metres so that clouds stay flat arrays.

/// A 3D point or vector, metres, in the frame its name says.
pub type Vec3 = [f32; 3];

/// `a + b`.
#[inline]
pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`.
#[inline]
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a * s`.
#[inline]
pub fn scale(a: Vec3, s: f32) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product, summed x + y + z in that order.
#[inline]
pub fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product `a × b`.
#[inline]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean length.
#[inline]
pub fn norm(a: Vec3) -> f32 {
    dot(a, a).sqrt()
}

/// `a / |a|`; a zero vector stays zero.
#[inline]
pub fn normalize(a: Vec3) -> Vec3 {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// `a + (b - a) * t`.
#[inline]
pub fn lerp(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    add(a, scale(sub(b, a), t))
}

/// An orthonormal frame `[x, y, z]` whose third axis is the unit vector `z` (not
/// normalised again): x ⟂ z from a helper axis (world z, or world x when `z` is near it),
/// y = z × x.
pub fn frame_around_unit_axis(z: Vec3) -> [Vec3; 3] {
    let helper = if z[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let x = normalize(cross(helper, z));
    [x, cross(z, x), z]
}

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

/// Chromaticity bins per axis: r / (r + g + b) and g / (r + g + b) of linear RGB, each in
/// [0, 1], in bins of 0.02. Shared by the refinement's foreign colours and geometry-mode
/// boxes, so both read a colour alike.
pub const CHROMA_BINS: usize = 50;

/// Linear value of an 8-bit sRGB channel (IEC 61966-2-1).
pub fn srgb_to_linear(x: u8) -> f32 {
    let c = f32::from(x) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The chromaticity bin of a linear-RGB colour (or a sum of them), as
/// `r_bin * CHROMA_BINS + g_bin`: shading scales a surface's linear RGB, which keeps this
/// bin, while sRGB's gamma moves a saturated colour's ratios as it darkens. The sum must be
/// positive.
pub fn chroma_bin(linear: [f32; 3]) -> usize {
    let s = linear[0] + linear[1] + linear[2];
    let bin = |x: f32| ((x / s * CHROMA_BINS as f32) as usize).min(CHROMA_BINS - 1);
    bin(linear[0]) * CHROMA_BINS + bin(linear[1])
}

/// The bins within one bin of `bin` on each axis (3 × 3, fewer at the edges), r-major.
pub fn near_chroma_bins(bin: usize) -> impl Iterator<Item = usize> {
    let (r, g) = (bin / CHROMA_BINS, bin % CHROMA_BINS);
    let near = |x: usize| x.saturating_sub(1)..=(x + 1).min(CHROMA_BINS - 1);
    near(r).flat_map(move |i| near(g).map(move |j| i * CHROMA_BINS + j))
}

/// A rigid transform `p_a = rotation · p_b + translation_m`, named `a_from_b` where it is
/// stored (`world_from_cloud`). Row-major rotation (orthonormal, determinant +1), metres;
/// f64, so that a rotation written out and read back stays orthonormal to 1e-12.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RigidTransform {
    /// Rotation matrix, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation, metres.
    pub translation_m: [f64; 3],
}

impl RigidTransform {
    /// The identity (frame a = frame b).
    pub const IDENTITY: RigidTransform = RigidTransform {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation_m: [0.0; 3],
    };

    /// `rotation · p + translation_m`, computed in f64.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        let r = &self.rotation;
        let t = self.translation_m;
        let p = p.map(f64::from);
        std::array::from_fn(|i| (r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + t[i]) as f32)
    }

    /// The inverse transform (`b_from_a` of an `a_from_b`).
    pub fn inverse(&self) -> RigidTransform {
        let r = &self.rotation;
        let t = self.translation_m;
        let rotation: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| r[j][i]));
        let translation_m =
            std::array::from_fn(|i| -(0..3).map(|j| rotation[i][j] * t[j]).sum::<f64>());
        RigidTransform {
            rotation,
            translation_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vector_ops_agree_with_their_definitions() {
        let (a, b) = ([1.0, 2.0, 3.0], [-4.0, 0.5, 2.0]);
        assert_eq!(add(a, b), [-3.0, 2.5, 5.0]);
        assert_eq!(sub(a, b), [5.0, 1.5, 1.0]);
        assert_eq!(scale(a, -2.0), [-2.0, -4.0, -6.0]);
        assert_eq!(dot(a, b), -4.0 + 1.0 + 6.0);
        let c = cross(a, b);
        assert_eq!(c, [2.5, -14.0, 8.5]);
        assert_eq!((dot(c, a), dot(c, b)), (0.0, 0.0));
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(norm([3.0, 0.0, 4.0]), 5.0);
        assert_eq!(normalize([0.0, 3.0, 4.0]), [0.0, 0.6, 0.8]);
        assert_eq!(normalize([0.0; 3]), [0.0; 3]);
        assert_eq!(lerp(a, b, 0.0), a);
        assert_eq!(lerp(a, b, 0.5), [-1.5, 1.25, 2.5]);
        assert_eq!(dist(a, b), norm(sub(a, b)));
    }

    #[test]
    fn chromaticity_keeps_its_bin_under_shading_and_neighbours_stay_in_range() {
        let orange = [215u8, 115, 15].map(srgb_to_linear);
        let shaded = orange.map(|x| x * 0.3);
        assert_eq!(chroma_bin(orange), chroma_bin(shaded));
        assert_ne!(chroma_bin(orange), chroma_bin([1.0, 1.0, 1.0]));
        assert_eq!(chroma_bin([1.0, 0.0, 0.0]), (CHROMA_BINS - 1) * CHROMA_BINS);
        let corner: Vec<usize> = near_chroma_bins(0).collect();
        assert_eq!(corner, vec![0, 1, CHROMA_BINS, CHROMA_BINS + 1]);
        assert_eq!(near_chroma_bins(CHROMA_BINS + 1).count(), 9);
        assert!((srgb_to_linear(255) - 1.0).abs() < 1e-6 && srgb_to_linear(0) == 0.0);
    }

    #[test]
    fn the_frame_around_an_axis_is_orthonormal_right_handed_and_keeps_the_axis() {
        // Axes far from and near world z (the helper switches at |z_z| = 0.9), both signs,
        // and the world axes themselves.
        let axes = [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            normalize([1.0, 2.0, 3.0]),
            normalize([-0.3, 0.1, 0.95]),
            normalize([0.2, -0.9, 0.1]),
        ];
        for z in axes {
            let [x, y, frame_z] = frame_around_unit_axis(z);
            assert_eq!(frame_z, z, "the third axis is the input, unchanged");
            for (name, v) in [("x", x), ("y", y)] {
                assert!(
                    (norm(v) - 1.0).abs() < 1e-6,
                    "|{name}| = {} for {z:?}",
                    norm(v)
                );
            }
            for (pair, d) in [("x.y", dot(x, y)), ("x.z", dot(x, z)), ("y.z", dot(y, z))] {
                assert!(d.abs() < 1e-6, "{pair} = {d} for {z:?}");
            }
            // Right-handed: x × y = z.
            assert!(dist(cross(x, y), z) < 1e-6, "x × y ≠ z for {z:?}");
        }
    }

    #[test]
    fn a_rigid_transform_and_its_inverse_cancel() {
        // 90° about z, then 1 m along x.
        let t = RigidTransform {
            rotation: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            translation_m: [1.0, 0.0, 0.0],
        };
        assert_eq!(t.apply([1.0, 0.0, 2.0]), [1.0, 1.0, 2.0]);
        let back = t.inverse().apply(t.apply([0.3, -0.7, 1.1]));
        assert!(dist(back, [0.3, -0.7, 1.1]) < 1e-6, "{back:?}");
        assert_eq!(RigidTransform::IDENTITY.apply([0.5; 3]), [0.5; 3]);
    }
}
