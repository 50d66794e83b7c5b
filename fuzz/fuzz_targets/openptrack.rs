//! libFuzzer target `openptrack`: see [`bodyseg_fuzz::openptrack`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::openptrack(data));
