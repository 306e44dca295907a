//! A trapezoidal move cut into `(interval, count, add)` blocks for the step
//! timer, with fractional (Q32) intervals so the executor follows the
//! analytical schedule to within one timer tick at any speed.
//!
//! A block's steps follow a quadratic in the step number through the last
//! emitted step and the block's first and last steps. Within one phase of the
//! move the schedule is smooth (`t = C√k` accelerating, linear at cruise,
//! `T − C√(n − k)` decelerating), so the interpolation error of that
//! quadratic is bounded by `max|t‴|·2c³/81` for a block of `c` steps; each
//! block is the longest whose bound stays within [`TOLERANCE_TICKS`]. The
//! first step of each phase is a block of its own (its interval spans the
//! change of formula), so no block straddles two phases. A cruise is one block.
//!
//! Why not Klipper's greedy compression, which checks every step of every
//! candidate block: measured on the Cortex-M4 (`chip-bench`, soft-float
//! f64), it took 203 M instructions (1.2 s) to plan one three-axis move. The
//! bound needs two evaluations of the schedule per block and a bisection in
//! f32 for its length, and the blocks come one at a time
//! ([`TrapezoidBlocks`]), so the planner can yield between them.

use super::trapezoid::Trapezoid;
use crate::hw::StepBlock;
use crate::math::sqrtf;

/// Largest deviation of an emitted step from the analytical time, in ticks,
/// before rounding to the tick (the rounding adds up to half a tick more).
const TOLERANCE_TICKS: f32 = 0.45;
/// The bound is evaluated in f32: a hair of margin, so that its rounding
/// never errs on the long side.
const BOUND_MARGIN: f32 = 0.98;
const Q32: f64 = 4_294_967_296.0;

/// What the chip spends planning one block (instructions): `chip-bench`'s
/// `move_block_instructions_max` (4 805 measured), rounded up; chip-bench
/// fails should it ever measure more. The simulated head waits this long per
/// block before a move starts, and the host's duration estimate counts it, so
/// neither hides a cost the chip pays.
pub const BLOCK_PLAN_INSTRUCTIONS: u32 = 5_000;

/// Time (s) the chip spends planning `blocks` blocks, one instruction a
/// cycle at [`crate::config::CPU_HZ`].
pub fn plan_s(blocks: usize) -> f64 {
    blocks as f64 * BLOCK_PLAN_INSTRUCTIONS as f64 / crate::config::CPU_HZ
}

/// Emitted tick of the `k`-th step (1-based) of a block starting at `start`
/// (Q32 ticks): the executor's exact integer arithmetic.
pub fn block_step_q32(start: u64, b: &StepBlock, k: u32) -> u64 {
    let k = k as i128;
    let t = start as i128 + k * b.interval as i128 + b.add as i128 * k * (k - 1) / 2;
    t.max(0) as u64
}

/// Rounds a Q32 time to whole ticks.
pub fn to_tick(q: u64) -> u64 {
    (q + (1 << 31)) >> 32
}

/// The smooth stretch a step belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Accelerating,
    Cruising,
    Decelerating,
}

/// The blocks of a trapezoidal move on a `tick_hz` timer, one at a time.
pub struct TrapezoidBlocks<'a> {
    t: &'a Trapezoid,
    hz: f64,
    /// `C` of `t = C√k` (ticks), for the error bound.
    c_ticks: f32,
    /// Last step of the acceleration and of the cruise.
    accel_end: u32,
    cruise_end: u32,
    /// Steps already in blocks, and the executor's exact Q32 time of the last.
    done: u32,
    start: u64,
}

impl<'a> TrapezoidBlocks<'a> {
    pub fn new(t: &'a Trapezoid, tick_hz: u32) -> Self {
        let hz = tick_hz as f64;
        let (accel_end, cruise_end) = t.phase_ends();
        TrapezoidBlocks {
            t,
            hz,
            c_ticks: (libm::sqrt(2.0 / t.a) * hz) as f32,
            accel_end,
            cruise_end,
            done: 0,
            start: 0,
        }
    }

    fn time_q32(&self, k: u32) -> f64 {
        self.t.step_time(k) * self.hz * Q32
    }

    /// Phase of step `k` and its last step.
    fn phase(&self, k: u32) -> (Phase, u32) {
        if k <= self.accel_end {
            (Phase::Accelerating, self.accel_end)
        } else if k <= self.cruise_end {
            (Phase::Cruising, self.cruise_end)
        } else {
            (Phase::Decelerating, self.t.n)
        }
    }

    /// Whether `c` steps after step `k0` stay within the tolerance:
    /// `max|t‴|·2c³/81`, with `|t‴| = (3/8)·C·r^(−5/2)` at the block's
    /// steepest end (`r` = `k0` accelerating, the steps left after the block
    /// decelerating), that is `C·c³ ≤ 108·tol·r^(5/2)`.
    fn within(&self, phase: Phase, k0: u32, c: u32) -> bool {
        let r = match phase {
            Phase::Cruising => return true,
            Phase::Accelerating => k0,
            Phase::Decelerating => self.t.n - k0 - c,
        } as f32;
        let c = c as f32;
        self.c_ticks * c * c * c <= 108.0 * TOLERANCE_TICKS * BOUND_MARGIN * r * r * sqrtf(r)
    }

    /// The block of `c` steps after the last one: through that step's exact
    /// time and the analytical times of its first and last steps.
    fn block(&self, c: u32) -> StepBlock {
        let start = self.start as f64;
        let interval = (self.time_q32(self.done + 1) - start).max(1.0);
        let add = if c > 1 {
            let cf = c as f64;
            2.0 * (self.time_q32(self.done + c) - start - cf * interval) / (cf * (cf - 1.0))
        } else {
            0.0
        };
        StepBlock {
            interval: libm::round(interval) as u64,
            count: c,
            add: libm::round(add) as i64,
        }
    }
}

impl Iterator for TrapezoidBlocks<'_> {
    type Item = StepBlock;

    fn next(&mut self) -> Option<StepBlock> {
        let k0 = self.done;
        if k0 >= self.t.n {
            return None;
        }
        let (phase, end) = self.phase(k0 + 1);
        // The first step of a phase is a block of its own; then the longest
        // block within the bound (bisection on a predicate true at 1).
        let mut c = 1;
        if k0 > 0 && self.phase(k0).0 == phase {
            let mut hi = end - k0 + 1;
            while hi - c > 1 {
                let mid = c + (hi - c) / 2;
                if self.within(phase, k0, mid) {
                    c = mid;
                } else {
                    hi = mid;
                }
            }
        }
        let mut b = self.block(c);
        // Every interval of the block stays positive (the schedule's do; this
        // guards the rounding): else one step.
        if (b.interval as i128 + b.add as i128 * (c as i128 - 1)) < 1 << 16 {
            b = self.block(1);
        }
        self.start = block_step_q32(self.start, &b, b.count);
        self.done += b.count;
        Some(b)
    }
}

/// Blocks of a trapezoidal move on a `tick_hz` timer, handed to `emit` in
/// order; stops early (returning false) when `emit` refuses one.
pub fn trapezoid_blocks(t: &Trapezoid, tick_hz: u32, mut emit: impl FnMut(StepBlock) -> bool) -> bool {
    TrapezoidBlocks::new(t, tick_hz).all(&mut emit)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn schedule(t: &Trapezoid) -> (Vec<StepBlock>, f64) {
        let mut blocks = Vec::new();
        assert!(trapezoid_blocks(t, 1_000_000, |b| {
            blocks.push(b);
            true
        }));
        // Replay as the executor will and compare with the analytical times.
        let (mut start, mut k, mut worst) = (0u64, 0u32, 0.0f64);
        for b in &blocks {
            for j in 1..=b.count {
                k += 1;
                let tick = to_tick(block_step_q32(start, b, j)) as f64;
                worst = worst.max((tick - t.step_time(k) * 1e6).abs());
            }
            start = block_step_q32(start, b, b.count);
        }
        assert_eq!(k, t.n);
        (blocks, worst)
    }

    #[test]
    fn long_and_short_moves_stay_within_a_tick_in_few_blocks() {
        // Arm: 30°/s, 60°/s² at 400 µsteps/°.
        for n in [1, 2, 3, 10, 100, 1000, 12_000, 72_000] {
            let t = Trapezoid::new(n, 12_000.0, 24_000.0);
            let (blocks, worst) = schedule(&t);
            assert!(worst <= 1.0, "n = {n}: {worst} ticks");
            assert!(blocks.len() <= super::super::executor::QUEUE, "n = {n}: {} blocks", blocks.len());
        }
    }
}
