//! Helpers shared by the calib crate's test binaries (each includes what it uses).
#![allow(dead_code)]

use bodyseg_calib::Distortion;

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

/// The colour sensor's rational distortion of Azure Kinect 001514394512
/// (`tests/fixtures/calib/azure_kinect/pyk4a_calibration.json`, `ModelParameters` 4..13
/// in OpenCV's order k1 k2 p1 p2 k3 k4 k5 k6).
#[allow(clippy::excessive_precision)]
pub const AZURE_COLOR_DISTORTION: Distortion = Distortion::Rational([
    0.33012130856513977,
    -2.489396572113037,
    -0.00016178244550246745,
    -0.00012944525224156678,
    1.453670859336853,
    0.20891207456588745,
    -2.302915096282959,
    1.3751275539398193,
]);
