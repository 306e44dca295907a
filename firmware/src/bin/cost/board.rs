//! A board for the probes: the core's own `Head`, serving a scripted host,
//! on hardware that answers at once and costs what memory accesses cost.
//! Every wait of the hardware (a delay, a chop period, a move) returns
//! `Pending` once, so each poll of the serve loop is one stretch between two
//! awaits as the chip's executor would run it; the link's send completes at
//! once (the chip's USB channel does when it has room), which can only make
//! a stretch longer.

use core::cell::{Cell, RefCell};
use core::convert::Infallible;
use core::future::Future;
use core::pin::Pin as Pinned;
use core::task::{Context, Poll, Waker};
// A wait of the hardware: `Pending` once, as the core's own yields.
use embassy_futures::yield_now as wait;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use embedded_hal_async::delay::DelayNs;
use gonio_firmware::config::REFERENCE;
use gonio_firmware::hw::{AdcStream, Board, ChopTiming, Clock, Hardware, Overrun, QueueFull, Sentry, StepBlock, StepTimer, Wake};
use gonio_firmware::link::{Link, LinkError};

/// The pins' levels and the stages' true positions (microsteps), which the
/// home switches read.
struct Rig {
    pins: [Cell<bool>; 16],
    steps: [Cell<i32>; 3],
    now_us: Cell<u64>,
}

// SAFETY: one core, no interrupts in the probe image.
unsafe impl Sync for Rig {}

static RIG: Rig = Rig {
    pins: [const { Cell::new(false) }; 16],
    steps: [const { Cell::new(0) }; 3],
    now_us: Cell::new(0),
};

const DIR: usize = 0;
const ENABLE_N: usize = 3;
const GAIN: usize = 6;
const LASER: usize = 8;

/// Places the stages `deg` degrees from their home switches (on the
/// positive side), so homing is short.
pub fn place_near_home(deg: f32) {
    for (i, a) in REFERENCE.axes.iter().enumerate() {
        RIG.steps[i].set(((a.home_deg + deg) * a.steps_per_deg()) as i32);
    }
}

pub struct Pin(usize);

impl ErrorType for Pin {
    type Error = Infallible;
}

impl OutputPin for Pin {
    fn set_high(&mut self) -> Result<(), Infallible> {
        RIG.pins[self.0].set(true);
        Ok(())
    }
    fn set_low(&mut self) -> Result<(), Infallible> {
        RIG.pins[self.0].set(false);
        Ok(())
    }
}

/// A home switch: pressed at and below the axis's home position.
pub struct HomeSwitch(usize);

impl ErrorType for HomeSwitch {
    type Error = Infallible;
}

impl InputPin for HomeSwitch {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        let a = &REFERENCE.axes[self.0];
        Ok(RIG.steps[self.0].get() <= (a.home_deg * a.steps_per_deg()) as i32)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        self.is_high().map(|h| !h)
    }
}

/// Chop periods of a steady signal: half the period bright.
pub struct Adc;

impl AdcStream for Adc {
    fn timer_hz(&self) -> u32 {
        84_000_000
    }
    const BITS: u8 = 12;
    fn start(&mut self, _: ChopTiming) {}
    fn stop(&mut self) {}
    async fn next_period(&mut self, out: &mut [u16]) -> Result<(), Overrun> {
        wait().await;
        let m = out.len();
        for (k, c) in out.iter_mut().enumerate() {
            *c = 1500 + if k < m / 2 { 700 } else { 0 } + (k as u16 * 13) % 7;
        }
        RIG.now_us.set(RIG.now_us.get() + 4_348);
        Ok(())
    }
}

/// A step timer that runs each move at once: the stages end where its steps
/// take them.
pub struct Steps {
    queued: [u32; 3],
    started: bool,
}

impl StepTimer for Steps {
    const TICK_HZ: u32 = 1_000_000;
    fn push(&mut self, axis: gonio_shared::Axis, block: StepBlock) -> Result<(), QueueFull> {
        self.queued[axis.index()] += block.count;
        Ok(())
    }
    fn start(&mut self) {
        self.started = true;
    }
    async fn finished(&mut self) -> [u32; 3] {
        if self.started {
            wait().await;
            self.started = false;
            for i in 0..3 {
                let sign = if RIG.pins[DIR + i].get() { 1 } else { -1 };
                RIG.steps[i].set(RIG.steps[i].get() + sign * self.queued[i] as i32);
            }
            RIG.now_us.set(RIG.now_us.get() + 100_000);
        }
        core::mem::take(&mut self.queued)
    }
    fn emitted(&self) -> [u32; 3] {
        // The rig runs a move at once, when its end is awaited.
        [0; 3]
    }
    fn brake(&mut self, _: [f32; 3]) {}
    fn clear(&mut self) {
        self.queued = [0; 3];
    }
}

pub struct Delay;

impl DelayNs for Delay {
    async fn delay_ns(&mut self, ns: u32) {
        wait().await;
        RIG.now_us.set(RIG.now_us.get() + ns as u64 / 1000 + 1);
    }
}

pub struct Uptime;

impl Clock for Uptime {
    fn now_us(&self) -> u64 {
        RIG.now_us.get()
    }
}

pub struct Rigged;

impl Board for Rigged {
    type Out = Pin;
    type In = HomeSwitch;
    type Adc = Adc;
    type Steps = Steps;
    type Delay = Delay;
    type Clock = Uptime;
}

pub fn hardware() -> Hardware<Rigged> {
    Hardware {
        dir: [Pin(DIR), Pin(DIR + 1), Pin(DIR + 2)],
        enable_n: [Pin(ENABLE_N), Pin(ENABLE_N + 1), Pin(ENABLE_N + 2)],
        home: [HomeSwitch(0), HomeSwitch(1), HomeSwitch(2)],
        gain: [Pin(GAIN), Pin(GAIN + 1)],
        laser: Pin(LASER),
        adc: Adc,
        steps: Steps {
            queued: [0; 3],
            started: false,
        },
        delay: Delay,
        clock: Uptime,
    }
}

/// The E-STOP stays closed; deadlines pass with the board's clock.
pub struct Calm;

impl Sentry for Calm {
    fn estop_open(&mut self) -> bool {
        false
    }
    fn now_us(&self) -> u64 {
        RIG.now_us.get()
    }
    async fn until(&mut self, deadline_us: Option<u64>, _estop: bool) -> Wake {
        core::future::poll_fn(|_| match deadline_us {
            Some(d) if RIG.now_us.get() >= d => Poll::Ready(Wake::Deadline),
            _ => Poll::Pending,
        })
        .await
    }
}

/// What the scripted host has seen of the head, and whether it hung up:
/// shared between the link (inside the head's future) and the executor.
pub struct Host {
    /// Frames for the head, handed out one per receive.
    pub inbox: RefCell<heapless::Deque<heapless::Vec<u8, 256>, 4>>,
    pub closed: Cell<bool>,
    /// Frames the head sent since the executor last looked (the oldest
    /// dropped: only the end of a scan is looked for, and it comes last).
    pub outbox: RefCell<heapless::Vec<heapless::Vec<u8, 256>, 8>>,
}

// SAFETY: one core, no interrupts in the probe image.
unsafe impl Sync for Host {}

pub static HOST: Host = Host {
    inbox: RefCell::new(heapless::Deque::new()),
    closed: Cell::new(false),
    outbox: RefCell::new(heapless::Vec::new()),
};

/// The scripted host's end of the link.
pub struct Script;

impl Script {
    fn take(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        if HOST.closed.get() {
            return Some(Err(LinkError::Closed));
        }
        let f = HOST.inbox.borrow_mut().pop_front()?;
        buf[..f.len()].copy_from_slice(&f);
        Some(Ok(f.len()))
    }
}

impl Link for Script {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        core::future::poll_fn(|_| match self.take(buf) {
            Some(r) => Poll::Ready(r),
            None => Poll::Pending,
        })
        .await
    }
    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        self.take(buf)
    }
    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let mut out = HOST.outbox.borrow_mut();
        if out.is_full() {
            out.remove(0);
        }
        let _ = out.push(heapless::Vec::from_slice(&frame[..frame.len().min(256)]).unwrap_or_default());
        Ok(())
    }
}

/// Room for the serve loop's future, which the chip keeps in its task arena
/// (a static), not on its 64 KiB stack.
const ARENA: usize = 48 * 1024;

#[repr(C, align(8))]
struct Arena([core::mem::MaybeUninit<u8>; ARENA]);

static mut SERVE_ARENA: Arena = Arena([core::mem::MaybeUninit::uninit(); ARENA]);

/// [`run`], with the future `make` makes kept in a static arena as the chip
/// keeps it.
pub fn run_in_arena<F: Future>(name: &'static str, make: impl FnOnce() -> F, stop: impl FnMut() -> bool) -> Option<F::Output> {
    if core::mem::size_of::<F>() > ARENA || core::mem::align_of::<F>() > 8 {
        super::mark("arena_refused", 0);
        return None;
    }
    // SAFETY: the arena is large and aligned enough (checked), used by one
    // future at a time (the probes run one after another on one core); the
    // future is pinned there until it is dropped in place below, before
    // anything it borrows goes away.
    unsafe {
        let slot = (&raw mut SERVE_ARENA).cast::<F>();
        place(slot, make);
        let out = run(name, Pinned::new_unchecked(&mut *slot), stop);
        slot.drop_in_place();
        out
    }
}

/// Writes the future `make` makes to `slot` from a frame of its own,
/// popped before the future is polled: on its way to the arena the future
/// (some 20 KiB) passes through the stack once, not beneath every poll.
///
/// # Safety
/// `slot` is valid for writes of an `F` and aligned.
#[inline(never)]
unsafe fn place<F>(slot: *mut F, make: impl FnOnce() -> F) {
    // SAFETY: the caller's promise.
    unsafe { slot.write(make()) }
}

/// Polls `f` until it is ready or `stop` (called between polls) says so;
/// every poll is measured as one stretch named `name`. The future is pinned
/// by the caller, where it was made: the serve loop's future is some 20 KiB,
/// and every move of it would be a copy on the stack.
pub fn run<F: Future>(name: &'static str, mut f: Pinned<&mut F>, mut stop: impl FnMut() -> bool) -> Option<F::Output> {
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = super::measure(name, || f.as_mut().poll(&mut cx)) {
            return Some(v);
        }
        if stop() {
            return None;
        }
    }
}
