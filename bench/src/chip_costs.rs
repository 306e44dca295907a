//! What `chip-bench` leaves for the other benchmarks: its figures, in the
//! build's target folder, and the Cortex-M4's cost of taking an interrupt.

use std::path::PathBuf;

/// Exception entry and exit of the Cortex-M4 (cycles, tail-chaining aside).
pub const EXCEPTION_CYCLES: u64 = 24;

/// The build's target folder (`CARGO_TARGET_DIR`, else `target/`).
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target"), PathBuf::from)
}

/// Where `chip-bench` writes its JSON object.
pub fn report_path() -> PathBuf {
    target_dir().join("chip-bench.json")
}
