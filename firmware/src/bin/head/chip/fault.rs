//! What happens when the firmware itself fails. A panic drives the safe
//! state first, then logs over defmt and executes `udf`; that and every
//! other fault (bus, memory, usage) end in the HardFault handler below,
//! which drives the safe state (again) and waits for the independent
//! watchdog (watchdog.rs) to restart the chip within a second; the
//! restarted head reports the watchdog reset (E304) to the host.
//!
//! The safe state comes before the log: with a probe attached, probe-rs
//! halts the core on the HardFault that `udf` raises, and a log that hung
//! or a halt before the handler must not leave the laser on. The watchdog
//! keeps counting under a debugger's halt (cpu.rs), so a halted head is
//! restarted too.

use cortex_m_rt::{exception, ExceptionFrame};

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    super::pins::force_safe_state();
    defmt::error!("{}", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    super::pins::force_safe_state();
    loop {
        cortex_m::asm::nop();
    }
}
