//! libFuzzer target `config`: see [`bodyseg_fuzz::config`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::config(data));
