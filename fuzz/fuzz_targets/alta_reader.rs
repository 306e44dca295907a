#![no_main]
//! See `gonio_frames::fuzz::alta_reader`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| gonio_frames::fuzz::alta_reader(data));
