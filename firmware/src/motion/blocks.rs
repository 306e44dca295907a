//! Compression of an analytical step schedule into `(interval, count, add)`
//! blocks for the step timer, with fractional (Q32) intervals so the executor
//! can follow the schedule to within one timer tick at any speed.
//!
//! Greedy, as Klipper's step compression: from the last step, the longest
//! block whose every step, as the executor will emit it, lies within
//! [`TOLERANCE_TICKS`] of the analytical time. A cruise is one block.

use super::trapezoid::Trapezoid;
use crate::hw::StepBlock;

/// Largest deviation of an emitted step from the analytical time, in ticks,
/// before rounding to the tick (the rounding adds up to half a tick more).
const TOLERANCE_TICKS: f64 = 0.45;
const Q32: f64 = 4_294_967_296.0;

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

/// Compresses the schedule `time(k)` (ticks, k = 1..=n) into blocks, handing
/// each to `emit`; stops early (returning false) when `emit` refuses one.
pub fn compress(n: u32, time: impl Fn(u32) -> f64, mut emit: impl FnMut(StepBlock) -> bool) -> bool {
    let (mut done, mut start) = (0u32, 0u64);
    while done < n {
        let fits = |c: u32| -> Option<StepBlock> {
            let t1 = time(done + 1) * Q32;
            let interval = (t1 - start as f64).max(1.0);
            let add = if c > 1 {
                let tc = time(done + c) * Q32;
                2.0 * (tc - start as f64 - c as f64 * interval) / (c as f64 * (c as f64 - 1.0))
            } else {
                0.0
            };
            let b = StepBlock {
                interval: libm::round(interval) as u64,
                count: c,
                add: libm::round(add) as i64,
            };
            // Every interval of the block must stay positive.
            let last = b.interval as i128 + b.add as i128 * (c as i128 - 1);
            if last < 1 << 16 {
                return None;
            }
            (1..=c)
                .all(|k| libm::fabs(block_step_q32(start, &b, k) as f64 / Q32 - time(done + k)) <= TOLERANCE_TICKS)
                .then_some(b)
        };
        // Exponential search for a failing length, then bisection.
        let remaining = n - done;
        let (mut good, mut bad) = (1u32, 2u32);
        let mut best = fits(1);
        while bad <= remaining {
            match fits(bad) {
                Some(b) => {
                    best = Some(b);
                    good = bad;
                    bad = bad.saturating_mul(2);
                }
                None => break,
            }
        }
        let mut hi = bad.min(remaining + 1);
        while hi - good > 1 {
            let mid = good + (hi - good) / 2;
            match fits(mid) {
                Some(b) => {
                    best = Some(b);
                    good = mid;
                }
                None => hi = mid,
            }
        }
        // One step always fits: its interval is exact to the Q32 rounding.
        let b = best.unwrap_or(StepBlock {
            interval: libm::round(time(done + 1) * Q32 - start as f64).max(1.0) as u64,
            count: 1,
            add: 0,
        });
        start = block_step_q32(start, &b, b.count);
        done += b.count;
        if !emit(b) {
            return false;
        }
    }
    true
}

/// Blocks of a trapezoidal move on a `tick_hz` timer.
pub fn trapezoid_blocks(t: &Trapezoid, tick_hz: u32, emit: impl FnMut(StepBlock) -> bool) -> bool {
    let hz = tick_hz as f64;
    compress(t.n, |k| t.step_time(k) * hz, emit)
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
