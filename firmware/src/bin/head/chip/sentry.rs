//! The E-STOP input and the head's timer, for the core's serve loop.
//!
//! The E-STOP is a normally-closed switch from PB12 to ground with the
//! internal pull-up: pressed, or its wire cut, the input reads high. Its
//! rising edge is latched in hardware terms: EXTI12 pends on the edge
//! whatever the firmware is doing, and its interrupt (priority just below
//! the step timer's, cpu.rs) drives the laser enable and the chop low at
//! once (`pins::cut_laser`) and counts the opening. The serve loop trips on an opening it has not handled yet
//! at every wait ([`Sentry::until`]), so an opening shorter than a turn of
//! the loop, or one that comes while no wait is armed (a sweep's blocked
//! publish), still stops the head. The trip is not debounced (the first
//! edge stops the head); re-arming is: the core asks for the input to read
//! closed for 20 ms of the embassy timer (TIM4, 1 MHz) before a continue is
//! accepted (`serve::ESTOP_DEBOUNCE_US`), forgetting the bounces of the
//! release ([`Sentry::rearm`]).
//!
//! The E-STOP chain should also cut the laser's and the drivers' enables in
//! series, in hardware (docs/faults.md): this is the firmware's half.

use core::sync::atomic::{AtomicU32, Ordering};
use embassy_futures::select::{select, Either};
use embassy_stm32::gpio::{Input, Pull};
use embassy_stm32::interrupt::typelevel::{Handler, Interrupt, EXTI15_10};
use embassy_stm32::pac;
use embassy_stm32::peripherals::PB12;
use embassy_stm32::Peri;
use embassy_sync::waitqueue::AtomicWaker;
use embassy_time::{Instant, Timer};
use gonio_firmware::hw::{Sentry, Wake};

/// When the serve loop last showed it was alive (ms of uptime, wrapping):
/// the watchdog's pet task reads it (`watchdog.rs`).
pub static ALIVE_MS: AtomicU32 = AtomicU32::new(0);

/// Records that the serve loop (or the wait between sessions) is alive.
pub fn alive() {
    ALIVE_MS.store(Instant::now().as_millis() as u32, Ordering::Relaxed);
}

/// E-STOP openings (rising edges of PB12) since boot, wrapping.
static OPENINGS: AtomicU32 = AtomicU32::new(0);
static OPENED: AtomicWaker = AtomicWaker::new();

/// EXTI line of PB12, and SYSCFG's port code for port B (RM0090 §9.2.6).
const LINE: usize = 12;
const PORT_B: u8 = 1;

/// EXTI lines 10–15: the E-STOP's opening.
pub struct EstopInterrupt;

impl Handler<EXTI15_10> for EstopInterrupt {
    unsafe fn on_interrupt() {
        if pac::EXTI.pr(0).read().line(LINE) {
            pac::EXTI.pr(0).write(|w| w.set_line(LINE, true));
            // Laser enable and chop low at once, whoever owns the pins.
            super::pins::cut_laser();
            super::guard::arm_backstop();
            OPENINGS.fetch_add(1, Ordering::Release);
            OPENED.wake();
        }
    }
}

pub struct ChipSentry {
    input: Input<'static>,
    /// The openings the serve loop has handled.
    handled: u32,
}

impl ChipSentry {
    /// Takes PB12 as the E-STOP input and latches its rising edge.
    pub fn new(pin: Peri<'static, PB12>) -> Self {
        let input = Input::new(pin, Pull::Up);
        // Nothing else writes SYSCFG or the EXTI (no embassy EXTI driver).
        pac::SYSCFG.exticr(LINE / 4).modify(|w| w.set_exti(LINE % 4, PORT_B));
        pac::EXTI.rtsr(0).modify(|w| w.set_line(LINE, true));
        pac::EXTI.ftsr(0).modify(|w| w.set_line(LINE, false));
        pac::EXTI.pr(0).write(|w| w.set_line(LINE, true));
        pac::EXTI.imr(0).modify(|w| w.set_line(LINE, true));
        EXTI15_10::unpend();
        // SAFETY: the handler is bound in `Irqs` and shares only atomics.
        unsafe { EXTI15_10::enable() };
        let handled = OPENINGS.load(Ordering::Acquire);
        ChipSentry { input, handled }
    }
}

impl Sentry for ChipSentry {
    fn estop_open(&mut self) -> bool {
        self.input.is_high() || OPENINGS.load(Ordering::Acquire) != self.handled
    }

    fn rearm(&mut self) {
        self.handled = OPENINGS.load(Ordering::Acquire);
    }

    fn rearmed(&mut self) -> bool {
        super::guard::disarm_backstop()
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
        let input = &self.input;
        let handled = &mut self.handled;
        let open = core::future::poll_fn(|cx| {
            if !estop {
                return core::task::Poll::Pending;
            }
            OPENED.register(cx.waker());
            let now = OPENINGS.load(Ordering::Acquire);
            if now != *handled || input.is_high() {
                *handled = now;
                core::task::Poll::Ready(())
            } else {
                core::task::Poll::Pending
            }
        });
        match select(open, deadline).await {
            Either::First(()) => Wake::EStop,
            Either::Second(()) => Wake::Deadline,
        }
    }
}
