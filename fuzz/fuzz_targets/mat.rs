//! libFuzzer target `mat`: see [`bodyseg_fuzz::mat`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::mat(data));
