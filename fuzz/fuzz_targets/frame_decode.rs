#![no_main]
//! See `gonio_frames::fuzz::frame_decode`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| gonio_frames::fuzz::frame_decode(data));
