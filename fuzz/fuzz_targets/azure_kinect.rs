//! libFuzzer target `azure_kinect`: see [`bodyseg_fuzz::azure_kinect`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::azure_kinect(data));
