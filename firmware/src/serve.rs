//! The head's side of the protocol: the serve loop, request dispatch, replies
//! and the scan's event stream.
//!
//! Every operation that takes time (homing, a move, a measurement, a scan
//! point) runs *under watch*: raced against the link, the E-STOP input and
//! the host timer ([`watch`]). An abort, a pause of a scan, a closed link,
//! a silent host or an open E-STOP ends the race at once; the operation is
//! dropped where it stands, the laser goes off in the state table's
//! transition, and the motion decelerates from its current speed
//! ([`Head::stop`]). A status poll is answered at once, from the head's
//! state as the operation began (the operation owns the head: its axes are
//! where it started, its state is the operation's); other requests that
//! arrive meanwhile are kept and answered when the operation ends.

use crate::active_scan::{Next, Recorded};
use crate::dispatch::{decode, encode, midway, request_id, Command, DecodeError, Midway};
use crate::head::Head;
use crate::hw::{Board, Sentry, Wake, ALIVE_EVERY_US};
use crate::link::{Link, LinkError};
use crate::state::{Event, Mode};
use crate::sweep::turns::SweepTurn;
use core::pin::pin;
use embassy_futures::select::{select, Either};
use embedded_hal_async::delay::DelayNs;
use gonio_shared::icd::{
    AbortEndpoint, ContinueEndpoint, DetectionEndpoint, HomeEndpoint, IdentifyEndpoint, LearnEndpoint, MeasureEndpoint, MechanicsEndpoint,
    MoveEndpoint, PauseEndpoint, SafetyEndpoint, SanityEndpoint, ScanEndpoint, ScanEventTopic, StatusEndpoint, VisitEndpoint,
};
use gonio_shared::sample::ScanPosition;
use gonio_shared::wire::check;
use gonio_shared::wire::framing::MAX_FRAME;
use gonio_shared::{Fault, HeadState, Reply, ScanEvent, Status, SweptSample, Visit};
use heapless::{Deque, Vec};
use postcard_rpc::header::{VarKeyKind, VarSeq};
use postcard_rpc::standard_icd::{WireError, ERROR_KEY};
use postcard_rpc::{Endpoint, Key, Topic};
use serde::Serialize;

/// Requests kept while an operation runs; beyond them a request is refused
/// at once with postcard-rpc's `WireError::FailedToSpawn` (no room to
/// handle it), as the last one kept is when an abort or a pause takes its
/// place. The link is still read, so an abort, a pause, a status poll or a
/// closed link is seen at once.
const HELD: usize = 16;

/// How long the E-STOP input must read closed before continuing re-arms
/// the head (µs): a bouncing contact does not re-arm it.
pub const ESTOP_DEBOUNCE_US: u64 = 20_000;

type Frame = Vec<u8, MAX_FRAME>;

/// Frames from the host: the receive buffer and the requests held back.
pub struct Inbox {
    rx: [u8; MAX_FRAME],
    held: Deque<Frame, HELD>,
}

impl Inbox {
    fn new() -> Self {
        Inbox {
            rx: [0; MAX_FRAME],
            held: Deque::new(),
        }
    }

    /// The requests kept, as a status reports them ([`HELD`] fits a byte).
    fn held_count(&self) -> u8 {
        self.held.len() as u8
    }

    fn frame(&self, n: usize) -> Frame {
        Vec::from_slice(&self.rx[..n.min(MAX_FRAME)]).unwrap_or_default()
    }
}

/// `deadline`, or sooner: the serve loop wakes at least every
/// [`ALIVE_EVERY_US`] (a wake that is not the deadline changes nothing).
fn alive_by<S: Sentry>(sentry: &S, deadline: Option<u64>) -> Option<u64> {
    let by = sentry.now_us().saturating_add(ALIVE_EVERY_US);
    Some(deadline.map_or(by, |d| d.min(by)))
}

/// What ended an operation under watch.
#[derive(Debug)]
enum Trip {
    /// An abort or a pause request, put first among the held requests (it is
    /// answered once the motion stands).
    Request(Midway),
    LinkLost,
    HostSilent,
    EStop,
}

/// Watches the link, the E-STOP input and the host timer while an operation
/// runs; returns what stops it. A status poll is answered with `status`
/// (its uptime and E-STOP input read now); requests other than abort (and
/// pause, when `pause` trips) are held for later; every frame shows the
/// host is there.
async fn watch<L: Link, S: Sentry>(
    link: &mut L,
    sentry: &mut S,
    inbox: &mut Inbox,
    heard: &mut u64,
    silence_us: Option<u64>,
    pause: bool,
    status: &Status,
) -> Trip {
    loop {
        sentry.alive();
        let deadline = silence_us.map(|t| heard.saturating_add(t));
        match select(sentry.until(alive_by(sentry, deadline), true), link.recv(&mut inbox.rx)).await {
            Either::First(Wake::EStop) => return Trip::EStop,
            Either::First(Wake::Deadline) => {
                if deadline.is_some_and(|d| sentry.now_us() >= d) {
                    return Trip::HostSilent;
                }
            }
            Either::Second(Err(_)) => return Trip::LinkLost,
            Either::Second(Ok(n)) => {
                // Any frame, even a damaged one, shows the host is there.
                *heard = sentry.now_us();
                let frame = inbox.frame(n);
                match midway(&frame) {
                    kind @ (Midway::Abort | Midway::Pause) if pause || matches!(kind, Midway::Abort) => {
                        // Room is made for it: it is answered first.
                        if inbox.held.is_full() {
                            if let Some(last) = inbox.held.pop_back() {
                                if refuse_unheld(&last, link).await.is_err() {
                                    return Trip::LinkLost;
                                }
                            }
                        }
                        let _ = inbox.held.push_front(frame);
                        return Trip::Request(kind);
                    }
                    Midway::Status(seq, kind) => {
                        let now = Status {
                            uptime_us: sentry.now_us(),
                            estop_open: sentry.estop_open(),
                            requests_held: inbox.held_count(),
                            ..*status
                        };
                        if send_keyed(kind, StatusEndpoint::RESP_KEY, seq, &now, link).await.is_err() {
                            return Trip::LinkLost;
                        }
                    }
                    _ => {
                        if let Err(frame) = inbox.held.push_back(frame) {
                            if refuse_unheld(&frame, link).await.is_err() {
                                return Trip::LinkLost;
                            }
                        }
                    }
                }
            }
        }
    }
}

impl<B: Board> Head<B> {
    /// Serves the host until the link fails; the head is then in its safe
    /// state (a running scan held at its next point, to be continued).
    pub async fn serve<L: Link, S: Sentry>(&mut self, link: &mut L, sentry: &mut S) -> LinkError {
        let mut inbox = Inbox::new();
        // An event of a session that ended is not for this one.
        self.talk.pending_event = None;
        let mut served_frame = false;
        loop {
            sentry.alive();
            self.estop_open = sentry.estop_open();
            // While a row is swept, its next sample comes after at most one
            // request: the ADC's ring (two chop periods) fills meanwhile,
            // and a burst of requests must not overrun it.
            let frames_first = !(self.sweeping() && served_frame);
            let held = if frames_first { inbox.held.pop_front() } else { None };
            served_frame = false;
            let r = if let Some(f) = held {
                served_frame = true;
                self.handle(&f, link, sentry, &mut inbox).await
            } else if self.mode == Mode::Scanning {
                match frames_first.then(|| link.try_recv(&mut inbox.rx)).flatten() {
                    Some(Ok(n)) => {
                        served_frame = true;
                        self.heard_host(sentry);
                        let f = inbox.frame(n);
                        self.handle(&f, link, sentry, &mut inbox).await
                    }
                    Some(Err(e)) => Err(e),
                    None => self.scan_step(link, sentry, &mut inbox).await,
                }
            } else {
                self.rest(link, sentry, &mut inbox).await
            };
            let r = match (r, self.talk.pending_event.take()) {
                (Ok(()), Some(ev)) => self.publish::<ScanEventTopic, L>(&ev, link).await,
                (r, _) => r,
            };
            if let Err(e) = r {
                // Laser off and motion braked at once; a scan is held. A
                // stop that already made the head safe (it found the link
                // closed) is not reported twice.
                if self.mode.busy() {
                    let _ = self.tripped(Trip::LinkLost).await;
                } else {
                    self.stop(Event::LinkLost).await;
                }
                crate::info!("link lost; head in safe state");
                return e;
            }
            // One turn of this loop is at most one stretch of the executor:
            // a turn whose awaits all completed at once (requests already
            // received, replies that found room in the USB channel, a scan
            // point skipped for its kinematics) would otherwise run into the
            // next, and a burst of queued visit chunks or a run of
            // unreachable points into one long stretch.
            embassy_futures::yield_now().await;
        }
    }

    /// At rest: waits for a request, the E-STOP or an idle deadline.
    async fn rest<L: Link, S: Sentry>(&mut self, link: &mut L, sentry: &mut S, inbox: &mut Inbox) -> Result<(), LinkError> {
        let armed = self.mode != Mode::Faulted;
        if self.wait(link, sentry, inbox, self.rest_deadline(), armed).await? {
            self.rest_expired();
        }
        Ok(())
    }

    /// Waits for a request (and serves it), the E-STOP (when `armed`) or
    /// `deadline`, waking at least every [`ALIVE_EVERY_US`]; true when it
    /// woke for the time (the deadline, or only to show it is alive).
    async fn wait<L: Link, S: Sentry>(
        &mut self,
        link: &mut L,
        sentry: &mut S,
        inbox: &mut Inbox,
        deadline: Option<u64>,
        armed: bool,
    ) -> Result<bool, LinkError> {
        match select(sentry.until(alive_by(sentry, deadline), armed), link.recv(&mut inbox.rx)).await {
            Either::First(Wake::EStop) => {
                let _ = self.tripped(Trip::EStop).await;
                Ok(false)
            }
            Either::First(Wake::Deadline) => Ok(true),
            Either::Second(Ok(n)) => {
                self.heard_host(sentry);
                let f = inbox.frame(n);
                self.handle(&f, link, sentry, inbox).await.map(|()| false)
            }
            Either::Second(Err(e)) => Err(e),
        }
    }

    fn heard_host<S: Sentry>(&mut self, sentry: &S) {
        self.last_heard_us = sentry.now_us();
    }

    /// Runs `op` under watch; `Err` says what stopped it (the operation was
    /// dropped where it stood: [`Head::tripped`] makes the head safe).
    /// Status polls meanwhile are answered with the state `busy` (the
    /// operation's; `None`: the head's own, a scan's).
    async fn guarded<T, L: Link, S: Sentry>(
        &mut self,
        link: &mut L,
        sentry: &mut S,
        inbox: &mut Inbox,
        pause: bool,
        busy: Option<HeadState>,
        op: impl AsyncFnOnce(&mut Self) -> T,
    ) -> Result<T, Trip> {
        let silence = self.host_timeout_us();
        let mut heard = self.last_heard_us;
        let mut status = self.status();
        if let Some(state) = busy {
            status.state = state;
        }
        let r = select(op(self), watch(link, sentry, inbox, &mut heard, silence, pause, &status)).await;
        self.last_heard_us = heard;
        match r {
            Either::First(v) => Ok(v),
            Either::Second(trip) => Err(trip),
        }
    }

    /// Stops the head after `trip`, keeps an abort or pause request to be
    /// answered next, holds or drops the scan; returns the fault to answer
    /// the interrupted request with, or the link's error.
    async fn tripped(&mut self, trip: Trip) -> Result<Fault, LinkError> {
        let (event, fault) = match trip {
            Trip::Request(kind) => {
                // Only a scan is paused, and only a scan point trips on it.
                let event = if matches!(kind, Midway::Pause) {
                    Event::Pause
                } else {
                    Event::Abort
                };
                (event, Fault::Aborted)
            }
            Trip::LinkLost => (Event::LinkLost, Fault::LinkLost),
            Trip::HostSilent => (Event::HostSilent, Fault::HostSilent),
            Trip::EStop => {
                self.estop_open = true;
                (Event::EStop, Fault::EmergencyStop)
            }
        };
        self.stop(event).await;
        if self.mode == Mode::Paused {
            self.hold_scan((event != Event::Pause).then_some(fault));
        } else {
            self.drop_scan(fault);
            self.last_fault = Some(fault);
        }
        crate::info!("stopped: E{}", fault.code());
        if event == Event::LinkLost {
            Err(LinkError::Closed)
        } else {
            Ok(fault)
        }
    }

    /// Runs an operation (in state `busy`) under watch and turns a stop
    /// into its answer.
    async fn operate<T, L: Link, S: Sentry>(
        &mut self,
        link: &mut L,
        sentry: &mut S,
        inbox: &mut Inbox,
        busy: HeadState,
        op: impl AsyncFnOnce(&mut Self) -> Reply<T>,
    ) -> Result<Reply<T>, LinkError> {
        match self.guarded(link, sentry, inbox, false, Some(busy), op).await {
            Ok(r) => Ok(r),
            Err(trip) => Ok(Err(self.tripped(trip).await?)),
        }
    }

    /// Pauses a running scan (braking a move in progress), or answers why not.
    async fn pause(&mut self) -> Reply<Status> {
        if self.mode == Mode::Scanning {
            self.stop(Event::Pause).await;
            self.hold_scan(None);
            return Ok(self.status());
        }
        self.apply(Event::Pause).map(|()| self.status())
    }

    /// Continues a held scan where it stopped, or re-arms the head after an
    /// E-STOP once the input has read closed for [`ESTOP_DEBOUNCE_US`].
    async fn continue_scan<S: Sentry>(&mut self, sentry: &mut S) -> Reply<Status> {
        if self.mode == Mode::Faulted {
            sentry.rearm();
            // Closed now, and still closed the debounce time later.
            let bounced = sentry.estop_open()
                || matches!(
                    select(self.hw.delay.delay_us(ESTOP_DEBOUNCE_US as u32), sentry.until(None, true)).await,
                    Either::Second(_)
                );
            if bounced {
                self.estop_open = true;
                return Err(Fault::EmergencyStop);
            }
            self.estop_open = false;
            if sentry.rearmed() {
                // The backstop cut the drivers mid-stop: where the axes
                // stand is no longer known.
                self.pos.homed = [false; 3];
                self.drivers(false);
                crate::warn!("the E-STOP's backstop disabled the drivers: home again");
            }
        }
        self.apply(Event::Continue)?;
        self.last_heard_us = sentry.now_us();
        Ok(self.status())
    }

    /// Aborts what runs (braking a move in progress), drops a held scan, and
    /// leaves the laser and the drivers off.
    async fn abort(&mut self) -> Status {
        self.stop(Event::Abort).await;
        self.drop_scan(Fault::Aborted);
        self.status()
    }

    /// Checks, decodes and answers one frame. A frame that fails its check
    /// is dropped unanswered: its header may be damaged too, and the host
    /// recovers a lost request by its timeout.
    async fn handle<L: Link, S: Sentry>(
        &mut self,
        sealed: &[u8],
        link: &mut L,
        sentry: &mut S,
        inbox: &mut Inbox,
    ) -> Result<(), LinkError> {
        let Some(frame) = check::open(sealed) else {
            return Ok(());
        };
        let (hdr, cmd) = match decode(frame) {
            Ok(x) => x,
            Err(DecodeError::NoHeader) => return Ok(()),
            Err(DecodeError::Wire(hdr, e)) => return self.send_keyed(ERROR_KEY, hdr.seq_no, &e, link).await,
        };
        self.talk.key_kind = hdr.key.kind();
        let seq = hdr.seq_no;
        // Each arm names its endpoint (so its answer's type is checked
        // against the table) and the answer: computed at once, or by an
        // operation run under watch (`operate`).
        macro_rules! answer {
            ($ep:ident, $resp:expr) => {{
                let resp = $resp;
                self.reply::<$ep, L>(seq, &resp, link).await
            }};
        }
        macro_rules! under_watch {
            ($ep:ident, $busy:expr, |$h:ident| $op:expr) => {
                answer!(
                    $ep,
                    self.operate(link, sentry, inbox, $busy, async |$h: &mut Self| $op.await)
                        .await?
                )
            };
        }
        match cmd {
            Command::Identify(()) => answer!(IdentifyEndpoint, self.identity()),
            Command::Status(()) => answer!(
                StatusEndpoint,
                Status {
                    requests_held: inbox.held_count(),
                    ..self.status()
                }
            ),
            Command::Mechanics(()) => answer!(MechanicsEndpoint, self.cfg.mechanics()),
            Command::Home(r) => under_watch!(HomeEndpoint, HeadState::Homing, |h| h.home(r)),
            Command::Move(g) => under_watch!(MoveEndpoint, HeadState::Moving, |h| h.move_to(g)),
            Command::Measure(r) => under_watch!(MeasureEndpoint, HeadState::Measuring, |h| h.measure(r)),
            Command::Learn(c) => under_watch!(LearnEndpoint, HeadState::Measuring, |h| h.learn_reference(c)),
            Command::Scan(spec) => answer!(ScanEndpoint, self.start_scan(spec)),
            Command::Visits(chunk) => answer!(VisitEndpoint, self.queue_visits(&chunk)),
            Command::Abort(()) => answer!(AbortEndpoint, self.abort().await),
            Command::Pause(()) => answer!(PauseEndpoint, self.pause().await),
            Command::Continue(()) => answer!(ContinueEndpoint, self.continue_scan(sentry).await),
            Command::Detection(s) => answer!(DetectionEndpoint, self.configure_detection(s)),
            Command::Sanity(c) => answer!(SanityEndpoint, self.load_sanity(c)),
            Command::Safety(c) => answer!(SafetyEndpoint, self.configure_safety(c)),
        }
    }

    /// Visits the next position of the running scan, under watch, and
    /// publishes what happened: a point whole, a sweep scan's row one turn
    /// (one sample) at a time, so requests are served between its samples;
    /// holds the scan instead when the host has gone silent.
    async fn scan_step<L: Link, S: Sentry>(&mut self, link: &mut L, sentry: &mut S, inbox: &mut Inbox) -> Result<(), LinkError> {
        if self.silence_deadline().is_some_and(|d| sentry.now_us() >= d) {
            self.tripped(Trip::HostSilent).await?;
            return Ok(());
        }
        // The run is out of the head while its position is visited (the
        // visit needs the whole head), and goes back unless the visit ended it.
        let Some(mut run) = self.scan.take() else {
            // Nothing to scan (cannot happen: scanning starts with a run).
            let _ = self.apply(Event::Done);
            return Ok(());
        };
        let (index, order, at) = match run.next() {
            Next::Visit { index, order, at } => (index, order, at),
            Next::Starved => {
                self.scan = Some(run);
                return self.starved(link, sentry, inbox).await;
            }
            Next::Finished(ev) => {
                let _ = self.apply(Event::Done);
                return self.publish::<ScanEventTopic, L>(&ev, link).await;
            }
        };
        let here = ScanPosition { index, order };
        let result = match at {
            Visit::Point(g) => {
                let visit = async |h: &mut Self| {
                    // A run of suspicious points ends the scan: the sample that
                    // completed it is not sent, and the scan resumes at it.
                    h.acquire(Some(g), Some(here))
                        .await
                        .and_then(|s| run.count_suspect(s.signal.flags).map(|()| ScanEvent::Sample(s)))
                };
                self.guarded(link, sentry, inbox, true, None, visit).await
            }
            Visit::Row(row) => {
                let turn = async |h: &mut Self| h.sweep_turn(&mut run, &row, here).await;
                match self.guarded(link, sentry, inbox, true, None, turn).await {
                    Ok(Ok(SweepTurn::Begun)) => {
                        self.scan = Some(run);
                        return Ok(());
                    }
                    Ok(Ok(SweepTurn::Sample(s))) => {
                        self.scan = Some(run);
                        return self.publish_swept(s, link, sentry).await.map(drop);
                    }
                    Ok(Ok(SweepTurn::Last(s, samples))) => {
                        // In the head while the sample goes out, for the stop a failed send or the E-STOP makes.
                        self.scan = Some(run);
                        let sent = self.publish_swept(s, link, sentry).await?;
                        match (sent, self.scan.take()) {
                            (true, Some(r)) => run = r,
                            (_, held) => {
                                self.scan = held;
                                return Ok(());
                            }
                        }
                        Ok(Ok(ScanEvent::Swept { index, order, samples }))
                    }
                    Ok(Err(f)) => Ok(Err(f)),
                    Err(trip) => Err(trip),
                }
            }
        };
        let result = match result {
            Ok(result) => result,
            Err(trip) => {
                // Held or dropped with its event, as any stop does.
                self.scan = Some(run);
                self.tripped(trip).await?;
                return Ok(());
            }
        };
        let ev = match run.record(index, order, result) {
            Recorded::GoesOn(ev) => {
                self.scan = Some(run);
                ev
            }
            Recorded::Ends(reason, ev) => {
                self.last_fault = Some(reason);
                let _ = self.apply(Event::Failed);
                ev
            }
        };
        self.publish::<ScanEventTopic, L>(&ev, link).await
    }

    /// Publishes a sample of a row the stages are still sweeping, raced
    /// against the E-STOP: no watch runs while it is sent, and a send that
    /// waits on a full queue (up to the link's timeout, 500 ms on the chip)
    /// must not hold the stop back. An opening stops the head as under
    /// watch does (the scan dropped, resumed by the host from its row), this
    /// sample with it. Whether the sample went out.
    async fn publish_swept<L: Link, S: Sentry>(&mut self, s: SweptSample, link: &mut L, sentry: &mut S) -> Result<bool, LinkError> {
        let ev = ScanEvent::SweptSample(s);
        let opened = {
            let mut send = pin!(self.publish::<ScanEventTopic, L>(&ev, link));
            loop {
                sentry.alive();
                match select(send.as_mut(), sentry.until(alive_by(sentry, None), true)).await {
                    Either::First(r) => break r.map(|()| false),
                    Either::Second(Wake::EStop) => break Ok(true),
                    Either::Second(Wake::Deadline) => {}
                }
            }
        }?;
        if opened {
            self.tripped(Trip::EStop).await?;
        }
        Ok(!opened)
    }

    /// A running scan whose visit queue has run dry: waits for the host's next
    /// chunk (or any request), the E-STOP, or the host's silence (which the
    /// next step sees and holds the scan for).
    async fn starved<L: Link, S: Sentry>(&mut self, link: &mut L, sentry: &mut S, inbox: &mut Inbox) -> Result<(), LinkError> {
        self.wait(link, sentry, inbox, self.silence_deadline(), true).await.map(drop)
    }

    async fn reply<E: Endpoint, L: Link>(&mut self, seq: VarSeq, msg: &E::Response, link: &mut L) -> Result<(), LinkError>
    where
        E::Response: Serialize,
    {
        self.send_keyed(E::RESP_KEY, seq, msg, link).await
    }

    async fn publish<T: Topic, L: Link>(&mut self, msg: &T::Message, link: &mut L) -> Result<(), LinkError>
    where
        T::Message: Serialize,
    {
        let seq = VarSeq::Seq4(self.talk.topic_seq);
        self.talk.topic_seq = self.talk.topic_seq.wrapping_add(1);
        self.send_keyed(T::TOPIC_KEY, seq, msg, link).await
    }

    async fn send_keyed<T: Serialize + ?Sized, L: Link>(&mut self, key: Key, seq: VarSeq, msg: &T, link: &mut L) -> Result<(), LinkError> {
        send_keyed(self.talk.key_kind, key, seq, msg, link).await
    }
}

/// Refuses a request there is no room to keep (see [`HELD`]); a frame
/// without a valid header gets nothing (the host's own checks find it).
async fn refuse_unheld<L: Link>(frame: &[u8], link: &mut L) -> Result<(), LinkError> {
    match request_id(frame) {
        Some((seq, kind)) => send_keyed(kind, ERROR_KEY, seq, &WireError::FailedToSpawn, link).await,
        None => Ok(()),
    }
}

/// Sends `msg` under `key` at the width `kind`, sealed.
async fn send_keyed<T: Serialize + ?Sized, L: Link>(
    kind: VarKeyKind,
    key: Key,
    seq: VarSeq,
    msg: &T,
    link: &mut L,
) -> Result<(), LinkError> {
    let mut tx = [0u8; MAX_FRAME];
    let body = MAX_FRAME - check::LEN;
    let n = match encode(key, kind, seq, msg, &mut tx[..body]) {
        Some(n) => n,
        // Every message fits MAX_FRAME (a test checks the largest);
        // should one not, the host still learns of it.
        None => encode(ERROR_KEY, kind, seq, &WireError::SerFailed, &mut tx[..body]).unwrap_or(0),
    };
    match check::seal(&mut tx, n) {
        Some(n) => link.send(&tx[..n]).await,
        None => Ok(()),
    }
}
