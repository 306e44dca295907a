//! The hardware the core needs, as traits. `embedded-hal` covers pins and
//! delays; three small traits of our own cover what it has no word for: the
//! timer-triggered ADC stream, the hardware step timer and a monotonic clock.

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal_async::delay::DelayNs;
use gonio_shared::Axis;

/// Timing of the chop timer, already converted to the timer's units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChopTiming {
    /// Timer ticks per ADC sample (the ADC trigger period).
    pub ticks_per_sample: u32,
    /// ADC samples per chop period; the chop output toggles every half of it.
    pub samples_per_period: u16,
}

/// A block of ADC codes was lost or arrived late (DMA overrun).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Overrun;

/// One timer chops the laser and triggers the ADC, so each chop period holds a
/// whole number of samples; DMA fills a double buffer whose halves are one
/// chop period each.
pub trait AdcStream {
    /// Timer input clock (Hz) that [`ChopTiming::ticks_per_sample`] counts:
    /// on the chip, what the clock tree gives the timer, so that a board
    /// clocked otherwise chops at the frequency asked all the same.
    fn timer_hz(&self) -> u32;
    /// ADC resolution in bits.
    const BITS: u8;

    /// (Re)start the chop output and the triggered conversions.
    fn start(&mut self, timing: ChopTiming);
    /// Stop conversions and hold the chop output low (laser dark).
    fn stop(&mut self);
    /// Copy the next chop period of codes into `out` (length
    /// `samples_per_period`). The first sample of each block is taken at the
    /// rising chop edge. `Err(Overrun)` when a block was lost before this one.
    async fn next_period(&mut self, out: &mut [u16]) -> Result<(), Overrun>;
}

/// A Klipper-style step command: `count` steps, the first `interval` after
/// the previous one, each next interval changed by `add`. Interval and add
/// are in Q32 timer ticks (32 fractional bits), so a long block follows a
/// non-integer step period without drifting; steps are emitted at the tick
/// nearest to the accumulated time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepBlock {
    pub interval: u64,
    pub count: u32,
    pub add: i64,
}

/// The step queue of one axis is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QueueFull;

/// A hardware timer that emits STEP pulses at scheduled times for the three
/// axes. The core sets DIR (and waits the driver's setup time) before it
/// queues steps, and never toggles STEP itself.
pub trait StepTimer {
    /// Timer tick rate (Hz) of [`StepBlock::interval`].
    const TICK_HZ: u32;

    /// Queue steps for one axis; nothing is emitted before [`StepTimer::start`].
    fn push(&mut self, axis: Axis, block: StepBlock) -> Result<(), QueueFull>;
    /// Start every queue at the same instant.
    fn start(&mut self);
    /// Wait until every queue is empty; returns the steps emitted per axis
    /// since [`StepTimer::start`]. Dropping the wait leaves the steps running:
    /// a stop brakes them and waits again.
    async fn finished(&mut self) -> [u32; 3];
    /// Steps emitted per axis since [`StepTimer::start`] so far, read while
    /// the move runs: where a sweep's samples begin and end.
    fn emitted(&self) -> [u32; 3];
    /// Cut the running moves short: each axis decelerates from its current
    /// speed to a stop (`brake_ticks` from [`crate::units::brake_ticks`]),
    /// every step counted ([`crate::motion::executor::Executor::brake`]).
    fn brake(&mut self, brake_ticks: [f32; 3]);
    /// Drop whatever is queued (the axes stop at the next tick): for faults
    /// of the timer itself, where braking is no longer possible.
    fn clear(&mut self);

    /// Start the queues and wait until they are empty.
    async fn run(&mut self) -> [u32; 3] {
        self.start();
        self.finished().await
    }
}

/// Longest wait of the serve loop (µs) before it shows it is alive
/// ([`Sentry::alive`]); the chip's watchdog bites after a second without.
pub const ALIVE_EVERY_US: u64 = 250_000;

/// Why [`Sentry::until`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    EStop,
    Deadline,
}

/// What stops the head from outside its link: the E-STOP input (a normally
/// closed switch to ground with a pull-up, so a pressed button and a cut
/// wire both read open) and the passing of time. Passed to
/// [`crate::Head::serve`] beside the link, so that they are watched while an
/// operation owns the hardware.
pub trait Sentry {
    /// Whether the E-STOP input reads open now, or opened since the last
    /// opening [`Sentry::until`] reported.
    fn estop_open(&mut self) -> bool;
    /// The head's clock (µs since boot), as [`Clock::now_us`].
    fn now_us(&self) -> u64;
    /// Resolves when the E-STOP input opens (when `estop`; at once if it is
    /// open or opened since the last opening reported, which is then
    /// reported), or at `deadline_us` on the head's clock (when given).
    async fn until(&mut self, deadline_us: Option<u64>, estop: bool) -> Wake;
    /// Forgets the openings of the E-STOP seen so far: the head re-arms
    /// after one, and the bounces of its release must not trip it again.
    /// A sentry that latches openings (the chip's) keeps them until
    /// [`Sentry::until`] reports one or this is called.
    fn rearm(&mut self) {}
    /// The E-STOP is re-armed (closed through the debounce, and a
    /// continue): a backstop that disables the drivers should the stop
    /// stall (the chip's guard) stands down. Whether it had to disable them
    /// since the opening: the steps emitted after that moved nothing.
    fn rearmed(&mut self) -> bool {
        false
    }
    /// The serve loop is alive: called on every turn and from every wait, at
    /// least every [`ALIVE_EVERY_US`]. The chip feeds its
    /// watchdog only while these keep coming, so a serve loop stuck in a
    /// future that never ends (a send to a host that stopped reading) resets
    /// the head into its safe state.
    fn alive(&mut self) {}
}

/// Monotonic time since boot.
pub trait Clock {
    fn now_us(&self) -> u64;
}

/// The set of types a board provides. Pins are one type each, as embassy's
/// `Output`/`Input` and embedded-hal-mock's pin mock are.
pub trait Board {
    type Out: OutputPin;
    type In: InputPin;
    type Adc: AdcStream;
    type Steps: StepTimer;
    type Delay: DelayNs;
    type Clock: Clock;
}

/// Everything the core drives, owned by [`crate::Head`].
pub struct Hardware<B: Board> {
    /// DIR output per axis (rotation, cradle, arm); high = positive direction.
    pub dir: [B::Out; 3],
    /// Driver enable per axis, active low as on common STEP/DIR drivers.
    pub enable_n: [B::Out; 3],
    /// Home switch per axis, at the negative end of travel; high = pressed.
    pub home: [B::In; 3],
    /// Transimpedance gain select, two bits: four decades.
    pub gain: [B::Out; 2],
    /// Laser enable (the chop timer gates the modulation input).
    pub laser: B::Out,
    pub adc: B::Adc,
    pub steps: B::Steps,
    pub delay: B::Delay,
    pub clock: B::Clock,
}
