//! libFuzzer target `pcd`: see [`bodyseg_fuzz::pcd`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::pcd(data));
