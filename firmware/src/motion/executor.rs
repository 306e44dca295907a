//! The step executor: what the step-timer interrupt does, as plain logic.
//! It follows each axis through its queued blocks, raises the STEP pins of
//! the axes that are due, drops each pin after the pulse width, and tells the
//! timer when to fire next. The chip's TIM5 interrupt, the simulated head and
//! the tests all run this same code.
//!
//! A move can be cut short ([`Executor::brake`]): each moving axis keeps the
//! step it has already scheduled and then slows down from the speed it has
//! at that moment at its deceleration limit, one step at a time, until it
//! stands; the steps it emits are counted like any others, so the position
//! stays exact and the head stays homed.

use super::blocks::to_tick;
use crate::hw::{QueueFull, StepBlock};
use embedded_hal::digital::OutputPin;
use gonio_shared::Axis;
use heapless::Deque;

/// Blocks queued per axis: a whole move is queued before it starts, two
/// ramps of at most ~100 blocks each at one-tick accuracy and the cruise
/// (about 207 for a long move of the reference axes), or a sweep scan's row
/// slowed across two lobes, up to six ramps (283 for a row slowed to a
/// quarter of its speed where it begins and to 40 % across the mirror lobe,
/// `blocks` tests). A row whose stretches take more runs at its slowest
/// speed all along (`motion::plan`).
pub const QUEUE: usize = 384;

const Q32: f32 = 4_294_967_296.0;

/// A deceleration in progress. With constant deceleration `a` (steps/tick²)
/// the speed with `r` steps left to the stop is `sqrt(2·a·r)`, so the step
/// from `r` to `r − 1` left takes `c / (sqrt(r) + sqrt(r − 1))` ticks, where
/// `c = sqrt(2/a)` (the sum form has no cancellation in f32). `r` starts where
/// that interval equals the axis's current one: no speed jump.
///
/// Single precision on purpose: the M4F computes VSQRT and VDIV in 14 cycles
/// each, a brake runs once per stop, and f32 keeps an interval of 10⁵ ticks
/// to 10⁻² ticks; the move's own blocks stay integer.
#[derive(Debug, Clone, Copy)]
struct Braking {
    c: f32,
    r: f32,
}

impl Braking {
    /// The ramp that continues at `interval` ticks per step. An axis slower
    /// than the last step of a ramp (`s < 1`) stops after its next step.
    fn from(c: f32, interval_ticks: f32) -> Self {
        let s = c / interval_ticks.max(f32::MIN_POSITIVE);
        let r = if s > 1.0 {
            let root = 0.5 * (s + 1.0 / s);
            root * root
        } else {
            0.0
        };
        Braking { c, r }
    }

    /// Steps after the one already scheduled.
    fn steps(&self) -> u32 {
        self.r.max(0.0) as u32
    }

    /// The next interval (Q32 ticks), one step nearer the stop. Out of line:
    /// inlined, its floating point makes every event save the FPU registers.
    #[inline(never)]
    fn step(&mut self) -> i64 {
        let r = self.r;
        self.r -= 1.0;
        let ticks = self.c / (crate::math::sqrtf(r) + crate::math::sqrtf((r - 1.0).max(0.0)));
        ((ticks * Q32) as i64).max(1)
    }
}

/// A tick that never comes: "no step due", "pin low".
const NEVER: u32 = u32::MAX;

/// Ticks since the move's start in 32 bits: the interrupt compares and takes
/// the minimum of single words. A move lasts far less than the 2³² ticks
/// (71 min at 1 MHz) this holds.
fn tick32(q32: u64) -> u32 {
    to_tick(q32) as u32
}

/// One axis: its queue and where it is in the current block.
///
/// The tick of the next step (`due`) and of the pulse's end (`high_until`)
/// are kept as plain ticks with [`NEVER`] for "none", so the interrupt
/// compares integers and finds the next event with two `min`s per axis
/// (measured on the Cortex-M4: `chip-bench`'s `step_event_instructions_max`).
///
/// `repr(C)` with the fields the interrupt touches first: they then sit at
/// small offsets from the track's address (one load each on the M4), ahead
/// of the 6 KiB queue.
#[repr(C)]
struct Track {
    /// `to_tick(next)` while a step is left, else [`NEVER`].
    due: u32,
    /// Tick at which this axis's STEP pulse ends, [`NEVER`] while it is low.
    high_until: u32,
    /// Steps left in the current block, the interval (Q32 ticks) to the next
    /// step, the block's add, and the next step's time (Q32 ticks).
    next: u64,
    interval: i64,
    add: i64,
    left: u32,
    /// Steps emitted and steps that fell due while the pin was still high,
    /// since the executor was made (wrapping): every step the interrupt
    /// passes counts in one of them. With `pushed` they give the steps still
    /// to come without the interrupt keeping a count of its own or the brake
    /// summing up to [`QUEUE`] blocks in its critical section.
    emitted: u32,
    collided: u32,
    /// Steps queued since the executor was made, less those dropped
    /// (wrapping; the thread's count, the interrupt never writes it).
    pushed: u32,
    /// `emitted` when the current move started, for [`Executor::emitted`].
    emitted_at_start: u32,
    /// Set while the axis decelerates to a stop instead of following its queue.
    braking: Option<Braking>,
    queue: Deque<StepBlock, QUEUE>,
}

impl Track {
    const fn new() -> Self {
        Track {
            queue: Deque::new(),
            left: 0,
            interval: 0,
            add: 0,
            next: 0,
            due: NEVER,
            emitted: 0,
            collided: 0,
            pushed: 0,
            emitted_at_start: 0,
            high_until: NEVER,
            braking: None,
        }
    }

    /// Loads the next block after the step at `from` (Q32 ticks); the queue
    /// holds no empty blocks and no interval below one ([`Executor::push`]).
    /// Inline: out of line, its call and frame cost a tenth of the worst
    /// event (three axes loading at one tick).
    #[inline(always)]
    fn load(&mut self, from: u64) {
        self.braking = None;
        match self.queue.pop_front() {
            Some(b) => {
                self.left = b.count;
                self.interval = b.interval as i64;
                self.add = b.add;
                self.next = from.wrapping_add(b.interval);
                self.due = tick32(self.next);
            }
            None => {
                self.left = 0;
                self.due = NEVER;
            }
        }
    }

    /// Steps still to come: the current block's and the queued ones.
    fn remaining(&self) -> u32 {
        self.pushed.wrapping_sub(self.passed())
    }

    /// Steps the interrupt has passed since the executor was made.
    fn passed(&self) -> u32 {
        self.emitted.wrapping_add(self.collided)
    }

    /// Drops the queue and the current block.
    fn drop_queue(&mut self) {
        self.queue.clear();
        self.left = 0;
        self.due = NEVER;
        self.pushed = self.passed();
    }

    /// Replaces what is left by a deceleration at `c = sqrt(2/a)` ticks from
    /// the current interval, unless what is left already stops sooner (a
    /// move in its own deceleration, which runs at the same limit).
    fn brake(&mut self, c: f32) {
        if self.left == 0 || self.braking.is_some() {
            return;
        }
        let b = Braking::from(c, self.interval as f32 / Q32);
        let steps = b.steps().saturating_add(1);
        if steps >= self.remaining() {
            return;
        }
        self.queue.clear();
        self.left = steps;
        self.pushed = self.passed().wrapping_add(steps);
        self.braking = Some(b);
    }

    /// The next event of this axis: its next step or its pulse's end.
    fn next_event(&self) -> u32 {
        self.due.min(self.high_until)
    }

    /// The timer firing at `now` for this axis, whose STEP pin is `pin`:
    /// ends its pulse if it is over and raises the pin if a step is due (a
    /// step due while the pin is still high collides); returns whether a
    /// step was due, for [`Track::follow`]. Every axis's pin is set before
    /// any axis's bookkeeping, so an edge due with another axis's waits for
    /// no block load or brake computation of that axis.
    #[inline(always)]
    fn raise<P: OutputPin>(&mut self, pin: &mut P, now: u32, pulse: u32) -> bool {
        if self.high_until <= now {
            self.high_until = NEVER;
            let _ = pin.set_low();
        }
        if self.due > now {
            return false;
        }
        if self.high_until == NEVER {
            let _ = pin.set_high();
            self.high_until = now + pulse;
            self.emitted = self.emitted.wrapping_add(1);
        } else {
            self.collided = self.collided.wrapping_add(1);
        }
        true
    }

    /// After [`Track::raise`] at `now`: moves past the step it served and
    /// past every later one already due (the pin is high: they collide);
    /// returns the axis's next event.
    #[inline(always)]
    fn follow(&mut self, stepped: bool, now: u32) -> u32 {
        if stepped {
            self.advance();
            while self.due <= now {
                self.collided = self.collided.wrapping_add(1);
                self.advance();
            }
        }
        self.next_event()
    }

    /// After a step: the next one of the block, or of the next block.
    /// Every interval is at least one (Q32): [`Executor::push`] and
    /// [`Braking::step`] see to it, so a step's time never goes back.
    fn advance(&mut self) {
        self.left -= 1;
        if self.left > 0 {
            self.interval = match self.braking.as_mut() {
                Some(b) => b.step(),
                None => self.interval + self.add,
            };
            // Wraps only after 2³² ticks (71 min at 1 MHz) in one move.
            self.next = self.next.wrapping_add(self.interval as u64);
            self.due = tick32(self.next);
        } else {
            self.load(self.next);
        }
    }
}

/// `b` with its first and last interval at least one (Q32 ticks); intervals
/// are linear in the step, so every one between is too.
fn at_least_one(mut b: StepBlock) -> StepBlock {
    b.interval = b.interval.clamp(1, i64::MAX as u64);
    let steps = b.count.saturating_sub(1) as i128;
    if steps > 0 && (b.interval as i128 + steps * b.add as i128) < 1 {
        // The least add that keeps the last interval at one or more.
        b.add = ((1 - b.interval as i128) / steps) as i64;
    }
    b
}

/// Executes queued blocks on three STEP pins. Times are ticks since `start`.
pub struct Executor<P: OutputPin> {
    tracks: [Track; 3],
    pins: [P; 3],
    pulse_ticks: u32,
}

impl<P: OutputPin> Executor<P> {
    pub fn new(pins: [P; 3], pulse_ticks: u64) -> Self {
        Executor {
            tracks: [Track::new(), Track::new(), Track::new()],
            pins,
            pulse_ticks: pulse_ticks.clamp(1, 1 << 16) as u32,
        }
    }

    /// Queues a block; an empty one is dropped (it has nothing to emit).
    /// A block whose intervals would fall below one (Q32) gets the least
    /// `add` that keeps its last one at one or more: no planner of ours makes
    /// such a block (`ProfileBlocks` cuts a block to one step where its
    /// rounding could), and checking here, once per block, spares the
    /// interrupt a clamp on every step.
    pub fn push(&mut self, axis: Axis, b: StepBlock) -> Result<(), QueueFull> {
        if b.count == 0 {
            return Ok(());
        }
        let t = &mut self.tracks[axis.index()];
        t.queue.push_back(at_least_one(b)).map_err(|_| QueueFull)?;
        t.pushed = t.pushed.wrapping_add(b.count);
        Ok(())
    }

    /// Drops everything queued and in progress; STEP pins low.
    pub fn clear(&mut self) {
        for (t, p) in self.tracks.iter_mut().zip(self.pins.iter_mut()) {
            t.drop_queue();
            if t.high_until != NEVER {
                t.high_until = NEVER;
                let _ = p.set_low();
            }
        }
    }

    /// Cuts the moves short: every moving axis decelerates from its current
    /// speed to a stop, `brake_ticks[i]` = `sqrt(2/a)` in ticks for an axis
    /// limited to `a` steps/tick² ([`crate::units::brake_ticks`]). The step
    /// each axis has already scheduled is kept; returns the next tick to fire at.
    pub fn brake(&mut self, brake_ticks: [f32; 3]) -> Option<u32> {
        for (t, c) in self.tracks.iter_mut().zip(brake_ticks) {
            t.brake(c);
        }
        self.next_event()
    }

    /// Arms every axis at tick 0; returns the first tick to fire at.
    pub fn start(&mut self) -> Option<u32> {
        for t in self.tracks.iter_mut() {
            t.emitted_at_start = t.emitted;
            t.load(0);
        }
        self.next_event()
    }

    /// The next tick at which something is due: a step or a pulse end.
    pub fn next_event(&self) -> Option<u32> {
        let next = self.tracks.iter().map(Track::next_event).fold(NEVER, u32::min);
        (next != NEVER).then_some(next)
    }

    /// Steps emitted per axis since [`Executor::start`].
    pub fn emitted(&self) -> [u32; 3] {
        [0, 1, 2].map(|i| self.tracks[i].emitted.wrapping_sub(self.tracks[i].emitted_at_start))
    }

    /// Steps that fell due while their pin was still high (too fast to
    /// emit), since the executor was made.
    pub fn collisions(&self) -> u32 {
        self.tracks.iter().map(|t| t.collided).fold(0, u32::wrapping_add)
    }

    /// Handles the timer firing at tick `now`: ends pulses that are over,
    /// starts the steps that are due; returns the next tick, or `None` when
    /// every queue is empty and every pin low.
    pub fn fire(&mut self, now: u32) -> Option<u32> {
        let now = now.min(NEVER - 1);
        // The three axes written out (not a loop): a loop's index, track
        // address and spilled registers cost a tenth of the worst event.
        let [a, b, c] = &mut self.tracks;
        let [pa, pb, pc] = &mut self.pins;
        let pulse = self.pulse_ticks;
        let (sa, sb, sc) = (a.raise(pa, now, pulse), b.raise(pb, now, pulse), c.raise(pc, now, pulse));
        let next = a.follow(sa, now).min(b.follow(sb, now)).min(c.follow(sc, now));
        (next != NEVER).then_some(next)
    }

    /// Gives the STEP pins back (for checking them in tests).
    pub fn into_pins(self) -> [P; 3] {
        self.pins
    }
}

/// A STEP pin that is always ready, for the unit tests of the executor
/// and of its interrupt (`step_irq`).
#[cfg(test)]
pub(super) struct ReadyPin;

#[cfg(test)]
impl embedded_hal::digital::ErrorType for ReadyPin {
    type Error = core::convert::Infallible;
}

#[cfg(test)]
impl OutputPin for ReadyPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Whatever a planner queues, every interval the interrupt will add
        /// is at least one, and a block that was already so is kept as it is.
        #[test]
        fn queued_intervals_are_at_least_one(
            interval in 0u64..(1 << 50),
            count in 1u32..100_000,
            add in -(1i64 << 45)..(1i64 << 45),
        ) {
            let b = StepBlock { interval, count, add };
            let held = at_least_one(b);
            let at = |k: u32| held.interval as i128 + k as i128 * held.add as i128;
            prop_assert!(at(0) >= 1 && at(count - 1) >= 1, "{b:?} -> {held:?}");
            let fine = interval >= 1 && interval as i128 + (count - 1) as i128 * add as i128 >= 1;
            if fine {
                prop_assert_eq!(held, b);
            }
        }

        /// The count of steps to come that the brake reads equals the
        /// current block's and the queued blocks' steps, whatever the
        /// interrupt has passed, with steps colliding (a pulse as long as
        /// the intervals) or not, through clears and restarts.
        #[test]
        fn steps_to_come_are_counted_without_summing_the_queue(
            blocks in proptest::collection::vec((1u32..40, 1u64..8), 1..20),
            pulse in 1u64..6,
            fires in proptest::collection::vec(0usize..200, 1..4),
        ) {
            let mut exec = Executor::new([ReadyPin, ReadyPin, ReadyPin], pulse);
            for (n, &cut) in fires.iter().enumerate() {
                for &(count, ticks) in &blocks {
                    let b = StepBlock { interval: ticks << 32, count, add: 0 };
                    exec.push(Axis::ALL[n % 3], b).unwrap();
                }
                let mut next = exec.start();
                for _ in 0..cut {
                    let Some(at) = next else { break };
                    next = exec.fire(at);
                }
                for t in &exec.tracks {
                    let queued: u32 = t.queue.iter().map(|b| b.count).sum();
                    prop_assert_eq!(t.remaining(), t.left + queued);
                }
                if n % 2 == 1 {
                    exec.clear();
                } else {
                    while let Some(at) = next {
                        next = exec.fire(at);
                    }
                }
            }
        }
    }
}
