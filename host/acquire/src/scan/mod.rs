//! Running a scan on a connected head: the request, the event stream with
//! its continuity check, durable storage of every sample, progress.
//! [`directory`] wraps it in a scan directory.

pub mod directory;
pub mod live;
pub mod page;
pub mod progress;
pub mod sequencer;

use crate::client::{is_link_loss, HeadClient};
use crate::session::Session;
use anyhow::{bail, Context, Result};
use gonio_scan_dir::record::Monitor;
use gonio_scan_dir::run::ScanOutcome;
use gonio_scan_dir::samples::SampleWriter;
use gonio_shared::icd::{
    AbortEndpoint, HomeEndpoint, HomeRequest, MeasureEndpoint, MeasureRequest, PauseEndpoint, StatusEndpoint, VisitEndpoint,
};
use gonio_shared::{HeadState, ScanAccepted, ScanEvent, ScanSpec, VisitChunk, VISIT_CHUNK, VISIT_QUEUE};
use postcard_rpc::host_client::Subscription;
use progress::Progress;
use sequencer::{Action, Interruption, Sequencer, Stretch, EVENT_TIMEOUT};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// Recoveries in a row without a new point before the host gives up.
const MAX_RECOVERIES: u32 = 5;
/// How long the host waits for an event before asking the head how it is.
const POLL: Duration = Duration::from_secs(1);

/// Runs `spec` to the end in the visit `order` (canonical index per visit
/// position, the whole scan's: [`crate::scan_order::visit_order`] for the
/// mechanics the head reported, planned once by the caller, which times
/// the scan by it; the head keeps only the next `VISIT_QUEUE` of it),
/// appending every sample (and every monitor reading, a row without scan
/// position) to `out`. Lost, damaged, duplicated or reordered events, a
/// lost link and transient faults are recovered: no position is stored
/// twice or left out.
pub async fn drive(
    session: &mut Session,
    spec: &ScanSpec,
    order: Vec<u32>,
    out: &mut SampleWriter,
    pb: &Progress,
    monitor: Option<&Monitor>,
) -> Result<ScanOutcome> {
    let t0 = Instant::now();
    let mut first = spec.first_order;
    let mut run = ScanDriver {
        session,
        out,
        pb,
        outcome: ScanOutcome {
            points: spec.len(),
            measured: 0,
            swept_samples: 0,
            skipped: 0,
            skipped_by_reason: BTreeMap::new(),
            flagged: 0,
            duplicates_dropped: 0,
            recoveries: BTreeMap::new(),
            head_time_s: 0.0,
            lower_bound_s: None,
            wall_time_s: 0.0,
        },
        clock: HeadClock::default(),
        recoveries_in_a_row: 0,
        progress: first,
        order,
    };
    let mut read_monitor_now = true;
    loop {
        if let (Some(m), true) = (monitor, read_monitor_now) {
            if !run.visit_monitor(m, first).await? {
                continue;
            }
        }
        let stop_at = monitor.map(|m| first.saturating_add(m.every.max(1)));
        let stretch = ScanSpec {
            first_order: first,
            ..spec.clone()
        };
        pb.live().state("scanning");
        match run.stretch(&stretch, stop_at).await? {
            Stretch::Finished => break,
            Stretch::Paused(next) => {
                first = next;
                // Held for the operator: the monitor waits for its turn.
                read_monitor_now = !pb.live().pause_requested();
                if !read_monitor_now {
                    run.hold(next).await?;
                }
            }
            Stretch::Interrupted(next, why) => {
                run.recover(why, next).await?;
                first = next;
                read_monitor_now = false;
            }
        }
    }
    if let Some(m) = monitor {
        while !run.visit_monitor(m, run.outcome.points).await? {}
    }
    pb.finish();
    pb.live().state("finished");
    let mut outcome = run.outcome;
    outcome.head_time_s = run.clock.span_s();
    outcome.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(outcome)
}

/// The host's side of one scan: what every stretch, monitor visit and
/// recovery shares (the head keeps its own `ActiveScan`).
struct ScanDriver<'a> {
    session: &'a mut Session,
    out: &'a mut SampleWriter,
    pb: &'a Progress,
    outcome: ScanOutcome,
    clock: HeadClock,
    /// Recoveries without a new point since, counted to give up.
    recoveries_in_a_row: u32,
    /// The furthest position reached.
    progress: u32,
    /// Canonical index per visit position.
    order: Vec<u32>,
}

impl ScanDriver<'_> {
    /// Recovers from an interruption before position `next`: reconnects, or
    /// homes, or (events lost, a transient fault) nothing but continuing.
    async fn recover(&mut self, why: Interruption, next: u32) -> Result<()> {
        if next > self.progress {
            (self.recoveries_in_a_row, self.progress) = (0, next);
        }
        self.recoveries_in_a_row += 1;
        if self.recoveries_in_a_row > MAX_RECOVERIES {
            bail!(
                "{}; gave up after {MAX_RECOVERIES} recoveries without progress; resume from position {next}",
                why.name()
            );
        }
        *self.outcome.recoveries.entry(why.name()).or_default() += 1;
        self.pb.live().state(format!("recovering: {}", why.name()));
        let operator = self.session.operator;
        self.pb
            .suspend(|| operator.notice(format_args!("scan interrupted: {}; continuing from position {next}", why.name())));
        match why {
            Interruption::LinkLost(_) => self
                .session
                .reconnect()
                .await
                .with_context(|| format!("resume from position {next}")),
            Interruption::Rehome(_) => self
                .session
                .head()
                .request::<HomeEndpoint>(&HomeRequest::ALL)
                .await
                .map(drop)
                .with_context(|| format!("homing after a stalled move; resume from position {next}")),
            Interruption::Gap | Interruption::Transient(_) => Ok(()),
        }
    }

    /// Holds the scan, paused before position `next`, until the operator
    /// asks it to go on; the head hears from the host meanwhile (its status,
    /// every heartbeat), so that it does not take the silence for a lost host.
    async fn hold(&mut self, next: u32) -> Result<()> {
        let live = self.pb.live().clone();
        live.state("paused");
        let operator = self.session.operator;
        self.pb.suspend(|| {
            operator.notice(format_args!(
                "paused before position {next}: the head holds (laser off, stages at rest); continue from the live page or with `gonio continue DIR`"
            ))
        });
        loop {
            tokio::select! {
                () = live.resumed() => break,
                () = tokio::time::sleep(self.session.heartbeat() / 2) => {
                    if let Err(e) = self.session.head().request::<StatusEndpoint>(&()).await {
                        if !is_link_loss(&e) {
                            return Err(e.context("keeping the paused head awake"));
                        }
                        self.recover(Interruption::LinkLost(format!("{e:#}")), next).await?;
                    }
                }
            }
        }
        live.state("scanning");
        Ok(())
    }

    /// One visit to the monitor before position `next`; a lost link is
    /// recovered (reconnected) and reported as `false`: the visit is to be
    /// made again.
    async fn visit_monitor(&mut self, m: &Monitor, next: u32) -> Result<bool> {
        match read_monitor(self.session.head(), m, self.out, &mut self.clock).await {
            Ok(()) => Ok(true),
            Err(e) if is_link_loss(&e) => {
                self.recover(Interruption::LinkLost(format!("{e:#}")), next).await?;
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }

    /// Runs the scan from `spec.first_order`, to the end or, with `stop_at`,
    /// until that visit position has been reached (then pauses it between
    /// points), or until something interrupts it: the requests, events and
    /// storage of the [`Sequencer`]'s decisions.
    async fn stretch(&mut self, spec: &ScanSpec, stop_at: Option<u32>) -> Result<Stretch> {
        let head = self.session.head();
        let (out, pb, outcome, clock, order) = (&mut *self.out, self.pb, &mut self.outcome, &mut self.clock, &self.order);
        let from = spec.first_order;
        // A scan the head holds where this stretch begins (paused for the
        // monitor, or after host silence or a lost link) is continued
        // without replanning; otherwise it starts (or replaces the held one).
        let held = match head.request::<StatusEndpoint>(&()).await {
            Ok(st) => {
                clock.start(st.uptime_us);
                match st.state {
                    HeadState::Paused { run, next_order, total } if next_order == from && total == spec.len() => Some((run, total)),
                    _ => None,
                }
            }
            Err(e) => return lost(e, from),
        };
        let started = match held {
            Some((run, points)) => head.continue_events().await.map(|(_, sub)| {
                let accepted = ScanAccepted {
                    points,
                    first_order: from,
                    run,
                };
                (accepted, sub)
            }),
            None => head.start_scan(spec).await,
        };
        let (accepted, mut events) = match started {
            Ok(x) => x,
            Err(e) => return lost(e, from),
        };
        outcome.points = accepted.points;
        // The head holds the visit order from here on (a held scan may hold more).
        let queued = match feed(head, accepted.run, order, from).await {
            Ok(q) => q,
            Err(e) => return lost(e, from),
        };
        let mut seq = Sequencer::new(&accepted, from, queued, order.len() as u32, stop_at);
        let mut beat = Instant::now();
        let (mut waiting_since, mut progress) = (Instant::now(), seq.progress());
        loop {
            let mut actions = match tokio::time::timeout(POLL, events.recv()).await {
                Ok(None) => {
                    return Ok(Stretch::Interrupted(
                        seq.expected(),
                        Interruption::LinkLost("the link closed".into()),
                    ))
                }
                Ok(Some(ev)) => {
                    if beat.elapsed() > self.session.heartbeat() {
                        beat = Instant::now();
                        if let Err(e) = head.request::<StatusEndpoint>(&()).await {
                            return lost(e, seq.expected());
                        }
                    }
                    seq.on_event(ev, outcome)
                }
                Err(_) => {
                    // No event for a while: ask the head where it is (this is
                    // also the heartbeat the head watches for).
                    beat = Instant::now();
                    match head.request::<StatusEndpoint>(&()).await {
                        // An event the head sent before this answer is in
                        // the channel by now: taken first, or a head that
                        // finished the position while the question was on
                        // its way would look like one whose event was lost.
                        Ok(st) => match arrived(&mut events).await {
                            Some(ev) => seq.on_event(ev, outcome),
                            None => seq
                                .on_status(st.state, waiting_since.elapsed() > EVENT_TIMEOUT)
                                .into_iter()
                                .collect(),
                        },
                        Err(e) => return lost(e, seq.expected()),
                    }
                }
            };
            if pb.live().pause_requested() {
                actions.extend(seq.pause());
            }
            for action in actions {
                match action {
                    Action::Store(s) => {
                        out.push(&s)?;
                        clock.saw(s.timestamp_us);
                        pb.sample(&s.reached, &s.signal);
                    }
                    Action::StoreRow(row) => {
                        out.push_swept(&row)?;
                        for s in &row {
                            pb.sample(&gonio_scan_dir::swept::geometry(s), &s.signal);
                        }
                        if let Some(last) = row.last() {
                            clock.saw(last.start_us + (last.duration_s as f64 * 1e6) as u64);
                        }
                    }
                    Action::Refill => match feed(head, accepted.run, order, seq.queued()).await {
                        Ok(q) => seq.fed(q),
                        Err(e) => return lost(e, seq.expected()),
                    },
                    Action::Pause => {
                        if let Err(e) = head.request::<PauseEndpoint>(&()).await {
                            return lost(e.context("pausing the scan"), seq.expected());
                        }
                    }
                    Action::Gap => return gap(head, seq.expected()).await,
                    Action::End(end) => return Ok(end),
                    Action::Fail(why) => bail!(why),
                }
            }
            if seq.progress() != progress {
                pb.update(seq.expected(), clock.span_s(), outcome.measured, outcome.skipped);
                (waiting_since, progress) = (Instant::now(), seq.progress());
            }
        }
    }
}

/// The event already received, if any, taken without waiting: the link's
/// reader hands a frame to the subscription before it reads the next, so
/// an event sent before an answer is here once the answer is.
async fn arrived(events: &mut Subscription<ScanEvent>) -> Option<ScanEvent> {
    tokio::time::timeout(Duration::ZERO, tokio::task::unconstrained(events.recv()))
        .await
        .ok()
        .flatten()
}

/// A request of the stretch failed at position `at`: a lost link is an
/// interruption to recover from, any other error ends the scan.
fn lost(e: anyhow::Error, at: u32) -> Result<Stretch> {
    if is_link_loss(&e) {
        Ok(Stretch::Interrupted(at, Interruption::LinkLost(format!("{e:#}"))))
    } else {
        Err(e)
    }
}

/// Events were lost or came out of order at position `expected`: the
/// head's scan is aborted, and the next stretch continues from there.
async fn gap(head: &HeadClient, expected: u32) -> Result<Stretch> {
    match head.request::<AbortEndpoint>(&()).await {
        Ok(_) => Ok(Stretch::Interrupted(expected, Interruption::Gap)),
        Err(e) => lost(e, expected),
    }
}

/// Sends the visit order from position `from` until the head's queue is full
/// or the order ends; returns the position the head's queue ends at. The
/// head says where its queue ends, so a guess (a held scan's queue may reach
/// further) costs one round trip. A plan the head refuses (its scan ended
/// for a fault) is left to the event stream to explain.
pub async fn feed(head: &HeadClient, run: u32, order: &[u32], mut from: u32) -> Result<u32> {
    // Each turn queues a chunk or learns where the queue ends.
    for _ in 0..2 * VISIT_QUEUE {
        let Some(rest) = order.get(from as usize..).filter(|r| !r.is_empty()) else {
            break;
        };
        let chunk = VisitChunk {
            run,
            first_order: from,
            indices: rest.iter().copied().take(VISIT_CHUNK).collect(),
        };
        match head.request::<VisitEndpoint>(&chunk).await {
            // A chunk taken in part filled the queue: room is then 0.
            Ok(q) => {
                from = q.next_order;
                if q.room == 0 {
                    break;
                }
            }
            Err(e) if is_link_loss(&e) => return Err(e),
            Err(_) => break,
        }
    }
    Ok(from)
}

/// Readings per monitor visit: every sample of the scan is referred to them,
/// so their noise is averaged down (`gonio calibrate` merges a visit's readings).
pub const MONITOR_READINGS: usize = 4;

/// One visit to the monitor geometry: a move, then [`MONITOR_READINGS`]
/// measurements in place.
async fn read_monitor(head: &HeadClient, m: &Monitor, out: &mut SampleWriter, clock: &mut HeadClock) -> Result<()> {
    for k in 0..MONITOR_READINGS {
        let at = (k == 0).then_some(m.at);
        let s = head
            .request::<MeasureEndpoint>(&MeasureRequest { at })
            .await
            .context("measuring the laser-drift monitor")?;
        out.push(&s)?;
        clock.saw(s.timestamp_us);
    }
    Ok(())
}

/// First and last timestamp the head reported (µs).
#[derive(Default)]
struct HeadClock {
    first: Option<u64>,
    last: u64,
}

impl HeadClock {
    fn saw(&mut self, t_us: u64) {
        self.first.get_or_insert(t_us);
        self.last = t_us;
    }

    /// The head's clock when the scan starts: the first move counts too.
    fn start(&mut self, t_us: u64) {
        self.first.get_or_insert(t_us);
        self.last = self.last.max(t_us);
    }

    fn span_s(&self) -> f64 {
        self.last.saturating_sub(self.first.unwrap_or(self.last)) as f64 * 1e-6
    }
}
