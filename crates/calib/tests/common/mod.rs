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

/// The crate's promise for undistortion, pixels.
pub const ROUND_TRIP_TOL_PX: f64 = 1e-6;

/// Fails naming `what` when a worst round trip (|project(unproject(u, v)·z) − (u, v)|,
/// pixels) breaks [`ROUND_TRIP_TOL_PX`].
pub fn assert_round_trip(worst_px: f64, what: &str) {
    assert!(
        worst_px < ROUND_TRIP_TOL_PX,
        "{what}: worst round trip {worst_px:e} px"
    );
}

/// The image's four outer corners: pixel borders at -0.5 and size - 0.5.
pub fn outer_corners(intr: &bodyseg_calib::Intrinsics) -> [[f64; 2]; 4] {
    let (w, h) = (f64::from(intr.width), f64::from(intr.height));
    [
        [-0.5, -0.5],
        [w - 0.5, -0.5],
        [-0.5, h - 0.5],
        [w - 0.5, h - 0.5],
    ]
}
