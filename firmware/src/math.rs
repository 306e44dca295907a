//! Single-precision functions the Cortex-M4F has in hardware.
//!
//! `libm::sqrtf` is a software square root (about 150 instructions on the
//! chip, measured by `chip-bench`); the FPU's VSQRT is one instruction of 14
//! cycles. Both are correctly rounded (IEEE 754), so the chip and the host
//! compute the same value. `core` has no stable `sqrt` for `f32` and inline
//! assembly cannot name S registers on this target without an unstable
//! feature, hence a two-instruction function in global assembly (the
//! hard-float ABI passes and returns the value in `s0`).

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
core::arch::global_asm!(
    ".section .text.gonio_vsqrtf,\"ax\",%progbits",
    ".fpu fpv4-sp-d16",
    ".global gonio_vsqrtf",
    ".type gonio_vsqrtf,%function",
    ".thumb_func",
    "gonio_vsqrtf:",
    "vsqrt.f32 s0, s0",
    "bx lr",
);

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
extern "C" {
    fn gonio_vsqrtf(x: f32) -> f32;
}

/// `√x`, correctly rounded.
#[inline]
pub fn sqrtf(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        // SAFETY: a leaf function of two instructions that reads and writes
        // `s0` only; the FPU is enabled by cortex-m-rt's reset handler.
        unsafe { gonio_vsqrtf(x) }
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}
