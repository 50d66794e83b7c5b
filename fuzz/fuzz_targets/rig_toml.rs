//! libFuzzer target `rig_toml`: see [`bodyseg_fuzz::rig_toml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::rig_toml(data));
