//! The head's firmware image for the STM32F405RG: wires the peripherals to the
//! hardware-independent core (`gonio_firmware`) and runs it.
//!
//! On the host this binary is a one-line program saying how to build it; the
//! tests and the simulated head drive the same core through the library.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod chip;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("gonio-head is the STM32F405 image: build it with `cargo head` (thumbv7em-none-eabihf) and flash it with `cargo flash`");
    std::process::exit(2);
}
