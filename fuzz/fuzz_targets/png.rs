//! libFuzzer target `png`: see [`bodyseg_fuzz::png`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::png(data));
