//! The step executor: what the step-timer interrupt does, as plain logic.
//! It follows each axis through its queued blocks, raises the STEP pins of
//! the axes that are due, drops each pin after the pulse width, and tells the
//! timer when to fire next. The chip's TIM5 interrupt, the simulated head and
//! the tests all run this same code.

use super::blocks::to_tick;
use crate::hw::{QueueFull, StepBlock};
use embedded_hal::digital::OutputPin;
use gonio_shared::Axis;
use heapless::Deque;

/// Blocks queued per axis: a whole move (two ramps of at most ~170 blocks
/// at one-tick accuracy, and the cruise) is queued before it starts.
pub const QUEUE: usize = 192;

/// One axis: its queue and where it is in the current block.
struct Track {
    queue: Deque<StepBlock, QUEUE>,
    /// Steps left in the current block, the interval (Q32 ticks) to the next
    /// step, the block's add, and the next step's time (Q32 ticks).
    left: u32,
    interval: i64,
    add: i64,
    next: u64,
    emitted: u32,
    /// Tick at which this axis's STEP pulse ends, while it is high.
    high_until: Option<u64>,
}

impl Track {
    const fn new() -> Self {
        Track {
            queue: Deque::new(),
            left: 0,
            interval: 0,
            add: 0,
            next: 0,
            emitted: 0,
            high_until: None,
        }
    }

    /// Loads the next non-empty block after the step at `from` (Q32 ticks).
    fn load(&mut self, from: u64) {
        self.left = 0;
        while let Some(b) = self.queue.pop_front() {
            if b.count > 0 {
                self.left = b.count;
                self.interval = b.interval as i64;
                self.add = b.add;
                self.next = from.saturating_add_signed(self.interval);
                return;
            }
        }
    }

    fn next_tick(&self) -> Option<u64> {
        (self.left > 0).then(|| to_tick(self.next))
    }

    /// After a step: the next one of the block, or of the next block.
    fn advance(&mut self) {
        self.left -= 1;
        if self.left > 0 {
            self.interval += self.add;
            self.next = self.next.saturating_add_signed(self.interval.max(1));
        } else {
            self.load(self.next);
        }
    }
}

/// Executes queued blocks on three STEP pins. Times are ticks since `start`.
pub struct Executor<P: OutputPin> {
    tracks: [Track; 3],
    pins: [P; 3],
    pulse_ticks: u64,
    /// Steps that fell due while their pin was still high (too fast to emit).
    pub collisions: u32,
}

impl<P: OutputPin> Executor<P> {
    pub fn new(pins: [P; 3], pulse_ticks: u64) -> Self {
        Executor {
            tracks: [Track::new(), Track::new(), Track::new()],
            pins,
            pulse_ticks: pulse_ticks.max(1),
            collisions: 0,
        }
    }

    pub fn push(&mut self, axis: Axis, b: StepBlock) -> Result<(), QueueFull> {
        self.tracks[axis.index()].queue.push_back(b).map_err(|_| QueueFull)
    }

    /// Drops everything queued and in progress; STEP pins low.
    pub fn clear(&mut self) {
        for (t, p) in self.tracks.iter_mut().zip(self.pins.iter_mut()) {
            t.queue.clear();
            t.left = 0;
            if t.high_until.take().is_some() {
                let _ = p.set_low();
            }
        }
    }

    /// Arms every axis at tick 0; returns the first tick to fire at.
    pub fn start(&mut self) -> Option<u64> {
        for t in self.tracks.iter_mut() {
            t.emitted = 0;
            t.load(0);
        }
        self.next_event()
    }

    /// The next tick at which something is due: a step or a pulse end.
    pub fn next_event(&self) -> Option<u64> {
        self.tracks.iter().flat_map(|t| [t.next_tick(), t.high_until]).flatten().min()
    }

    /// Steps emitted per axis since [`Executor::start`].
    pub fn emitted(&self) -> [u32; 3] {
        [0, 1, 2].map(|i| self.tracks[i].emitted)
    }

    /// Handles the timer firing at tick `now`: ends pulses that are over,
    /// starts the steps that are due; returns the next tick, or `None` when
    /// every queue is empty and every pin low.
    pub fn fire(&mut self, now: u64) -> Option<u64> {
        for (t, p) in self.tracks.iter_mut().zip(self.pins.iter_mut()) {
            if t.high_until.is_some_and(|end| end <= now) {
                t.high_until = None;
                let _ = p.set_low();
            }
            while t.next_tick().is_some_and(|due| due <= now) {
                if t.high_until.is_some() {
                    self.collisions += 1;
                } else {
                    let _ = p.set_high();
                    t.high_until = Some(now + self.pulse_ticks);
                    t.emitted += 1;
                }
                t.advance();
            }
        }
        self.next_event()
    }

    /// Gives the STEP pins back (for checking them in tests).
    pub fn into_pins(self) -> [P; 3] {
        self.pins
    }

    /// Runs to completion against a clock that jumps to each event (the
    /// simulated head, tests); returns the tick at which the last pulse ended.
    pub fn run_to_end(&mut self) -> u64 {
        let mut now = 0;
        let mut next = self.start();
        while let Some(t) = next {
            now = t;
            next = self.fire(t);
        }
        now
    }
}
