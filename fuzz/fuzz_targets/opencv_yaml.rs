//! libFuzzer target `opencv_yaml`: see [`bodyseg_fuzz::opencv_yaml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::opencv_yaml(data));
