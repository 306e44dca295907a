#![no_main]
//! See `gonio_frames::fuzz::csv_reader`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| gonio_frames::fuzz::csv_reader(data));
