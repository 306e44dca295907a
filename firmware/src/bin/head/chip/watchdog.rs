//! The independent watchdog (IWDG, its own 32 kHz clock): a task pets it
//! every 250 ms, but only while the serve loop keeps showing it is alive
//! (`sentry::ALIVE_MS`, at least every 250 ms: the core wakes its waits for
//! it). So it fires if the executor stops running tasks — a busy loop, a
//! panic or a fault (fault.rs has made the pins safe and waits for it) — and
//! also if the serve loop is stuck in a future that never ends (a wait
//! without a deadline, such as a send with no timeout). The chip then
//! restarts, and restarting means the safe state: the pins come up with the
//! laser off and the drivers disabled before anything else runs, and the
//! head reports the watchdog reset in its status. A step timer that stops is
//! the core's business: every move has its own deadline (a stall fault).

use super::sentry;
use core::sync::atomic::Ordering;
use embassy_executor::Spawner;
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::Peri;
use embassy_time::{Instant, Timer};

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

/// How old the serve loop's last sign of life may be (ms) for a pet.
const ALIVE_WITHIN_MS: u32 = 750;

#[embassy_executor::task]
async fn pet(mut wdg: IndependentWatchdog<'static, IWDG>) -> ! {
    loop {
        let now = Instant::now().as_millis() as u32;
        if now.wrapping_sub(sentry::ALIVE_MS.load(Ordering::Relaxed)) <= ALIVE_WITHIN_MS {
            wdg.pet();
        }
        Timer::after_millis(PET_MS).await;
    }
}

/// Starts the watchdog; from here on it cannot be stopped.
pub fn start(spawner: &Spawner, iwdg: Peri<'static, IWDG>) {
    sentry::alive();
    let mut wdg = IndependentWatchdog::new(iwdg, TIMEOUT_US);
    wdg.unleash();
    spawner.must_spawn(pet(wdg));
}
