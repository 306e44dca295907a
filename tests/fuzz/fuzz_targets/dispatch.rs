#![no_main]
//! See `gonio_tests::fuzz::dispatch`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| gonio_tests::fuzz::dispatch(data));
