//! libFuzzer target `ros_camera_info`: see [`bodyseg_fuzz::ros_camera_info`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodyseg_fuzz::ros_camera_info(data));
