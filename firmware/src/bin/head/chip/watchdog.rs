//! The independent watchdog (IWDG, its own 32 kHz clock): a task pets it
//! every 250 ms, so it fires only if the executor stops running tasks — a
//! busy loop, a panic or a fault (fault.rs has made the pins safe and
//! waits for it). The chip then restarts, and restarting means the safe
//! state: the pins come up with the laser off and the drivers disabled
//! before anything else runs, and the head reports the watchdog reset in its
//! status. Futures that never complete are the core's business: every move
//! and measurement it awaits has its own deadline.

use embassy_executor::Spawner;
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::Peri;
use embassy_time::Timer;

/// The watchdog's timeout (µs): four missed pets.
const TIMEOUT_US: u32 = 1_000_000;
const PET_MS: u64 = 250;

/// Whether the last reset was the watchdog's; clears the reset flags.
pub fn reset_cause() -> bool {
    let rcc = embassy_stm32::pac::RCC;
    let by_watchdog = rcc.csr().read().wdgrstf();
    rcc.csr().modify(|w| w.set_rmvf(true));
    by_watchdog
}

#[embassy_executor::task]
async fn pet(mut wdg: IndependentWatchdog<'static, IWDG>) -> ! {
    loop {
        wdg.pet();
        Timer::after_millis(PET_MS).await;
    }
}

/// Starts the watchdog; from here on it cannot be stopped.
pub fn start(spawner: &Spawner, iwdg: Peri<'static, IWDG>) {
    let mut wdg = IndependentWatchdog::new(iwdg, TIMEOUT_US);
    wdg.unleash();
    spawner.must_spawn(pet(wdg));
}
