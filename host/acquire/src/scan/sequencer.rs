//! What a stretch of scan does with each event the head sends and each
//! status it reports, decided apart from the I/O: continuity (every visit
//! position stored once, in order), a sweep row's samples kept only whole,
//! the head's visit queue kept filled, the pause for the drift monitor, and
//! how the stretch ends. The loop in [`super`] performs the actions.

use gonio_scan_dir::run::ScanOutcome;
use gonio_shared::{Fault, HeadState, Sample, ScanAccepted, ScanEvent, SweptSample, VISIT_QUEUE};
use std::time::Duration;

/// Longest time the head may stay at one position (one move plus one integration).
pub const EVENT_TIMEOUT: Duration = Duration::from_secs(180);

/// How a stretch of scan ended.
#[derive(Debug, PartialEq)]
pub enum Stretch {
    Finished,
    /// Paused for the monitor or the operator; continue at this visit position.
    Paused(u32),
    /// Cut short; continue at this visit position once recovered.
    Interrupted(u32, Interruption),
}

/// Why a stretch was cut short, and so how the host recovers.
#[derive(Debug, PartialEq)]
pub enum Interruption {
    /// Events lost, damaged or out of order: the head is asked for the
    /// rest again (the scan continued from the first position not stored).
    Gap,
    /// The link closed or stopped answering: find the head again.
    LinkLost(String),
    /// The head stopped for a fault a retry clears (a lost ADC block twice,
    /// a host heartbeat that came too late).
    Transient(Fault),
    /// A move stalled: the stages lost their position; home, then continue.
    Rehome(Fault),
}

impl Interruption {
    pub fn name(&self) -> String {
        match self {
            Interruption::Gap => "events lost or out of order".into(),
            Interruption::LinkLost(why) => format!("link lost ({why})"),
            Interruption::Transient(f) | Interruption::Rehome(f) => f.to_string(),
        }
    }
}

/// One thing for the I/O loop to do, in the order given.
#[derive(Debug, PartialEq)]
pub enum Action {
    /// Append this sample to the samples file.
    Store(Sample),
    /// Append this sweep row, whole, to the samples file.
    StoreRow(Vec<SweptSample>),
    /// Send the head more of the visit order, from [`Sequencer::queued`].
    Refill,
    /// Ask the head to hold the scan (the drift monitor is due, or the
    /// operator asked).
    Pause,
    /// Abort the head's scan: events were lost or came out of order; the
    /// stretch ends `Interrupted(expected, Gap)`.
    Gap,
    /// The stretch ended.
    End(Stretch),
    /// The scan cannot go on: this is why, in the operator's words.
    Fail(String),
}

/// The host's view of one stretch of a scan run.
pub struct Sequencer {
    run: u32,
    points: u32,
    /// The next visit position to store.
    expected: u32,
    /// Where the head's visit queue ends.
    queued: u32,
    /// Visit positions in the whole order.
    order_len: u32,
    /// Pause once this visit position has been reached (drift monitor).
    stop_at: Option<u32>,
    pausing: bool,
    /// The samples of the row being swept, kept once it is done and whole.
    row: Vec<SweptSample>,
}

impl Sequencer {
    /// A stretch of run `accepted`, storing from visit position `from`, the
    /// head's queue filled up to `queued` of an order of `order_len`.
    pub fn new(accepted: &ScanAccepted, from: u32, queued: u32, order_len: u32, stop_at: Option<u32>) -> Self {
        Sequencer {
            run: accepted.run,
            points: accepted.points,
            expected: from,
            queued,
            order_len,
            stop_at,
            pausing: false,
            row: Vec::new(),
        }
    }

    /// The next visit position to store.
    pub fn expected(&self) -> u32 {
        self.expected
    }

    /// How far the stretch has got, for the wait on a silent head: changes
    /// with every position stored and every swept sample taken.
    pub fn progress(&self) -> (u32, usize) {
        (self.expected, self.row.len())
    }

    /// Where to refill the head's queue from.
    pub fn queued(&self) -> u32 {
        self.queued
    }

    /// The head's queue now ends at `queued`.
    pub fn fed(&mut self, queued: u32) {
        self.queued = queued;
    }

    /// What to do with event `ev`; counts go to `outcome`.
    pub fn on_event(&mut self, ev: ScanEvent, outcome: &mut ScanOutcome) -> Vec<Action> {
        if let ScanEvent::SweptSample(s) = ev {
            return self.on_swept_sample(s, outcome);
        }
        if let ScanEvent::Swept { order, samples, .. } = ev {
            if order == self.expected && self.row.len() != samples as usize {
                return vec![Action::Gap];
            }
        }
        let order = match &ev {
            ScanEvent::Sample(s) => s.scan.map(|p| p.order),
            ScanEvent::Skipped { order, .. } | ScanEvent::Swept { order, .. } => Some(*order),
            ScanEvent::SweptSample(_) | ScanEvent::Finished { .. } | ScanEvent::Stopped { .. } | ScanEvent::Paused { .. } => None,
        };
        if let Some(o) = order {
            if o < self.expected {
                // Sent twice, or an earlier run's late event: stored already.
                outcome.duplicates_dropped += 1;
                return Vec::new();
            }
            if o > self.expected {
                return vec![Action::Gap];
            }
            self.expected += 1;
        }
        let mut actions = Vec::new();
        match ev {
            ScanEvent::Sample(s) => {
                outcome.measured += 1;
                if s.signal.flags.doubtful() {
                    outcome.flagged += 1;
                }
                actions.push(Action::Store(s));
            }
            ScanEvent::Swept { .. } => {
                let row = std::mem::take(&mut self.row);
                outcome.measured += 1;
                outcome.swept_samples += row.len() as u32;
                outcome.flagged += row.iter().filter(|s| s.signal.flags.doubtful()).count() as u32;
                actions.push(Action::StoreRow(row));
            }
            ScanEvent::SweptSample(_) => {}
            ScanEvent::Skipped { reason, .. } => {
                outcome.skipped += 1;
                *outcome.skipped_by_reason.entry(reason.to_string()).or_default() += 1;
            }
            ScanEvent::Finished { run, .. } if run == self.run => {
                // The head finished, but events before the end may have been lost.
                return vec![Action::End(match self.expected < self.points {
                    true => Stretch::Interrupted(self.expected, Interruption::Gap),
                    false => Stretch::Finished,
                })];
            }
            ScanEvent::Paused { run, reason: None, .. } if run == self.run && self.pausing => {
                return vec![Action::End(Stretch::Paused(self.expected))];
            }
            ScanEvent::Stopped { run, reason, .. }
            | ScanEvent::Paused {
                run, reason: Some(reason), ..
            } if run == self.run => {
                return vec![match reason {
                    Fault::AdcOverrun | Fault::HostSilent => {
                        Action::End(Stretch::Interrupted(self.expected, Interruption::Transient(reason)))
                    }
                    Fault::StepTimer(_) => Action::End(Stretch::Interrupted(self.expected, Interruption::Rehome(reason))),
                    _ => Action::Fail(format!(
                        "the head stopped the scan: {reason}; resume from position {}",
                        self.expected
                    )),
                }];
            }
            // The end of an earlier run, arriving late.
            ScanEvent::Finished { .. } | ScanEvent::Stopped { .. } | ScanEvent::Paused { .. } => {}
        }
        // Stored first: a refill or a pause that fails ends the stretch
        // after this position, which must then be on disk.
        if order.is_some() && self.queued < self.order_len && self.queued.saturating_sub(self.expected) < (VISIT_QUEUE / 2) as u32 {
            actions.push(Action::Refill);
        }
        if !self.pausing && self.stop_at.is_some_and(|p| self.expected >= p && self.expected < self.points) {
            self.pausing = true;
            actions.push(Action::Pause);
        }
        actions
    }

    /// The operator asks to hold the scan: paused before the next position
    /// (asked once), unless the scan is done; the stretch then ends
    /// `Paused`, as for the monitor.
    pub fn pause(&mut self) -> Option<Action> {
        (!self.pausing && self.expected < self.points).then(|| {
            self.pausing = true;
            Action::Pause
        })
    }

    fn on_swept_sample(&mut self, s: SweptSample, outcome: &mut ScanOutcome) -> Vec<Action> {
        let o = s.scan.map_or(u32::MAX, |p| p.order);
        if o < self.expected || self.row.last().is_some_and(|l| l.seq == s.seq) {
            outcome.duplicates_dropped += 1;
            return Vec::new();
        }
        // Consecutive samples of the row expected, or a gap: the row is
        // swept again.
        if o > self.expected || self.row.last().is_some_and(|l| l.seq.wrapping_add(1) != s.seq) {
            return vec![Action::Gap];
        }
        self.row.push(s);
        Vec::new()
    }

    /// What to do when the head, silent for a while, reports `state`;
    /// `stalled`: no progress for longer than [`EVENT_TIMEOUT`]. `None`:
    /// wait on.
    pub fn on_status(&self, state: HeadState, stalled: bool) -> Option<Action> {
        let at = self.expected;
        match state {
            HeadState::Scanning { next_order, .. } if next_order <= at => stalled.then(|| {
                Action::Fail(format!(
                    "the head has been at position {at} for {} s; resume from position {at}",
                    EVENT_TIMEOUT.as_secs()
                ))
            }),
            HeadState::Scanning { .. } => Some(Action::Gap),
            HeadState::Idle if at >= self.points => Some(Action::End(Stretch::Finished)),
            HeadState::Paused { .. } if self.pausing => Some(Action::End(Stretch::Paused(at))),
            // Held (the head stopped hearing us) or ended early: the next
            // stretch continues from the first position not stored.
            HeadState::Idle | HeadState::Paused { .. } => Some(Action::End(Stretch::Interrupted(at, Interruption::Gap))),
            HeadState::Faulted => Some(Action::Fail(format!(
                "the head's E-STOP is open; close it, then resume from position {at}"
            ))),
            HeadState::Homing | HeadState::Moving | HeadState::Measuring | HeadState::Stopping => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_shared::sample::ScanPosition;
    use gonio_shared::{AxisAngles, Geometry, SampleFlags, Signal};

    fn signal(flags: SampleFlags) -> Signal {
        Signal {
            in_phase_v: 1.0,
            quadrature_v: 0.0,
            amplitude_v: 1.0,
            magnitude_v: 1.0,
            phase_deg: 0.0,
            noise_v: 0.01,
            gain_v_per_a: 1e6,
            gain_index: 1,
            periods: 23,
            flags,
        }
    }

    fn at(order: u32) -> Option<ScanPosition> {
        Some(ScanPosition { index: order, order })
    }

    fn sample(order: u32) -> ScanEvent {
        let g = Geometry::new(30.0, 30.0, 0.0);
        ScanEvent::Sample(Sample {
            seq: 1000 + order,
            scan: at(order),
            timestamp_us: 1_000 * order as u64,
            target: g,
            reached: g,
            axes: AxisAngles::default(),
            signal: signal(SampleFlags::empty()),
        })
    }

    fn swept(order: u32, seq: u32) -> ScanEvent {
        ScanEvent::SweptSample(SweptSample {
            seq,
            scan: at(order),
            start_us: 0,
            duration_s: 0.035,
            axes_from: AxisAngles::default(),
            axes_to: AxisAngles::default(),
            signal: signal(SampleFlags::empty()),
        })
    }

    const RUN: u32 = 7;

    /// A stretch of a 10-position run from position `from`, the head's queue
    /// full to the end.
    fn stretch(from: u32, stop_at: Option<u32>) -> (Sequencer, ScanOutcome) {
        let accepted = ScanAccepted {
            points: 10,
            first_order: from,
            run: RUN,
        };
        let outcome = ScanOutcome {
            points: 10,
            measured: 0,
            swept_samples: 0,
            skipped: 0,
            skipped_by_reason: Default::default(),
            flagged: 0,
            duplicates_dropped: 0,
            recoveries: Default::default(),
            head_time_s: 0.0,
            lower_bound_s: None,
            wall_time_s: 0.0,
        };
        (Sequencer::new(&accepted, from, 10, 10, stop_at), outcome)
    }

    fn stored(a: &[Action]) -> Vec<u32> {
        a.iter()
            .filter_map(|a| match a {
                Action::Store(s) => s.scan.map(|p| p.order),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn positions_in_order_are_stored_once_and_late_copies_dropped() {
        let (mut q, mut o) = stretch(3, None);
        let mut kept = Vec::new();
        for ev in [sample(3), sample(4), sample(3), sample(2), sample(5)] {
            kept.extend(stored(&q.on_event(ev, &mut o)));
        }
        assert_eq!(kept, [3, 4, 5]);
        assert_eq!((o.measured, o.duplicates_dropped, q.expected()), (3, 2, 6));
    }

    #[test]
    fn a_position_skipped_over_is_a_gap_and_nothing_after_it_is_stored() {
        let (mut q, mut o) = stretch(0, None);
        assert_eq!(stored(&q.on_event(sample(0), &mut o)), [0]);
        assert_eq!(q.on_event(sample(2), &mut o), [Action::Gap]);
        assert_eq!(q.expected(), 1, "the next stretch continues at the lost position");
    }

    #[test]
    fn unreachable_points_are_counted_by_reason_and_advance() {
        let (mut q, mut o) = stretch(0, None);
        let skip = ScanEvent::Skipped {
            index: 0,
            order: 0,
            reason: Fault::Unreachable(gonio_shared::fault::Unreachable::BlindZone),
        };
        assert!(q.on_event(skip, &mut o).is_empty());
        assert_eq!((o.skipped, q.expected()), (1, 1));
        assert_eq!(o.skipped_by_reason.values().sum::<u32>(), 1);
    }

    #[test]
    fn a_sweep_row_is_stored_only_whole() {
        let (mut q, mut o) = stretch(4, None);
        for seq in 50..53 {
            assert!(q.on_event(swept(4, seq), &mut o).is_empty());
        }
        // A copy of the last sample is dropped; the row is still whole.
        assert!(q.on_event(swept(4, 52), &mut o).is_empty());
        let done = q.on_event(
            ScanEvent::Swept {
                index: 4,
                order: 4,
                samples: 3,
            },
            &mut o,
        );
        let [Action::StoreRow(row)] = &done[..] else { panic!("{done:?}") };
        assert_eq!(row.iter().map(|s| s.seq).collect::<Vec<_>>(), [50, 51, 52]);
        assert_eq!((o.measured, o.swept_samples, o.duplicates_dropped, q.expected()), (1, 3, 1, 5));
    }

    #[test]
    fn a_sweep_row_missing_a_sample_is_swept_again() {
        // A sequence number skipped within the row.
        let (mut q, mut o) = stretch(4, None);
        q.on_event(swept(4, 50), &mut o);
        assert_eq!(q.on_event(swept(4, 52), &mut o), [Action::Gap]);
        // Or fewer samples than the head says it sent.
        let (mut q, mut o) = stretch(4, None);
        q.on_event(swept(4, 50), &mut o);
        assert_eq!(
            q.on_event(
                ScanEvent::Swept {
                    index: 4,
                    order: 4,
                    samples: 2
                },
                &mut o
            ),
            [Action::Gap]
        );
        assert_eq!(q.expected(), 4);
    }

    #[test]
    fn the_queue_is_refilled_after_the_position_is_stored() {
        let accepted = ScanAccepted {
            points: 1000,
            first_order: 0,
            run: RUN,
        };
        let (_, mut o) = stretch(0, None);
        // The head holds positions up to 100: fewer than half a queue ahead.
        let mut q = Sequencer::new(&accepted, 0, 100, 1000, None);
        let a = q.on_event(sample(0), &mut o);
        assert!(matches!(&a[..], [Action::Store(_), Action::Refill]), "{a:?}");
        q.fed(300);
        assert_eq!(q.queued(), 300);
        assert!(matches!(&q.on_event(sample(1), &mut o)[..], [Action::Store(_)]));
    }

    #[test]
    fn the_monitor_pause_is_asked_once_and_ends_the_stretch_when_held() {
        let (mut q, mut o) = stretch(0, Some(2));
        assert!(!q.on_event(sample(0), &mut o).contains(&Action::Pause));
        assert!(q.on_event(sample(1), &mut o).contains(&Action::Pause));
        // The head finishes the position it is at before it holds.
        assert!(!q.on_event(sample(2), &mut o).contains(&Action::Pause));
        let held = ScanEvent::Paused {
            run: RUN,
            next_order: 3,
            reason: None,
        };
        assert_eq!(q.on_event(held, &mut o), [Action::End(Stretch::Paused(3))]);
    }

    #[test]
    fn the_end_of_this_run_finishes_the_stretch_and_an_earlier_runs_is_ignored() {
        let (mut q, mut o) = stretch(9, None);
        let finished = |run| ScanEvent::Finished {
            run,
            measured: 0,
            skipped: 0,
        };
        assert!(q.on_event(finished(RUN - 1), &mut o).is_empty());
        // Finished while position 9 never came: lost.
        assert_eq!(
            q.on_event(finished(RUN), &mut o),
            [Action::End(Stretch::Interrupted(9, Interruption::Gap))]
        );
        q.on_event(sample(9), &mut o);
        assert_eq!(q.on_event(finished(RUN), &mut o), [Action::End(Stretch::Finished)]);
    }

    #[test]
    fn faults_decide_how_the_host_recovers() {
        let stopped = |reason| ScanEvent::Stopped {
            run: RUN,
            next_order: 5,
            reason,
        };
        let (mut q, mut o) = stretch(5, None);
        assert_eq!(
            q.on_event(stopped(Fault::AdcOverrun), &mut o),
            [Action::End(Stretch::Interrupted(5, Interruption::Transient(Fault::AdcOverrun)))]
        );
        let stall = Fault::StepTimer(gonio_shared::Axis::Rotation);
        assert_eq!(
            q.on_event(stopped(stall), &mut o),
            [Action::End(Stretch::Interrupted(5, Interruption::Rehome(stall)))]
        );
        assert!(matches!(&q.on_event(stopped(Fault::Saturated), &mut o)[..], [Action::Fail(_)]));
    }

    #[test]
    fn a_silent_heads_status_says_what_to_do() {
        let (q, _) = stretch(4, None);
        let scanning = |next_order| HeadState::Scanning { next_order, total: 10 };
        assert_eq!(q.on_status(scanning(4), false), None);
        assert!(matches!(q.on_status(scanning(4), true), Some(Action::Fail(_))));
        assert_eq!(q.on_status(scanning(6), false), Some(Action::Gap), "events lost");
        assert_eq!(
            q.on_status(HeadState::Idle, false),
            Some(Action::End(Stretch::Interrupted(4, Interruption::Gap)))
        );
        assert!(matches!(q.on_status(HeadState::Faulted, false), Some(Action::Fail(_))));
        assert_eq!(q.on_status(HeadState::Moving, true), None);
        let (done, _) = stretch(10, None);
        assert_eq!(done.on_status(HeadState::Idle, false), Some(Action::End(Stretch::Finished)));
    }
}
