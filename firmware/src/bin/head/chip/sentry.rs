//! The E-STOP input and the head's timer, for the core's serve loop.
//!
//! The E-STOP is a normally-closed switch from PB12 to ground with the
//! internal pull-up: pressed, or its wire cut, the input reads high. EXTI12
//! wakes the serve loop on the rising edge, so the trip is not debounced at
//! all (the first edge stops the head); re-arming is: the core asks for the
//! input to read closed for 20 ms of the embassy timer (TIM4, 1 MHz) before
//! a continue is accepted (`serve::ESTOP_DEBOUNCE_US`).

use core::sync::atomic::{AtomicU32, Ordering};
use embassy_futures::select::{select, Either};
use embassy_stm32::exti::ExtiInput;
use embassy_time::{Instant, Timer};
use gonio_firmware::hw::{Sentry, Wake};

/// When the serve loop last showed it was alive (ms of uptime, wrapping):
/// the watchdog's pet task reads it (`watchdog.rs`).
pub static ALIVE_MS: AtomicU32 = AtomicU32::new(0);

/// Records that the serve loop (or the wait between sessions) is alive.
pub fn alive() {
    ALIVE_MS.store(Instant::now().as_millis() as u32, Ordering::Relaxed);
}

pub struct ChipSentry {
    pub estop: ExtiInput<'static>,
}

impl Sentry for ChipSentry {
    fn estop_open(&mut self) -> bool {
        self.estop.is_high()
    }

    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    fn alive(&mut self) {
        alive();
    }

    async fn until(&mut self, deadline_us: Option<u64>, estop: bool) -> Wake {
        let deadline = async {
            match deadline_us {
                Some(t) => Timer::at(Instant::from_micros(t)).await,
                None => core::future::pending().await,
            }
        };
        let open = async {
            if estop {
                self.estop.wait_for_high().await
            } else {
                core::future::pending().await
            }
        };
        match select(open, deadline).await {
            Either::First(()) => Wake::EStop,
            Either::Second(()) => Wake::Deadline,
        }
    }
}
