//! Handlers that make the pins safe and restart the chip at once, leaving
//! their cause for the head that comes up (`gonio_firmware::restart`):
//!
//! - the NMI, raised by the clock security system when the crystal stops:
//!   the core is then on the HSI, ten times slower, with no PLL and no
//!   USB clock, so nothing but a restart (onto the HSI, the laser
//!   inhibited, `clocks.rs`) makes sense;
//! - the default handler, for an interrupt enabled with no handler of
//!   ours: cortex-m-rt's own spins in the interrupt at its priority (0 at
//!   reset, above the guard), the pins latched as they were.
//!
//! Both drive the pins first, with single stores ([`super::pins::force_safe_state`]).

use core::mem::MaybeUninit;
use core::ptr::{addr_of_mut, read_volatile, write_volatile};
use gonio_firmware::restart;
use gonio_shared::Fault;

/// The cause's words, in RAM the startup code neither zeroes nor loads.
#[link_section = ".uninit.gonio_restart"]
static mut CAUSE: MaybeUninit<[u32; 2]> = MaybeUninit::uninit();

fn restart_for(cause: Fault) -> ! {
    super::pins::force_safe_state();
    if let Some(words) = restart::encode(cause) {
        // SAFETY: written only here, where nothing runs on after it, and
        // read once at boot, before any interrupt is enabled.
        unsafe { write_volatile(addr_of_mut!(CAUSE).cast::<[u32; 2]>(), words) };
    }
    cortex_m::peripheral::SCB::sys_reset()
}

/// The cause the last restart left, if any; cleared, so it is told once.
pub fn take_cause() -> Option<Fault> {
    let words = addr_of_mut!(CAUSE).cast::<[u32; 2]>();
    // SAFETY: any bit pattern is a valid [u32; 2]; this runs at boot, before
    // the handlers that write it can run.
    unsafe {
        let cause = restart::decode(read_volatile(words));
        write_volatile(words, [0, 0]);
        cause
    }
}

#[cortex_m_rt::exception]
unsafe fn NonMaskableInt() -> ! {
    // The clock security system is the NMI's only source on this board;
    // CSSC drops its request.
    embassy_stm32::pac::RCC.cir().write(|w| w.set_cssc(true));
    restart_for(Fault::ClockStopped)
}

#[cortex_m_rt::exception]
unsafe fn DefaultHandler(irqn: i16) -> ! {
    restart_for(Fault::StrayInterrupt(irqn))
}
