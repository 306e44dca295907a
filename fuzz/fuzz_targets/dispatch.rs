#![no_main]
//! See `gonio_frames::fuzz::dispatch`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| gonio_frames::fuzz::dispatch(data));
