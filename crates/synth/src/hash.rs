//! Counter-based random numbers: a value is a pure function of (seed, stream, index), so
//! pixels rendered in parallel get the same noise in any order and the output is
//! byte-identical for a seed.

/// SplitMix64's finaliser: a well-mixed 64-bit hash (core's [`splitmix64`]).
pub use bodyseg_core::rng::splitmix64 as mix;

/// Hash of a seed and up to three counters.
#[inline]
pub fn hash(seed: u64, a: u64, b: u64, c: u64) -> u64 {
    mix(mix(mix(seed ^ mix(a)) ^ b.wrapping_mul(0xD6E8_FEB8_6659_FD93)) ^ c)
}

/// Uniform in `[0, 1)` from a hash.
#[inline]
pub fn unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A standard normal value from a hash (Box-Muller on its two halves).
#[inline]
pub fn gaussian(h: u64) -> f32 {
    let u1 = ((h >> 40) as f32 + 0.5) * (1.0 / (1u64 << 24) as f32);
    let u2 = ((h & 0xFF_FFFF) as f32) * (1.0 / (1u64 << 24) as f32);
    (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_has_unit_variance_and_zero_mean() {
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let g = f64::from(gaussian(hash(7, i, 1, 2)));
            s += g;
            s2 += g * g;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        // 200k samples: standard error of the mean 0.0022, of the variance ~0.003.
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
        let u: f64 = (0..n)
            .map(|i| f64::from(unit(hash(1, i, 0, 0))))
            .sum::<f64>()
            / n as f64;
        assert!((u - 0.5).abs() < 0.005, "{u}");
    }
}
