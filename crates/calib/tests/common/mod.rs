//! Helpers shared by the calib crate's test binaries (each includes what it uses).
#![allow(dead_code)]

/// Seed of the random tests: `BODYSEG_TEST_SEED` overrides it; failures print it.
pub fn seed() -> u64 {
    std::env::var("BODYSEG_TEST_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5EED_CA11_B0D1_5E65)
}

/// xorshift64* (core's): enough randomness to sample pixels, points and depths.
#[allow(unused_imports)] // not every test binary that includes this module samples
pub use bodyseg_core::rng::XorShift64Star as Rng;
