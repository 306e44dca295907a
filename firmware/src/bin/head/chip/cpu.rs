//! Core and bus settings that embassy-stm32 0.5 leaves at their reset values.
//!
//! - Flash accelerator: `init` writes the wait states (LATENCY) only; the
//!   ART instruction and data caches and the prefetch buffer stay off, and
//!   code runs from flash at roughly half speed at 168 MHz (RM0090 §3.5.2).
//! - Interrupt priorities: every interrupt starts at priority 0, so none can
//!   pre-empt another. The step timer must pre-empt everything (a late STEP
//!   is a lost microstep at speed), the E-STOP and the guard come next
//!   (each cuts the laser; neither pre-empts the other), then the
//!   conversions' DMA and the time driver, and USB last (its host retries).
//!   Lower numbers pre-empt higher ones; the serve loop runs in thread mode.
//! - Watchdog under a debugger: left counting while the core is halted
//!   (DBGMCU's freeze bit stays clear). probe-rs halts on a HardFault,
//!   before the handler can drive the safe state; the watchdog's reset
//!   then brings the pins back safe within a second. A debugging session
//!   that needs to hold a breakpoint sets DBGMCU_APB1_FZ.DBG_IWDG_STOP
//!   itself.

use embassy_stm32::interrupt::{self, InterruptExt, Priority};
use embassy_stm32::pac;

/// Priorities of the interrupts the head uses (P0 highest).
pub const STEP_TIMER: Priority = Priority::P0;
pub const ESTOP: Priority = Priority::P1;
pub const GUARD: Priority = Priority::P1;
pub const DMA: Priority = Priority::P2;
pub const TIME_DRIVER: Priority = Priority::P2;
pub const USB: Priority = Priority::P3;

/// Applies the settings above; call right after `embassy_stm32::init`,
/// before any task is spawned.
pub fn setup() {
    pac::FLASH.acr().modify(|w| {
        w.set_prften(true);
        w.set_icen(true);
        w.set_dcen(true);
    });
    interrupt::TIM5.set_priority(STEP_TIMER);
    interrupt::EXTI15_10.set_priority(ESTOP);
    interrupt::TIM7.set_priority(GUARD);
    interrupt::TIM4.set_priority(TIME_DRIVER);
    interrupt::OTG_FS.set_priority(USB);
}
