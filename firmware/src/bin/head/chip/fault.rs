//! What happens when the firmware itself fails. A panic (panic-probe prints
//! it over defmt, then executes `udf`) and every other fault (bus, memory,
//! usage) end in the HardFault handler below: it switches the laser off and
//! disables the drivers at once, then waits for the independent watchdog
//! (watchdog.rs), which restarts the chip within a second; the restarted
//! head reports the watchdog reset (E304) to the host.

use cortex_m_rt::{exception, ExceptionFrame};

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    super::pins::force_safe_state();
    loop {
        cortex_m::asm::nop();
    }
}
