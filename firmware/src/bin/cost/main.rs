//! `gonio-cost`: the core's hot paths as the chip image builds them
//! (thumbv7em-none-eabihf, the release profile), each run between two calls
//! of [`mark`]. `chip-bench` runs this image on an emulated Cortex-M4F
//! (`python3 -m board.emulate` in `tests/chip`) and counts the instructions
//! between the marks: the chip's costs in instructions, not host nanoseconds
//! scaled by a guess.
//!
//! On the host this binary is a one-line program that says so.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod probes;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("gonio-cost runs on an emulated Cortex-M4F: `cargo run --release -p gonio-bench --bin chip-bench`");
    std::process::exit(2);
}
