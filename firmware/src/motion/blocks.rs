//! A move's profile ([`Profile`]) cut into `(interval, count, add)` blocks
//! for the step timer, with fractional (Q32) intervals so the executor follows the
//! analytical schedule to within one timer tick at any speed.
//!
//! A block's steps follow a quadratic in the step number through the last
//! emitted step and the block's first and last steps. Within one phase of the
//! move the schedule is smooth (`t = t₀ + C√(k + r₀)` accelerating, linear
//! at cruise, `T − C√(r₁ − k)` decelerating, `r₀`, `r₁` where the ramp would
//! start from or end at rest), so the interpolation error of that
//! quadratic is bounded by `max|t‴|·2c³/81` for a block of `c` steps; each
//! block is the longest whose bound stays within [`TOLERANCE_TICKS`]. The
//! first step of each phase is a block of its own (its interval spans the
//! change of formula), so no block straddles two phases. A cruise is one block.
//!
//! Why not Klipper's greedy compression, which checks every step of every
//! candidate block: on the Cortex-M4 (soft-float f64) that costs hundreds of
//! millions of instructions, over a second, per three-axis move
//! (`docs/decisions/006-step-blocks-from-an-error-bound.md`). The
//! bound needs two evaluations of the schedule per block and a bisection in
//! f32 for its length, and the blocks come one at a time
//! ([`ProfileBlocks`]), so the planner can yield between them.

use super::profile::{Kind, Profile};
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
/// `move_block_instructions_max` (4 930 measured, a sweep scan's row
/// slowed across its lobes included), rounded up; chip-bench
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

/// The blocks of a move on a `tick_hz` timer, one at a time.
pub struct ProfileBlocks<'a> {
    t: &'a Profile,
    hz: f64,
    /// `C` of `t = C√k` (ticks), for the error bound.
    c_ticks: f32,
    /// Steps already in blocks, and the executor's exact Q32 time of the last.
    done: u32,
    start: u64,
    /// The phase of the last step in blocks (phases come in order).
    phase: usize,
}

/// How far (steps) a block's steepest end lies from where its phase's ramp
/// would start from or end at rest, `r` of the error bound.
#[derive(Clone, Copy)]
enum Reach {
    /// A cruise: no bound.
    Any,
    /// Accelerating: `r` at the block's start, whatever its length.
    From(f32),
    /// Decelerating: `r` less the block's length.
    Before(f32),
}

impl<'a> ProfileBlocks<'a> {
    pub fn new(t: &'a Profile, tick_hz: u32) -> Self {
        let hz = tick_hz as f64;
        ProfileBlocks {
            t,
            hz,
            c_ticks: (libm::sqrt(2.0 / t.a) * hz) as f32,
            done: 0,
            start: 0,
            phase: 0,
        }
    }

    /// Step `k`'s time (Q32 ticks), `k` in the current phase.
    fn time_q32(&self, k: u32) -> f64 {
        self.t.step_time_in(self.phase, k) * self.hz * Q32
    }

    /// Moves on to the phase of step `k`; whether it is a later one.
    fn advance(&mut self, k: u32) -> bool {
        let (phases, from) = (self.t.phases(), self.phase);
        while self.phase + 1 < phases.len() && k as f64 > phases[self.phase].x1 {
            self.phase += 1;
        }
        self.phase != from
    }

    /// The last step of the current phase.
    fn phase_end(&self) -> u32 {
        let phases = self.t.phases();
        match phases.get(self.phase) {
            Some(p) if self.phase + 1 < phases.len() => (p.x1 as u32).min(self.t.n),
            _ => self.t.n,
        }
    }

    /// The bound's reach for a block after step `k0` in the current phase,
    /// worked out once in f64 for the bisection's f32 tests.
    fn reach(&self, k0: u32) -> Reach {
        let Some(p) = self.t.phases().get(self.phase) else {
            return Reach::Before(0.0);
        };
        let rest = |v: f64| v * v / (2.0 * self.t.a);
        match p.kind {
            Kind::Cruising => Reach::Any,
            Kind::Accelerating => Reach::From((k0 as f64 - p.x0 + rest(p.v0)) as f32),
            Kind::Decelerating => Reach::Before((p.x1 + rest(p.v1) - k0 as f64) as f32),
        }
    }

    /// Whether a block of `c` steps stays within the tolerance:
    /// `max|t‴|·2c³/81`, with `|t‴| = (3/8)·C·r^(−5/2)` at the block's
    /// steepest end, `r` its distance (steps) from where the phase's ramp
    /// would start from or end at rest (`k0` accelerating from rest, the
    /// steps left after the block decelerating to a stop), that is
    /// `C·c³ ≤ 108·tol·r^(5/2)`. Single precision: the bisection tests it
    /// some fifteen times a block.
    fn within(&self, reach: Reach, c: u32) -> bool {
        let c = c as f32;
        let r = match reach {
            Reach::Any => return true,
            Reach::From(r) => r,
            Reach::Before(r) => r - c,
        }
        .max(0.0);
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

impl Iterator for ProfileBlocks<'_> {
    type Item = StepBlock;

    fn next(&mut self) -> Option<StepBlock> {
        let k0 = self.done;
        if k0 >= self.t.n {
            return None;
        }
        let first_of_phase = self.advance(k0 + 1);
        // The first step of a phase is a block of its own; then the longest
        // block within the bound (bisection on a predicate true at 1).
        let mut c = 1;
        if k0 > 0 && !first_of_phase {
            let reach = self.reach(k0);
            let mut hi = self.phase_end() - k0 + 1;
            while hi - c > 1 {
                let mid = c + (hi - c) / 2;
                if self.within(reach, mid) {
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

/// Blocks of a move on a `tick_hz` timer, handed to `emit` in order; stops
/// early (returning false) when `emit` refuses one.
pub fn profile_blocks(t: &Profile, tick_hz: u32, mut emit: impl FnMut(StepBlock) -> bool) -> bool {
    ProfileBlocks::new(t, tick_hz).all(&mut emit)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn schedule(t: &Profile) -> (Vec<StepBlock>, f64) {
        let mut blocks = Vec::new();
        assert!(profile_blocks(t, 1_000_000, |b| {
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
            let t = Profile::new(n, 12_000.0, 24_000.0);
            let (blocks, worst) = schedule(&t);
            assert!(worst <= 1.0, "n = {n}: {worst} ticks");
            assert!(blocks.len() <= super::super::executor::QUEUE, "n = {n}: {} blocks", blocks.len());
        }
    }

    #[test]
    fn a_row_slowed_in_its_lobes_stays_within_a_tick_in_few_blocks() {
        // Slow near the retro lobe, fast, slow across the mirror lobe, fast.
        let caps = [(4_000, 3_000.0), (14_000, 12_000.0), (20_000, 5_000.0), (34_000, 12_000.0)];
        let t = Profile::levels(34_000, 24_000.0, caps);
        let (blocks, worst) = schedule(&t);
        assert!(worst <= 1.0, "{worst} ticks");
        assert!(blocks.len() <= super::super::executor::QUEUE, "{} blocks", blocks.len());
    }
}
