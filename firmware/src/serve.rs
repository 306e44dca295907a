//! The head's side of the protocol: the serve loop, request dispatch, replies
//! and the scan's event stream.

use crate::check;
use crate::dispatch::{decode, encode, Command, DecodeError};
use crate::framing::MAX_FRAME;
use crate::head::Head;
use crate::hw::Board;
use crate::link::{Link, LinkError};
use gonio_shared::icd::{
    AbortEndpoint, CalibrateEndpoint, DetectionEndpoint, HomeEndpoint, IdentifyEndpoint, MeasureEndpoint, MoveEndpoint, SafetyEndpoint,
    SanityEndpoint, ScanEndpoint, ScanEventTopic, StatusEndpoint,
};
use gonio_shared::sample::ScanPosition;
use gonio_shared::{Fault, ScanEvent};
use postcard_rpc::header::VarSeq;
use postcard_rpc::standard_icd::{WireError, ERROR_KEY};
use postcard_rpc::{Endpoint, Key, Topic};
use serde::Serialize;

impl<B: Board> Head<B> {
    /// Serves the host until the link fails; the head is then in its safe
    /// state and an interrupted scan can be resumed from its last position.
    pub async fn serve<L: Link>(&mut self, link: &mut L) -> LinkError {
        let mut rx = [0u8; MAX_FRAME];
        loop {
            let got = if self.scan.is_some() {
                link.try_recv(&mut rx)
            } else {
                Some(link.recv(&mut rx).await)
            };
            let handled = match got {
                Some(Ok(n)) => {
                    // Any frame, even a damaged one, shows the host is there.
                    self.heard_host();
                    self.handle(&rx[..n], link).await
                }
                Some(Err(e)) => Err(e),
                None => Ok(()),
            };
            let r = match (handled, self.pending_event.take()) {
                (Ok(()), Some(ev)) => self.publish::<ScanEventTopic, L>(&ev, link).await,
                (r, _) => r,
            };
            let r = match r {
                Ok(()) if got.is_none() => self.scan_step(link).await,
                r => r,
            };
            if let Err(e) = r {
                self.scan = None;
                self.safe_state();
                crate::info!("link lost; head in safe state");
                return e;
            }
        }
    }

    /// Checks, decodes and answers one frame. A frame that fails its check
    /// is dropped unanswered: its header may be damaged too, and the host
    /// recovers a lost request by its timeout.
    async fn handle<L: Link>(&mut self, sealed: &[u8], link: &mut L) -> Result<(), LinkError> {
        let Some(frame) = check::open(sealed) else {
            return Ok(());
        };
        let (hdr, cmd) = match decode(frame) {
            Ok(x) => x,
            Err(DecodeError::NoHeader) => return Ok(()),
            Err(DecodeError::Wire(hdr, e)) => return self.send_keyed(ERROR_KEY, hdr.seq_no, &e, link).await,
        };
        self.key_kind = hdr.key.kind();
        let seq = hdr.seq_no;
        match cmd {
            Command::Identify => self.reply::<IdentifyEndpoint, L>(seq, &self.identity(), link).await,
            Command::Status => self.reply::<StatusEndpoint, L>(seq, &self.status(), link).await,
            Command::Home(r) => {
                let resp = self.home(r).await;
                self.reply::<HomeEndpoint, L>(seq, &resp, link).await
            }
            Command::Move(g) => {
                let resp = self.move_to(g).await;
                self.reply::<MoveEndpoint, L>(seq, &resp, link).await
            }
            Command::Measure(r) => {
                let resp = self.measure(r).await;
                self.reply::<MeasureEndpoint, L>(seq, &resp, link).await
            }
            Command::Scan(spec) => {
                let resp = self.start_scan(spec);
                self.reply::<ScanEndpoint, L>(seq, &resp, link).await
            }
            Command::Abort => {
                let resp = self.abort();
                self.reply::<AbortEndpoint, L>(seq, &resp, link).await
            }
            Command::Detection(s) => {
                let resp = self.configure_detection(s);
                self.reply::<DetectionEndpoint, L>(seq, &resp, link).await
            }
            Command::Calibrate(c) => {
                let resp = self.calibrate(c).await;
                self.reply::<CalibrateEndpoint, L>(seq, &resp, link).await
            }
            Command::Sanity(c) => {
                let resp = self.load_sanity(c);
                self.reply::<SanityEndpoint, L>(seq, &resp, link).await
            }
            Command::Safety(c) => {
                let resp = self.configure_safety(c);
                self.reply::<SafetyEndpoint, L>(seq, &resp, link).await
            }
        }
    }

    /// Visits the next point of the running scan and publishes what happened;
    /// stops the scan instead when the host has gone silent.
    async fn scan_step<L: Link>(&mut self, link: &mut L) -> Result<(), LinkError> {
        if let Some((run, next_order)) = self.host_silent() {
            self.scan = None;
            self.last_fault = Some(Fault::HostSilent);
            self.safe_state();
            crate::info!("host silent during a scan; head in safe state");
            let ev = ScanEvent::Stopped {
                run,
                next_order,
                reason: Fault::HostSilent,
            };
            return self.publish::<ScanEventTopic, L>(&ev, link).await;
        }
        let Some(run) = self.scan.as_mut() else {
            return Ok(());
        };
        let (order, run_no) = (run.next_order, run.run);
        let point = run
            .planner
            .next(&self.cfg, &run.spec)
            .and_then(|i| run.spec.point(i).map(|g| (i, g)));
        let ev = match point {
            None => {
                let ev = ScanEvent::Finished {
                    run: run_no,
                    measured: run.measured,
                    skipped: run.skipped,
                };
                self.scan = None;
                self.safe_state();
                ev
            }
            Some((index, g)) => match self.acquire(Some(g), Some(ScanPosition { index, order })).await.and_then(|s| {
                // A run of suspicious points ends the scan: the sample that
                // completed it is not sent, and the scan resumes at it.
                self.watch(&s).map(|()| s)
            }) {
                Ok(s) => {
                    self.advance(|r| r.measured += 1);
                    ScanEvent::Sample(s)
                }
                Err(reason @ (Fault::Unreachable(_) | Fault::InvalidValue(_))) => {
                    self.advance(|r| r.skipped += 1);
                    ScanEvent::Skipped { index, order, reason }
                }
                Err(reason) => {
                    self.scan = None;
                    self.last_fault = Some(reason);
                    self.safe_state();
                    ScanEvent::Stopped {
                        run: run_no,
                        next_order: order,
                        reason,
                    }
                }
            },
        };
        self.publish::<ScanEventTopic, L>(&ev, link).await
    }

    fn advance(&mut self, count: impl FnOnce(&mut crate::head::ScanRun)) {
        if let Some(run) = self.scan.as_mut() {
            count(run);
            run.next_order += 1;
        }
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
        let seq = VarSeq::Seq4(self.topic_seq);
        self.topic_seq = self.topic_seq.wrapping_add(1);
        self.send_keyed(T::TOPIC_KEY, seq, msg, link).await
    }

    async fn send_keyed<T: Serialize + ?Sized, L: Link>(&mut self, key: Key, seq: VarSeq, msg: &T, link: &mut L) -> Result<(), LinkError> {
        let mut tx = [0u8; MAX_FRAME];
        let body = MAX_FRAME - check::LEN;
        let n = match encode(key, self.key_kind, seq, msg, &mut tx[..body]) {
            Some(n) => n,
            // Every message fits MAX_FRAME (a test checks the largest);
            // should one not, the host still learns of it.
            None => encode(ERROR_KEY, self.key_kind, seq, &WireError::SerFailed, &mut tx[..body]).unwrap_or(0),
        };
        match check::seal(&mut tx, n) {
            Some(n) => link.send(&tx[..n]).await,
            None => Ok(()),
        }
    }
}
