//! Colour of a surface point: texture, Lambertian shading under a key light, a fill
//! light and the camera's own light, sensor noise, sRGB encoding.

use crate::geometry::{Material, Texture, V3, dot, normalize};
use crate::hash::{hash, mix, unit};

/// Direction towards the key light (world, unit): high, from the +x −y side.
fn key_light() -> V3 {
    normalize([0.35, -0.45, 1.0])
}

/// The albedo of `material` at world point `p`.
pub fn albedo(material: &Material, p: V3) -> [f32; 3] {
    let a = material.albedo;
    match material.texture {
        Texture::Plain => a,
        Texture::Stripes { period_m, other } => {
            if ((p[2] / period_m).floor() as i64) & 1 == 0 {
                a
            } else {
                other
            }
        }
        Texture::Checker { cell_m, other } => {
            let i = (p[0] / cell_m).floor() as i64
                + (p[1] / cell_m).floor() as i64
                + (p[2] / cell_m).floor() as i64;
            if i & 1 == 0 { a } else { other }
        }
        Texture::Noise { cell_m, amplitude } => {
            let n = value_noise([p[0] / cell_m, p[1] / cell_m, p[2] / cell_m]);
            let k = 1.0 + amplitude * (2.0 * n - 1.0);
            [a[0] * k, a[1] * k, a[2] * k]
        }
    }
}

/// Smooth 3D value noise in `[0, 1]` (trilinear with smoothstep over hashed lattice
/// values).
pub fn value_noise(p: V3) -> f32 {
    let f = [p[0].floor(), p[1].floor(), p[2].floor()];
    let i = [f[0] as i64, f[1] as i64, f[2] as i64];
    let mut w = [p[0] - f[0], p[1] - f[1], p[2] - f[2]];
    for x in &mut w {
        *x = *x * *x * (3.0 - 2.0 * *x);
    }
    let lattice = |dx: i64, dy: i64, dz: i64| {
        unit(mix(((i[0] + dx) as u64).wrapping_mul(0x9E37_79B9)
            ^ ((i[1] + dy) as u64).wrapping_mul(0x85EB_CA77_0000)
            ^ ((i[2] + dz) as u64).wrapping_mul(0xC2B2_AE3D_0000_0000)))
    };
    let mut acc = 0.0;
    for c in 0..8i64 {
        let (dx, dy, dz) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
        let wx = if dx == 1 { w[0] } else { 1.0 - w[0] };
        let wy = if dy == 1 { w[1] } else { 1.0 - w[1] };
        let wz = if dz == 1 { w[2] } else { 1.0 - w[2] };
        acc += wx * wy * wz * lattice(dx, dy, dz);
    }
    acc
}

/// Linear radiance of a point with `normal` (unit, facing the camera) seen along `view`
/// (unit, from the camera).
pub fn shade(material: &Material, p: V3, normal: V3, view: V3) -> [f32; 3] {
    let a = albedo(material, p);
    let key = dot(normal, key_light()).max(0.0);
    // Hemisphere fill: brighter when facing up.
    let fill = 0.5 + 0.5 * normal[2];
    let head = (-dot(normal, view)).max(0.0);
    let light = 0.18 + 0.55 * key + 0.17 * fill + 0.25 * head;
    [a[0] * light, a[1] * light, a[2] * light]
}

/// Entries of the linear → sRGB table (14 bits: the darkest step is < 1 sRGB level
/// apart from the exact curve's at 8 bits above linear 0.0005).
const SRGB_LUT_SIZE: usize = 1 << 14;

fn srgb_lut() -> &'static [u8; SRGB_LUT_SIZE] {
    static LUT: std::sync::OnceLock<Box<[u8; SRGB_LUT_SIZE]>> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        let mut t = Box::new([0u8; SRGB_LUT_SIZE]);
        for (i, v) in t.iter_mut().enumerate() {
            let x = i as f32 / (SRGB_LUT_SIZE - 1) as f32;
            // The γ ≈ 2.2 approximation of the sRGB curve is enough for a synthetic sensor.
            *v = (x.powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
        }
        t
    })
}

/// sRGB byte of a linear value, with sensor noise `noise` (linear units) added.
#[inline]
pub fn encode(linear: f32, noise: f32) -> u8 {
    let v = (linear + noise).clamp(0.0, 1.0);
    srgb_lut()[(v * (SRGB_LUT_SIZE - 1) as f32 + 0.5) as usize]
}

/// Per-pixel sensor noise of the three channels, linear units (uniform, ±1% of full
/// scale), from one hash.
#[inline]
pub fn sensor_noise(seed: u64, pixel: u64) -> [f32; 3] {
    let h = hash(seed, pixel, 0x5E45, 0);
    let part = |shift: u32| (((h >> shift) & 0x1F_FFFF) as f32 / 2_097_152.0 - 0.5) * 0.02;
    [part(0), part(21), part(42)]
}
