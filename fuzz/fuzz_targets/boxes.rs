//! libFuzzer target `boxes`: see [`bodyseg_fuzz::boxes`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::boxes(data));
