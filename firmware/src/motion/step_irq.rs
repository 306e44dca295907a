//! The step timer's interrupt as plain logic, over a free-running 32-bit
//! counter with one compare channel ([`CompareTimer`]): the chip's TIM5
//! handler is this code on TIM5's registers, and `chip-bench` measures this
//! code on the emulated Cortex-M4.
//!
//! Two races of a compare channel are closed here, where a test can show
//! them: a match left pending from an earlier compare is cleared before the
//! interrupt is enabled (else the handler runs at once, before the move's
//! origin), and a compare written when the counter is already at or past it
//! never matches until the counter wraps (71 min at 1 MHz): after writing it
//! the counter is read again, and an event already due is run at once.

use super::executor::Executor;
use embedded_hal::digital::OutputPin;

/// The registers the step interrupt touches.
pub trait CompareTimer {
    /// The free-running counter (ticks).
    fn count(&self) -> u32;
    /// Writes the compare value.
    fn set_compare(&mut self, at: u32);
    /// Clears a pending compare match.
    fn clear_match(&mut self);
    /// Enables or disables the compare interrupt.
    fn enable_interrupt(&mut self, on: bool);
}

/// Ticks since `origin` (a move's tick 0), read as signed so that a count
/// just before the origin is 0, not 2³² ticks.
pub fn since(timer: &impl CompareTimer, origin: u32) -> u32 {
    (timer.count().wrapping_sub(origin) as i32).max(0) as u32
}

/// Arms the compare for `next` (ticks since `origin`), running at once the
/// events the counter has already reached; returns the steps emitted per
/// axis when nothing is left (the interrupt is then off).
pub fn schedule<P: OutputPin, T: CompareTimer>(
    exec: &mut Executor<P>,
    timer: &mut T,
    origin: u32,
    mut next: Option<u32>,
) -> Option<[u32; 3]> {
    loop {
        let Some(at) = next else {
            timer.enable_interrupt(false);
            return Some(exec.emitted());
        };
        timer.set_compare(origin.wrapping_add(at));
        timer.clear_match();
        timer.enable_interrupt(true);
        let now = since(timer, origin);
        if now < at {
            return None;
        }
        next = exec.fire(now);
    }
}

/// The compare interrupt: runs the events due now and arms the next one;
/// returns the steps emitted per axis when the move is over.
pub fn on_compare<P: OutputPin, T: CompareTimer>(exec: &mut Executor<P>, timer: &mut T, origin: u32) -> Option<[u32; 3]> {
    timer.clear_match();
    let now = since(timer, origin);
    let next = exec.fire(now);
    schedule(exec, timer, origin, next)
}

#[cfg(test)]
mod tests {
    use super::super::executor::ReadyPin;
    use super::*;
    use crate::hw::StepBlock;
    use gonio_shared::Axis;

    /// A counter that advances by `per_read` ticks at every read (time passing
    /// while the handler runs) and records what was written.
    struct Counter {
        now: core::cell::Cell<u32>,
        per_read: u32,
        compare: u32,
        /// Whether the counter was still short of the compare when it was
        /// written (else it cannot match before the counter wraps).
        reachable: bool,
        pending: bool,
        enabled: bool,
    }

    impl Counter {
        /// At `now`, advancing `per_read` ticks per read, nothing armed.
        fn at(now: u32, per_read: u32) -> Self {
            Counter {
                now: core::cell::Cell::new(now),
                per_read,
                compare: 0,
                reachable: false,
                pending: false,
                enabled: false,
            }
        }
    }

    impl CompareTimer for Counter {
        fn count(&self) -> u32 {
            let t = self.now.get();
            self.now.set(t.wrapping_add(self.per_read));
            t
        }
        fn set_compare(&mut self, at: u32) {
            self.compare = at;
            self.reachable = (at.wrapping_sub(self.now.get()) as i32) > 0;
        }
        fn clear_match(&mut self) {
            self.pending = false;
        }
        fn enable_interrupt(&mut self, on: bool) {
            self.enabled = on;
        }
    }

    fn executor(steps: u32, interval_ticks: u64) -> Executor<ReadyPin> {
        let mut e = Executor::new([ReadyPin, ReadyPin, ReadyPin], 3);
        let b = StepBlock {
            interval: interval_ticks << 32,
            count: steps,
            add: 0,
        };
        e.push(Axis::Rotation, b).unwrap();
        e
    }

    /// Runs a move on `timer` as the interrupt would: the handler runs when
    /// the counter reaches an armed compare, never otherwise.
    fn run(exec: &mut Executor<ReadyPin>, timer: &mut Counter, origin: u32) -> Option<[u32; 3]> {
        let first = exec.start();
        if let Some(done) = schedule(exec, timer, origin, first) {
            return Some(done);
        }
        for _ in 0..10_000 {
            if !timer.enabled {
                return None;
            }
            // A compare written behind the counter never matches: the move stalls.
            if !timer.reachable {
                return None;
            }
            // The match (the counter may have passed it while the handler ran).
            if ((timer.compare.wrapping_sub(timer.now.get())) as i32) > 0 {
                timer.now.set(timer.compare);
            }
            timer.pending = true;
            if let Some(done) = on_compare(exec, timer, origin) {
                return Some(done);
            }
        }
        None
    }

    #[test]
    fn a_compare_passed_while_it_was_written_is_run_at_once() {
        // Steps every 7 ticks, pulses of 3; every read of the counter costs
        // 3 ticks, so the pulse ends are passed before their compare lands:
        // without the re-read the move would wait for the counter to wrap.
        let mut exec = executor(50, 7);
        let mut timer = Counter::at(1000, 3);
        assert_eq!(run(&mut exec, &mut timer, 1000), Some([50, 0, 0]));
        assert!(!timer.enabled, "the interrupt is off after the move");
    }

    #[test]
    fn a_stale_match_is_cleared_before_the_interrupt_is_enabled() {
        let mut exec = executor(5, 100);
        let mut timer = Counter {
            pending: true,
            ..Counter::at(0, 0)
        };
        let first = exec.start();
        assert_eq!(schedule(&mut exec, &mut timer, 0, first), None);
        assert!(timer.enabled && !timer.pending, "armed with no match pending");
        assert_eq!(timer.compare, 100);
    }

    #[test]
    fn the_origin_is_read_signed() {
        let timer = Counter::at(u32::MAX - 4, 0);
        assert_eq!(since(&timer, 5), 0, "10 ticks before the origin");
        assert_eq!(since(&timer, u32::MAX - 10), 6);
    }
}
