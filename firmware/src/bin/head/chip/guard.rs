//! The guard (`gonio_firmware::guard`) on the chip: TIM7's update interrupt
//! at 8 kHz, at the E-STOP's priority (below the step timer, above the DMA,
//! the time driver and USB: cpu.rs), and the thread's loop it watches.
//!
//! At each tick the handler reads the laser enable (PB0's output register),
//! the thread loop's turns, and, while a measurement's conversion chain is
//! watched, DMA2 stream 0's NDTR; on a trip it drives the laser enable and
//! the chop low (`pins::cut_laser`), as the E-STOP's handler does, and wakes
//! the period reader, which
//! fails the read at once. The trip holds until the thread sets the laser
//! enable high again: a measurement retried after a trip (`Head::acquire`
//! retries a lost block once) finds the laser enable still low and fails
//! too, rather than measuring dark. The drivers are left to the thread's
//! orderly stop, but for the E-STOP's backstop: armed by the E-STOP's
//! interrupt, it disables the drivers (their EN high) should the thread's
//! stop not have within `backstop_ticks` (`gonio_firmware::guard::backstop`).
//!
//! The thread's loop is embassy's thread-mode executor loop (poll, then
//! WFE) with the turn counted: `embassy_executor::Executor::run` has no hook
//! for it, so the loop is written here on the raw executor.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU16, AtomicU32, Ordering};
use embassy_executor::raw;
use embassy_stm32::interrupt::typelevel::{Handler, Interrupt, TIM7 as Tim7Irq};
use embassy_stm32::pac;
use embassy_stm32::peripherals::TIM7;
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::low_level::Timer;
use embassy_stm32::Peri;
use embassy_sync::waitqueue::AtomicWaker;
use gonio_firmware::guard::{backstop, backstop_ticks, ChainWatch, Guard, TICK_HZ};

/// The thread loop's turns, wrapping.
static TURNS: AtomicU32 = AtomicU32::new(0);
/// The watched chain, packed (`ChainWatch::pack`); 0 when none runs.
static CHAIN: AtomicU32 = AtomicU32::new(0);
/// The thread's count of chain starts (the watch's generation).
static STARTS: AtomicU16 = AtomicU16::new(0);
static TRIPPED: AtomicBool = AtomicBool::new(false);
/// The E-STOP backstop's state (`guard::backstop`), and what an opening
/// arms it with.
static BACKSTOP: AtomicU32 = AtomicU32::new(0);
static BACKSTOP_ARMED: AtomicU32 = AtomicU32::new(0);
/// Whether the backstop disabled the drivers since it was last disarmed.
static BACKSTOP_FIRED: AtomicBool = AtomicBool::new(false);
static TRIP: AtomicWaker = AtomicWaker::new();

/// The guard's memory, touched by TIM7's handler only.
struct HandlerState(UnsafeCell<Guard>);
// SAFETY: only TIM7's handler uses it, and a handler does not pre-empt itself.
unsafe impl Sync for HandlerState {}
static STATE: HandlerState = HandlerState(UnsafeCell::new(Guard::new()));

/// Whether any driver is enabled: its active-low EN (PC2, PC6, PC10) low in
/// the output register.
fn drivers_enabled() -> bool {
    let odr = pac::GPIOC.odr().read().0;
    odr & (1 << 2 | 1 << 6 | 1 << 10) != 1 << 2 | 1 << 6 | 1 << 10
}

/// The laser enable (PB0) as driven: its output register, whoever set it.
fn laser_enabled() -> bool {
    pac::GPIOB.odr().read().odr(0) == pac::gpio::vals::Odr::HIGH
}

pub struct GuardInterrupt;

impl Handler<Tim7Irq> for GuardInterrupt {
    unsafe fn on_interrupt() {
        pac::TIM7.sr().write(|w| w.set_uif(false));
        let laser_on = laser_enabled();
        let chain = ChainWatch::unpack(CHAIN.load(Ordering::Acquire)).map(|w| (w, pac::DMA2.st(0).ndtr().read().ndt()));
        // SAFETY: see `HandlerState`.
        let guard = unsafe { &mut *STATE.0.get() };
        if let Some(trip) = guard.tick(laser_on, TURNS.load(Ordering::Relaxed), chain) {
            super::pins::cut_laser();
            TRIPPED.store(true, Ordering::Release);
            TRIP.wake();
            defmt::error!("guard: laser cut, {}", defmt::Debug2Format(&trip));
        }
        let state = BACKSTOP.load(Ordering::Relaxed);
        if state != 0 {
            let (next, cut) = backstop(state, drivers_enabled());
            BACKSTOP.store(next, Ordering::Relaxed);
            if cut {
                super::pins::disable_drivers();
                BACKSTOP_FIRED.store(true, Ordering::Relaxed);
                defmt::error!("guard: drivers disabled, the E-STOP's stop overdue");
            }
        }
    }
}

/// An E-STOP opening: the backstop counts from now, unless it already runs.
/// Called from the E-STOP's interrupt, at the guard's priority.
pub fn arm_backstop() {
    let _ = BACKSTOP.compare_exchange(0, BACKSTOP_ARMED.load(Ordering::Relaxed), Ordering::Relaxed, Ordering::Relaxed);
}

/// The E-STOP re-armed (closed through the debounce, and a continue): the
/// drivers may be enabled again. Whether the backstop had disabled them.
pub fn disarm_backstop() -> bool {
    BACKSTOP.store(0, Ordering::Relaxed);
    BACKSTOP_FIRED.swap(false, Ordering::Relaxed)
}

/// Starts the guard's ticks.
pub fn start(tim7: Peri<'static, TIM7>) {
    BACKSTOP_ARMED.store(backstop_ticks(&gonio_firmware::config::REFERENCE) + 1, Ordering::Relaxed);
    let timer = Timer::new(tim7);
    timer.set_frequency(Hertz(TICK_HZ));
    timer.enable_update_interrupt(true);
    timer.start();
    // The timer runs for the program's life.
    core::mem::forget(timer);
    Tim7Irq::unpend();
    // SAFETY: the handler is bound in `Irqs` and shares only atomics.
    unsafe { Tim7Irq::enable() };
}

/// The thread: embassy's thread-mode loop, each turn counted for the guard.
pub fn run(executor: &'static raw::Executor) -> ! {
    loop {
        TURNS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: polled from thread mode only, the executor's one thread.
        unsafe { executor.poll() };
        cortex_m::asm::wfe();
    }
}

/// A measurement's conversion chain runs from now, a code every
/// `sample_us`: watched until [`unwatch_chain`]. A trip is forgotten if the
/// thread has set the laser enable high since.
pub fn watch_chain(sample_us: u32) {
    if laser_enabled() {
        TRIPPED.store(false, Ordering::Release);
    }
    let generation = STARTS.fetch_add(1, Ordering::Relaxed).wrapping_add(1);
    CHAIN.store(ChainWatch::for_sample_interval(sample_us, generation).pack(), Ordering::Release);
}

/// The chain is stopped on purpose.
pub fn unwatch_chain() {
    CHAIN.store(0, Ordering::Release);
}

/// Whether the guard has cut the laser since the thread last turned it on.
pub fn tripped() -> bool {
    TRIPPED.load(Ordering::Acquire)
}

/// Ends when the guard cuts the laser.
pub async fn trip() {
    core::future::poll_fn(|cx| {
        TRIP.register(cx.waker());
        if tripped() {
            core::task::Poll::Ready(())
        } else {
            core::task::Poll::Pending
        }
    })
    .await
}
