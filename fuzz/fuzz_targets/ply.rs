//! libFuzzer target `ply`: see [`bodyseg_fuzz::ply`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::ply(data));
