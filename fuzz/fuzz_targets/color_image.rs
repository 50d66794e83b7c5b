//! libFuzzer target `color_image`: see [`bodyseg_fuzz::color_image`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::color_image(data));
