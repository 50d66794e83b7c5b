//! Skin, hair and clothing colours: palettes, distinct-colour picks and the hand-over
//! object's colour.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::math::uni;
use crate::geometry::{Material, Texture, norm, sub};

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Clothes {
    pub(crate) shirt: Material,
    /// The forearms: the shirt with long sleeves, skin with short ones.
    pub(crate) sleeve: Material,
    pub(crate) trousers: Material,
    pub(crate) skin: Material,
    pub(crate) hair: Material,
    pub(crate) shoes: Material,
    pub(crate) short_sleeves: bool,
}

pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub(crate) fn linear(srgb: [f32; 3]) -> [f32; 3] {
    srgb.map(srgb_to_linear)
}

pub(crate) fn hsv(h: f32, s: f32, v: f32) -> [f32; 3] {
    let h6 = h.rem_euclid(1.0) * 6.0;
    let c = v * s;
    let x = c * (1.0 - ((h6 % 2.0) - 1.0).abs());
    let (r, g, b) = match h6 as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// Distance of two sRGB colours (roughly perceptual).
pub(crate) fn srgb_dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    norm(sub(a, b))
}

pub(crate) fn jitter(rng: &mut ChaCha8Rng, c: [f32; 3], amount: f32) -> [f32; 3] {
    c.map(|x| (x + uni(rng, -amount, amount)).clamp(0.0, 1.0))
}

pub(crate) const SKIN_SRGB: [[f32; 3]; 7] = [
    [1.00, 0.88, 0.77],
    [0.95, 0.76, 0.65],
    [0.88, 0.67, 0.55],
    [0.78, 0.53, 0.40],
    [0.63, 0.40, 0.27],
    [0.47, 0.29, 0.20],
    [0.31, 0.20, 0.14],
];
pub(crate) const HAIR_SRGB: [[f32; 3]; 6] = [
    [0.08, 0.07, 0.06],
    [0.24, 0.16, 0.11],
    [0.42, 0.31, 0.22],
    [0.77, 0.63, 0.39],
    [0.59, 0.27, 0.16],
    [0.63, 0.63, 0.63],
];
pub(crate) const SHOES_SRGB: [[f32; 3]; 5] = [
    [0.10, 0.10, 0.10],
    [0.31, 0.20, 0.12],
    [0.86, 0.86, 0.84],
    [0.43, 0.43, 0.45],
    [0.12, 0.14, 0.27],
];
/// Minimum sRGB distance between shirt, trousers and skin colours, so a parser can tell
/// the torso, the legs and bare skin apart.
pub(crate) const MIN_CLOTHES_DIST: f32 = 0.3;

pub(crate) fn pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[T], fallback: T) -> T {
    if items.is_empty() {
        return fallback;
    }
    let i = ((rng.random::<f32>() * items.len() as f32) as usize).min(items.len() - 1);
    items.get(i).copied().unwrap_or(fallback)
}

pub(crate) fn skin_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    let t = uni(rng, 0.0, (SKIN_SRGB.len() - 1) as f32);
    let i = (t as usize).min(SKIN_SRGB.len() - 2);
    let f = t - i as f32;
    let a = SKIN_SRGB[i];
    let b = SKIN_SRGB[i + 1];
    jitter(rng, [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * f), 0.02)
}

pub(crate) fn shirt_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    if rng.random::<f32>() < 0.15 {
        let v = pick(rng, &[0.12, 0.45, 0.92], 0.45);
        return jitter(rng, [v, v, v], 0.04);
    }
    hsv(uni(rng, 0.0, 1.0), uni(rng, 0.3, 0.85), uni(rng, 0.3, 0.95))
}

pub(crate) fn trousers_srgb(rng: &mut ChaCha8Rng) -> [f32; 3] {
    match (rng.random::<f32>() * 5.0) as u32 {
        0 | 1 => hsv(
            uni(rng, 0.58, 0.64),
            uni(rng, 0.4, 0.75),
            uni(rng, 0.3, 0.65),
        ),
        2 => {
            let v = uni(rng, 0.08, 0.5);
            jitter(rng, [v, v, v], 0.02)
        }
        3 => hsv(
            uni(rng, 0.07, 0.14),
            uni(rng, 0.25, 0.5),
            uni(rng, 0.45, 0.8),
        ),
        _ => hsv(uni(rng, 0.0, 1.0), uni(rng, 0.3, 0.7), uni(rng, 0.2, 0.7)),
    }
}

pub(crate) fn make_clothes(rng: &mut ChaCha8Rng, short_sleeves_prob: f64) -> Clothes {
    let skin = skin_srgb(rng);
    let mut shirt = [0.15, 0.3, 0.75];
    for _ in 0..64 {
        let c = shirt_srgb(rng);
        if srgb_dist(c, skin) >= MIN_CLOTHES_DIST {
            shirt = c;
            break;
        }
    }
    let mut trousers = if srgb_dist(shirt, [0.2, 0.2, 0.22]) >= MIN_CLOTHES_DIST {
        [0.2, 0.2, 0.22]
    } else {
        [0.85, 0.8, 0.6]
    };
    for _ in 0..64 {
        let c = trousers_srgb(rng);
        if srgb_dist(c, skin) >= MIN_CLOTHES_DIST && srgb_dist(c, shirt) >= MIN_CLOTHES_DIST {
            trousers = c;
            break;
        }
    }
    let mut hair = pick(rng, &HAIR_SRGB, HAIR_SRGB[0]);
    hair = jitter(rng, hair, 0.03);
    if srgb_dist(hair, skin) < 0.15 {
        hair = HAIR_SRGB[1];
    }
    let shoes = pick(rng, &SHOES_SRGB, SHOES_SRGB[0]);
    let shoes = jitter(rng, shoes, 0.02);

    let shirt_texture = {
        let r = rng.random::<f32>();
        if r < 0.3 {
            let toward = if shirt.iter().sum::<f32>() > 1.5 {
                [0.0; 3]
            } else {
                [1.0; 3]
            };
            let f = uni(rng, 0.3, 0.5);
            let other = [0, 1, 2].map(|k| shirt[k] + (toward[k] - shirt[k]) * f);
            if srgb_dist(other, skin) >= 0.2 && srgb_dist(other, trousers) >= 0.2 {
                Texture::Stripes {
                    period_m: uni(rng, 0.03, 0.12),
                    other: linear(other),
                }
            } else {
                Texture::Plain
            }
        } else if r < 0.6 {
            Texture::Noise {
                cell_m: uni(rng, 0.02, 0.06),
                amplitude: uni(rng, 0.1, 0.25),
            }
        } else {
            Texture::Plain
        }
    };
    let shirt = Material {
        albedo: linear(shirt),
        texture: shirt_texture,
    };
    let skin = Material {
        albedo: linear(skin),
        texture: Texture::Noise {
            cell_m: 0.02,
            amplitude: 0.05,
        },
    };
    let short_sleeves = f64::from(rng.random::<f32>()) < short_sleeves_prob;
    Clothes {
        shirt,
        sleeve: if short_sleeves { skin } else { shirt },
        trousers: Material {
            albedo: linear(trousers),
            texture: Texture::Noise {
                cell_m: uni(rng, 0.01, 0.03),
                amplitude: uni(rng, 0.08, 0.2),
            },
        },
        skin,
        hair: Material {
            albedo: linear(hair),
            texture: Texture::Noise {
                cell_m: 0.006,
                amplitude: 0.2,
            },
        },
        shoes: Material::plain(linear(shoes)),
        short_sleeves,
    }
}

// ---------------------------------------------------------------------------------------
// Motion through the area.

/// A plain colour for the hand-over object that differs most from both people's clothes
/// and skin (linear RGB).
pub(crate) fn object_color(clothes: &[&Clothes]) -> [f32; 3] {
    const CANDIDATES: [[f32; 3]; 5] = [
        [0.85, 0.35, 0.02],
        [0.02, 0.55, 0.65],
        [0.85, 0.75, 0.02],
        [0.65, 0.03, 0.5],
        [0.08, 0.55, 0.08],
    ];
    let mut best = CANDIDATES[0];
    let mut best_d = f32::NEG_INFINITY;
    for c in CANDIDATES {
        let mut dmin = f32::INFINITY;
        for cl in clothes {
            for m in [cl.shirt, cl.trousers, cl.skin, cl.sleeve] {
                dmin = dmin.min(norm(sub(c, m.albedo)));
            }
        }
        if dmin > best_d {
            best_d = dmin;
            best = c;
        }
    }
    best
}
