//! A scan in progress, apart from the head that runs it: its visit order as
//! the host has queued it, where it stands, what it has counted (its points,
//! its streaks of suspect samples), the row it is sweeping between two turns,
//! and the events that say so. The head decides *when* (its state table, the
//! serve loop's watch) and does the moving and measuring; this says *what
//! comes next*, in a few integer steps per operation.

use crate::sweep::sweeping::Sweeping;
use gonio_shared::{Fault, Field, Reply, SampleFlags, ScanEvent, ScanSpec, Visit, VisitChunk, VisitsQueued, VISIT_QUEUE};
use heapless::Deque;

/// Consecutive scan points that may all be saturated at the lowest gain, or
/// all below the noise floor, before the head stops the scan (stray light or
/// a failed amplifier; a dead laser or a blocked beam). A retroreflector's
/// scan has neither streak; a black sample needs the dark limit relaxed.
pub const SUSPECT_STREAK: u32 = 8;

/// Streaks of suspect samples in a scan.
#[derive(Debug, Default, Clone, Copy)]
struct SuspectStreaks {
    saturated: u32,
    dark: u32,
}

pub(crate) struct ActiveScan {
    /// Number of the run since power-up (`ScanAccepted::run`).
    run: u32,
    spec: ScanSpec,
    /// The visit order the host has sent and the head not yet taken
    /// (canonical indices), and the visit position after its last.
    queue: Deque<u32, VISIT_QUEUE>,
    queued_to: u32,
    total: u32,
    next_order: u32,
    measured: u32,
    skipped: u32,
    /// The position taken from the queue and not yet done: a stop in the
    /// middle of it leaves it here, and continuing visits it again (a row
    /// from its start: the host keeps a row's samples only once it is done).
    current: Option<(u32, Visit)>,
    suspect: SuspectStreaks,
    /// The row a sweep scan is sweeping, between two turns of the serve
    /// loop; any stop ends it (the row is swept again on continuing).
    pub(crate) sweeping: Option<Sweeping>,
}

/// What the scan does next.
pub(crate) enum Next {
    /// Visit position `order`, canonical index `index`: a point or a row.
    Visit { index: u32, order: u32, at: Visit },
    /// The visit queue has run dry before the last point: wait for the host.
    Starved,
    /// Every point is done.
    Finished(ScanEvent),
}

/// What became of a visited point: its event, and whether the scan goes on.
pub(crate) enum Recorded {
    /// Measured or skipped: the scan goes on with its next position.
    GoesOn(ScanEvent),
    /// The visit failed for `reason`: the scan ends with this `Stopped` event.
    Ends(Fault, ScanEvent),
}

impl ActiveScan {
    /// Run `run` of `spec` (already validated: `total` points), from its
    /// `first_order`.
    pub(crate) fn new(run: u32, spec: ScanSpec, total: u32) -> Self {
        let first = spec.first_order;
        ActiveScan {
            run,
            spec,
            queue: Deque::new(),
            queued_to: first,
            total,
            next_order: first,
            measured: 0,
            skipped: 0,
            current: None,
            suspect: SuspectStreaks::default(),
            sweeping: None,
        }
    }

    /// Counts streaks of saturated and of dark samples; a streak of
    /// [`SUSPECT_STREAK`] stops the scan.
    pub(crate) fn count_suspect(&mut self, flags: SampleFlags) -> Result<(), Fault> {
        let streak = |n: &mut u32, hit: bool| {
            *n = if hit { *n + 1 } else { 0 };
            *n >= SUSPECT_STREAK
        };
        if streak(&mut self.suspect.saturated, flags.contains(SampleFlags::SATURATED)) {
            return Err(Fault::Saturated);
        }
        if streak(&mut self.suspect.dark, flags.contains(SampleFlags::BELOW_NOISE)) {
            return Err(Fault::NoSignal);
        }
        Ok(())
    }

    /// `(run, next visit position, points)`, for the status.
    pub(crate) fn progress(&self) -> (u32, u32, u32) {
        (self.run, self.next_order, self.total)
    }

    /// Whether `chunk` is addressed to this run (0: whichever runs).
    pub(crate) fn is_addressed_by(&self, chunk: &VisitChunk) -> bool {
        chunk.run == 0 || chunk.run == self.run
    }

    /// Queues the next stretch of the visit order. A chunk that does not
    /// start where the queue ends takes nothing, and what does not fit is
    /// left out: the answer says where to go on.
    pub(crate) fn queue(&mut self, chunk: &VisitChunk) -> Reply<VisitsQueued> {
        if chunk.indices.iter().any(|&i| i >= self.total) {
            return Err(Fault::InvalidValue(Field::ScanRange));
        }
        if chunk.first_order == self.queued_to {
            for &i in &chunk.indices {
                if self.queued_to >= self.total || self.queue.push_back(i).is_err() {
                    break;
                }
                self.queued_to += 1;
            }
        }
        Ok(VisitsQueued {
            next_order: self.queued_to,
            room: (VISIT_QUEUE - self.queue.len()) as u32,
        })
    }

    /// The position to visit next: the one a stop interrupted, else the
    /// next of the queue.
    pub(crate) fn next(&mut self) -> Next {
        if self.current.is_none() {
            // Indices were checked against the grid when they were queued.
            let order = self.next_order;
            self.current = self.queue.pop_front().and_then(|i| self.spec.visit(i, order).map(|v| (i, v)));
        }
        match self.current {
            Some((index, at)) => Next::Visit {
                index,
                order: self.next_order,
                at,
            },
            None if self.next_order < self.total => Next::Starved,
            None => Next::Finished(ScanEvent::Finished {
                run: self.run,
                measured: self.measured,
                skipped: self.skipped,
            }),
        }
    }

    /// Counts what became of position `index` at visit position `order`: a
    /// measured one (its `Sample` or `Swept` event) goes on, an unreachable
    /// or refused geometry is skipped, any other fault ends the scan (it
    /// resumes at this position).
    pub(crate) fn record(&mut self, index: u32, order: u32, result: Reply<ScanEvent>) -> Recorded {
        match result {
            Ok(ev) => {
                self.measured += 1;
                self.advance();
                Recorded::GoesOn(ev)
            }
            Err(reason @ (Fault::Unreachable(_) | Fault::InvalidValue(_))) => {
                self.skipped += 1;
                self.advance();
                Recorded::GoesOn(ScanEvent::Skipped { index, order, reason })
            }
            Err(reason) => Recorded::Ends(reason, self.stopped(reason)),
        }
    }

    fn advance(&mut self) {
        self.current = None;
        self.next_order += 1;
    }

    /// The event of this run stopped for `reason` (it will not go on).
    pub(crate) fn stopped(&self, reason: Fault) -> ScanEvent {
        ScanEvent::Stopped {
            run: self.run,
            next_order: self.next_order,
            reason,
        }
    }

    /// The event of this run held at its next point: at the host's request
    /// (`None`) or for a fault.
    pub(crate) fn paused(&self, reason: Option<Fault>) -> ScanEvent {
        ScanEvent::Paused {
            run: self.run,
            next_order: self.next_order,
            reason,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_shared::Unreachable;

    fn belcour_run(indices: &[u32]) -> ActiveScan {
        let spec = ScanSpec::belcour();
        let total = spec.validate().unwrap();
        let mut run = ActiveScan::new(1, spec, total);
        let chunk = VisitChunk {
            run: 1,
            first_order: 0,
            indices: heapless::Vec::from_slice(indices).unwrap(),
        };
        assert_eq!(run.queue(&chunk).unwrap().next_order, indices.len() as u32);
        run
    }

    fn visit(run: &mut ActiveScan) -> (u32, u32) {
        match run.next() {
            Next::Visit { index, order, .. } => (index, order),
            _ => panic!("a queued point is visited next"),
        }
    }

    #[test]
    fn a_skipped_point_goes_on_and_a_failed_one_ends_the_scan_where_it_failed() {
        let mut run = belcour_run(&[5, 7, 9]);
        assert_eq!(visit(&mut run), (5, 0));
        let unreachable = Fault::Unreachable(Unreachable::BlindZone);
        match run.record(5, 0, Err(unreachable)) {
            Recorded::GoesOn(ScanEvent::Skipped {
                index: 5,
                order: 0,
                reason,
            }) => assert_eq!(reason, unreachable),
            _ => panic!("an unreachable point is skipped"),
        }
        assert_eq!(visit(&mut run), (7, 1));
        match run.record(7, 1, Err(Fault::WeakSignal)) {
            Recorded::Ends(
                Fault::WeakSignal,
                ScanEvent::Stopped {
                    run: 1,
                    next_order: 1,
                    reason,
                },
            ) => {
                assert_eq!(reason, Fault::WeakSignal)
            }
            _ => panic!("a failed visit ends the scan"),
        }
        // Held instead of dropped, it would visit the failed point again.
        assert_eq!(visit(&mut run), (7, 1));
        assert_eq!(run.progress(), (1, 1, 3441));
    }
}
