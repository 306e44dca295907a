//! The guard's judgement: from what an interrupt of its own sees at each
//! tick, whether the laser enable must be cut now.
//!
//! The serve loop turns the laser off when a chop period fails to come,
//! but only once it has waited three periods and a millisecond for it, and
//! a thread that is stuck (a task that never yields) turns nothing off: the
//! watchdog resets it within a second. The virtual board measured both:
//! 15 ms and 0.96 s of laser after the fault. The guard bounds them to a
//! millisecond, from a timer interrupt that pre-empts the thread and needs
//! nothing of it. At each tick it checks:
//!
//! - the thread: the executor's loop counts its turns, and an exception's
//!   return wakes a sleeping loop for one more turn, so an idle thread
//!   turns at every tick too. No turn for [`STUCK_TICKS`] ticks in a row
//!   is a thread stuck in one poll (or in the loop itself). A poll that
//!   legitimately lasts longer than `STUCK_TICKS` ticks with the laser on
//!   would trip it: `chip-bench` holds the serve loop's longest poll under
//!   100 000 instructions (595 µs at 168 MHz, the rest of the 750 µs left to
//!   the interrupts that pre-empt it), and `board-bench` measures the
//!   longest the thread ran without a turn with the laser on.
//! - the conversion chain, while a measurement runs it: the DMA's count of
//!   codes to come must move at least once per sample interval; unmoved
//!   for longer than that and a tick, a trigger, a conversion or a transfer
//!   has stopped.
//!
//! Both only matter with the laser enable high. The trip is the chip's to
//! act on (`chip/guard.rs`): the laser enable low, and every period read
//! failing until the thread turns the laser on again.
//!
//! The guard is also the E-STOP's backstop ([`backstop`]). The E-STOP's
//! stop is of category 1 (IEC 60204-1 §9.2.2): its interrupt cuts the laser
//! at once, the thread brakes the motion from its speed (the head stays
//! homed) and then disables the drivers. Should the drivers still be
//! enabled [`backstop_ticks`] after the opening, the guard disables them
//! itself; the steps emitted after that move nothing, and a head whose
//! backstop fired must be homed again.

use crate::config::HeadConfig;

/// The guard's interrupt rate (Hz), and its tick (µs).
pub const TICK_HZ: u32 = 8_000;
pub const TICK_US: u32 = 1_000_000 / TICK_HZ;

/// Ticks in a row with no turn of the thread's loop, the laser on, that
/// mean the thread is stuck: found within `(STUCK_TICKS + 1)` ticks of its
/// last turn (875 µs), and a poll of up to `STUCK_TICKS` ticks (750 µs) is
/// allowed.
pub const STUCK_TICKS: u32 = 6;

/// Slack for the thread's part of an E-STOP stop beyond the longest brake
/// (s): its turn to see the opening, the brake's planning, the enables.
pub const BACKSTOP_MARGIN_S: f32 = 0.1;

/// Ticks the E-STOP's orderly stop may take before the backstop disables
/// the drivers: the longest brake of `cfg`'s axes from full speed at full
/// deceleration (0.5 s for the reference head), plus [`BACKSTOP_MARGIN_S`].
pub fn backstop_ticks(cfg: &HeadConfig) -> u32 {
    let brake_s = cfg.axes.iter().map(|a| a.max_speed_dps / a.max_accel_dps2).fold(0.0f32, f32::max);
    ((brake_s + BACKSTOP_MARGIN_S) * TICK_HZ as f32) as u32 + 1
}

/// The backstop's state: 0 idle; an E-STOP opening arms it with
/// `backstop_ticks + 1`, and it counts down while the drivers are enabled;
/// 1 once the stop is over (the thread disabled them) or overdue: from
/// then until the E-STOP is re-armed (back to 0), enabled drivers are cut.
/// One tick with the drivers' state: the state after it, and whether the
/// drivers must be disabled now.
pub fn backstop(state: u32, drivers_enabled: bool) -> (u32, bool) {
    match state {
        0 => (0, false),
        1 => (1, drivers_enabled),
        _ if !drivers_enabled => (1, false),
        2 => (1, true),
        n => (n - 1, false),
    }
}

/// Why the guard cut the laser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trip {
    /// The thread made no turn for [`STUCK_TICKS`] ticks.
    ThreadStuck,
    /// The conversion chain's count did not move for longer than a sample.
    ChainStalled,
}

/// A running conversion chain, as the guard watches it; packed in a `u32`
/// to be handed to the interrupt in one atomic store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChainWatch {
    /// Which start of the chain this is: a new one forgets the last count.
    pub generation: u16,
    /// Ticks in a row the count may stay where it is.
    pub still_allowed: u16,
}

impl ChainWatch {
    /// The watch for a chain that moves a code every `sample_us`: the count
    /// may stay put over as many whole ticks as a sample interval can
    /// span, so one tick later than the longest gap it trips.
    pub fn for_sample_interval(sample_us: u32, generation: u16) -> Self {
        let spans = sample_us.div_ceil(TICK_US).min(u16::MAX as u32 - 1);
        ChainWatch {
            generation,
            still_allowed: spans as u16,
        }
    }

    /// Packed; never 0, which stands for no chain.
    pub fn pack(self) -> u32 {
        (self.generation as u32) << 16 | (self.still_allowed as u32 + 1)
    }

    /// `None` for 0, no chain running.
    pub fn unpack(word: u32) -> Option<Self> {
        (word != 0).then(|| ChainWatch {
            generation: (word >> 16) as u16,
            still_allowed: (word & 0xFFFF) as u16 - 1,
        })
    }
}

/// What the guard remembers from tick to tick.
pub struct Guard {
    turns: u32,
    turns_still: u32,
    /// The watched chain's generation, its count at the last tick, and the
    /// ticks in a row it has stayed there.
    chain: Option<(u16, u16, u16)>,
}

impl Default for Guard {
    fn default() -> Self {
        Self::new()
    }
}

impl Guard {
    pub const fn new() -> Self {
        Guard {
            turns: 0,
            turns_still: 0,
            chain: None,
        }
    }

    /// One tick: the laser enable's level, the thread loop's turn count,
    /// and the chain being watched with the DMA's count now. Returns why
    /// the laser must be cut, if it must.
    pub fn tick(&mut self, laser_on: bool, turns: u32, chain: Option<(ChainWatch, u16)>) -> Option<Trip> {
        if !laser_on {
            // A thread busy with the laser off endangers nothing; it is
            // timed from the laser's rise (a long poll may end by turning
            // it on).
            self.turns = turns;
            self.turns_still = 0;
        } else if turns == self.turns {
            self.turns_still = self.turns_still.saturating_add(1);
        } else {
            self.turns = turns;
            self.turns_still = 0;
        }
        let stalled = match (chain, self.chain) {
            (Some((w, count)), Some((generation, last, still))) if generation == w.generation => {
                let still = if count == last { still.saturating_add(1) } else { 0 };
                self.chain = Some((generation, count, still));
                still > w.still_allowed
            }
            (Some((w, count)), _) => {
                self.chain = Some((w.generation, count, 0));
                false
            }
            (None, _) => {
                self.chain = None;
                false
            }
        };
        if !laser_on {
            None
        } else if self.turns_still >= STUCK_TICKS {
            Some(Trip::ThreadStuck)
        } else if stalled {
            Some(Trip::ChainStalled)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Ticks of a thread that turns `every` ticks and a chain whose count
    /// moves every `moves` ticks (0: never), the laser on; the first trip
    /// and its tick.
    fn run(ticks: u32, every: u32, moves: u32, watch: Option<ChainWatch>) -> Option<(u32, Trip)> {
        let mut g = Guard::new();
        (1..=ticks).find_map(|t| {
            let turns = t.checked_div(every).unwrap_or(0);
            let count = t.checked_div(moves).map_or(7, |n| (1000 - n) as u16);
            g.tick(true, turns, watch.map(|w| (w, count))).map(|trip| (t, trip))
        })
    }

    /// The backstop from an opening, the drivers enabled for `enabled`
    /// ticks then disabled by the thread: the tick it cut them, if it did.
    fn backstop_run(armed: u32, enabled: u32, ticks: u32) -> Option<u32> {
        let mut state = armed + 1;
        (1..=ticks).find(|&t| {
            let (next, cut) = backstop(state, t <= enabled);
            state = next;
            cut
        })
    }

    #[test]
    fn the_backstop_cuts_the_drivers_only_when_the_stop_is_overdue() {
        let ticks = backstop_ticks(&crate::config::REFERENCE);
        // 0.5 s of brake and 0.1 s of slack at 8 kHz.
        assert_eq!(ticks, 4801);
        assert_eq!(backstop_run(ticks, ticks - 1, 10_000), None, "stopped in time");
        assert_eq!(backstop_run(ticks, 20_000, 10_000), Some(ticks), "overdue");
        assert_eq!(backstop_run(ticks, 0, 10_000), None, "idle at the opening");
        // Once the stop is over, drivers enabled before the re-arm are cut at once.
        assert_eq!(backstop(1, true), (1, true));
        assert_eq!(backstop(1, false), (1, false));
        assert_eq!(backstop(0, true), (0, false), "not armed");
    }

    #[test]
    fn a_thread_that_stops_turning_trips_after_the_stuck_ticks() {
        assert_eq!(run(100, 1, 1, None), None);
        // Turns at tick 0 only: the count stays from tick 1.
        assert_eq!(run(100, 0, 1, None), Some((STUCK_TICKS, Trip::ThreadStuck)));
        // A poll of STUCK_TICKS ticks is allowed, one more is not.
        assert_eq!(run(100, STUCK_TICKS, 1, None), None);
        assert!(run(100, STUCK_TICKS + 1, 1, None).is_some());
    }

    #[test]
    fn a_chain_that_stops_trips_one_tick_after_its_longest_gap() {
        let w = ChainWatch::for_sample_interval(68, 1);
        assert_eq!(w.still_allowed, 1);
        assert_eq!(run(100, 1, 1, Some(w)), None);
        assert_eq!(run(100, 1, 0, Some(w)), Some((3, Trip::ChainStalled)));
        // A code every 300 µs spans three ticks.
        let slow = ChainWatch::for_sample_interval(300, 1);
        assert_eq!(run(100, 1, 3, Some(slow)), None);
        assert_eq!(run(100, 1, 0, Some(slow)), Some((5, Trip::ChainStalled)));
    }

    #[test]
    fn nothing_trips_with_the_laser_off() {
        let mut g = Guard::new();
        let w = ChainWatch::for_sample_interval(68, 1);
        for _ in 0..100 {
            assert_eq!(g.tick(false, 0, Some((w, 5))), None);
        }
        // Then on, the thread still: timed from the laser's rise (the
        // chain's stall was found while it was off, and trips at once).
        assert_eq!(g.tick(true, 0, Some((w, 5))), Some(Trip::ChainStalled));
        let mut g = Guard::new();
        for _ in 0..100 {
            assert_eq!(g.tick(false, 0, None), None);
        }
        for _ in 1..STUCK_TICKS {
            assert_eq!(g.tick(true, 0, None), None);
        }
        assert_eq!(g.tick(true, 0, None), Some(Trip::ThreadStuck));
    }

    #[test]
    fn a_new_start_of_the_chain_forgets_the_last_count() {
        let mut g = Guard::new();
        let first = ChainWatch::for_sample_interval(68, 1);
        let second = ChainWatch::for_sample_interval(68, 2);
        assert_eq!(g.tick(true, 1, Some((first, 5))), None);
        assert_eq!(g.tick(true, 2, Some((first, 5))), None);
        // The same count in a new generation: a fresh start, not a stall.
        assert_eq!(g.tick(true, 3, Some((second, 5))), None);
        assert_eq!(g.tick(true, 4, Some((second, 5))), None);
        assert_eq!(g.tick(true, 5, Some((second, 5))), Some(Trip::ChainStalled));
    }

    proptest! {
        #[test]
        fn a_watch_packs_and_unpacks(generation in any::<u16>(), sample_us in 1u32..10_000_000) {
            let w = ChainWatch::for_sample_interval(sample_us, generation);
            prop_assert_ne!(w.pack(), 0);
            prop_assert_eq!(ChainWatch::unpack(w.pack()), Some(w));
            prop_assert!(u32::from(w.still_allowed) * TICK_US >= sample_us.min((u16::MAX as u32 - 1) * TICK_US));
        }

        /// A chain whose count moves at least once per sample interval
        /// never trips, whatever the phase of its codes to the ticks.
        #[test]
        fn a_moving_chain_never_trips(sample_us in 1u32..5_000, phase_us in 0u32..5_000, ticks in 1u32..400) {
            let w = ChainWatch::for_sample_interval(sample_us, 3);
            let mut g = Guard::new();
            for t in 1..=ticks {
                let codes = (t * TICK_US + phase_us % sample_us) / sample_us;
                prop_assert_eq!(g.tick(true, t, Some((w, (60_000 - codes % 60_000) as u16))), None);
            }
        }
    }
}
