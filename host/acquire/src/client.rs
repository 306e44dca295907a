//! A connected head: typed requests with a timeout on every one, and the
//! identity check that names a protocol mismatch as such.

use crate::link::Workers;
use crate::target::{Opened, Target};
use anyhow::{anyhow, bail, Context, Result};
use gonio_firmware::config::{HeadConfig, REFERENCE};
use gonio_shared::icd::{
    Answer, ContinueEndpoint, HeadEndpoint, HomeEndpoint, IdentifyEndpoint, Latency, LearnEndpoint, MeasureEndpoint, MechanicsEndpoint,
    MoveEndpoint, ScanEndpoint, ScanEventTopic, StatusEndpoint,
};
use gonio_shared::{HeadState, Identity, ScanAccepted, ScanEvent, ScanSpec, Status, PROTOCOL_VERSION};
use postcard_rpc::host_client::{HostClient, HostErr, Subscription};
use postcard_rpc::standard_icd::WireError;
use postcard_rpc::Endpoint;
use postcard_schema::Schema;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::thread::JoinHandle;
use std::time::Duration;
use tokio::time::Instant;

/// Timeouts of the three [`Latency`] classes: prompt requests, the ones that
/// move the stages, homing: how long a request may go without its answer or
/// a sign that the head still works on it (see [`watched`]: a lost request
/// is found much sooner, a long operation the head reports is waited for).
const QUICK: Duration = Duration::from_secs(5);
const HOMING: Duration = Duration::from_secs(300);
const MOTION: Duration = Duration::from_secs(120);
/// How long a request may go unanswered before the host sends a probe.
const PROBE_AFTER: Duration = Duration::from_secs(1);
/// While a long request runs, a status request this often shows the head
/// that the host is still there (its host watch runs during moves and
/// homing too: `SafetySettings::host_timeout_s`, 4× this on a real head).
const HEARTBEAT: Duration = Duration::from_secs(5);

pub struct HeadClient {
    client: HostClient<WireError>,
    workers: Workers,
    identity: Identity,
    /// The reference configuration with the head's reported mechanics: what
    /// scans are planned and estimated with.
    config: HeadConfig,
    /// The thread serving the head in this process, if any.
    server: Option<JoinHandle<()>>,
}

impl HeadClient {
    /// Connects and identifies the head. Must run within a tokio runtime.
    pub async fn connect(target: &dyn Target) -> Result<HeadClient> {
        let Opened { client, workers, server } = target.open()?;
        let identity = match call::<IdentifyEndpoint>(&client, &(), QUICK).await {
            Ok(i) => i,
            Err(CallError::UnknownKey(_)) => {
                bail!("protocol mismatch: the head does not know this host's identify request (host speaks protocol v{PROTOCOL_VERSION}); update the firmware or the host")
            }
            Err(e) => return Err(anyhow::Error::new(e).context("the head did not identify itself")),
        };
        if identity.protocol_version != PROTOCOL_VERSION {
            bail!(
                "protocol version mismatch: head {} speaks v{}, this host v{}; update the firmware or the host",
                identity.serial,
                identity.protocol_version,
                PROTOCOL_VERSION
            );
        }
        let mechanics = call::<MechanicsEndpoint>(&client, &(), QUICK)
            .await
            .context("the head did not report its mechanics")?;
        if !mechanics.is_plausible() {
            bail!(
                "head {} reports mechanics no scan can be planned with: {mechanics:?}",
                identity.serial
            );
        }
        Ok(HeadClient {
            client,
            workers,
            identity,
            config: REFERENCE.with_mechanics(&mechanics),
            server,
        })
    }

    pub fn identity(&self) -> &Identity {
        &self.identity
    }

    /// The head's configuration as far as planning goes: its reported
    /// gearing, travel, speeds and blind zone.
    pub fn config(&self) -> &HeadConfig {
        &self.config
    }

    /// Sends any request of the head's endpoint table and waits for its
    /// answer as long as the endpoint's [`Latency`] allows (a lost request is
    /// found much sooner: see [`watched`]). A refusal is an error naming the
    /// endpoint and the head's reason.
    pub async fn request<E>(&self, req: &E::Request) -> Result<<E::Response as Answer>::Accepted>
    where
        E: HeadEndpoint,
        E::Request: Serialize + Schema,
        E::Response: DeserializeOwned + Schema + Answer,
    {
        let answer = watched::<E>(&self.client, req, timeout(E::LATENCY)).await?;
        answer.accepted().map_err(|f| anyhow!("{}: head refused: {f}", E::PATH))
    }

    /// Subscribes to scan events; opened before a request that starts them.
    async fn scan_events(&self) -> Result<Subscription<ScanEvent>> {
        self.client
            .subscribe_exclusive::<ScanEventTopic>(1024)
            .await
            .map_err(|e| anyhow!("cannot subscribe to scan events: {e:?}"))
    }

    /// Continues a held scan; its further events arrive on the subscription.
    pub async fn continue_events(&self) -> Result<(Status, Subscription<ScanEvent>)> {
        let sub = self.scan_events().await?;
        Ok((self.request::<ContinueEndpoint>(&()).await?, sub))
    }

    /// Starts a scan; its events arrive on the returned subscription, which is
    /// opened before the request so none is missed.
    pub async fn start_scan(&self, spec: &ScanSpec) -> Result<(ScanAccepted, Subscription<ScanEvent>)> {
        let sub = self.scan_events().await?;
        let accepted = self.request::<ScanEndpoint>(spec).await?;
        Ok((accepted, sub))
    }

    /// Closes the link: the port is released (another client may open it at
    /// once) and a head served in this process has reached its safe state and
    /// stopped.
    pub async fn close(mut self) {
        self.client.close();
        drop(self.client);
        self.workers.join().await;
        if let Some(t) = self.server.take() {
            let _ = tokio::task::spawn_blocking(move || t.join()).await;
        }
    }
}

/// Whether an error means the link to the head is gone (closed, or a
/// request unanswered), rather than the head refusing something.
pub fn is_link_loss(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<CallError>(),
            Some(CallError::Timeout(..) | CallError::Closed(_) | CallError::Lost(_))
        )
    })
}

/// How long the host waits for an answer of the given latency.
fn timeout(latency: Latency) -> Duration {
    match latency {
        Latency::Prompt => QUICK,
        Latency::Motion => MOTION,
        Latency::Homing => HOMING,
    }
}

/// Why a request got no valid answer.
#[derive(Debug, thiserror::Error)]
pub enum CallError {
    #[error("no answer from the head to {0}, nor any sign that it still works on it, for {1:.0} s")]
    Timeout(&'static str, f64),
    #[error("{0}: the head does not know this request (protocol mismatch)")]
    UnknownKey(&'static str),
    #[error("{0}: the head reported a wire error: {1}")]
    Wire(&'static str, WireError),
    #[error("{0}: the link to the head closed")]
    Closed(&'static str),
    #[error("{0}: the request or its answer was lost (the head answered a later request first)")]
    Lost(&'static str),
    #[error("{0}: undecodable answer: {1}")]
    BadAnswer(&'static str, String),
}

async fn call<E: Endpoint>(client: &HostClient<WireError>, req: &E::Request, timeout: Duration) -> Result<E::Response, CallError>
where
    E::Request: Serialize + Schema,
    E::Response: DeserializeOwned + Schema,
{
    match tokio::time::timeout(timeout, client.send_resp::<E>(req)).await {
        Err(_) => Err(CallError::Timeout(E::PATH, timeout.as_secs_f64())),
        Ok(r) => answered::<E>(r),
    }
}

/// What an answer to `E`, or its failure, means.
fn answered<E: Endpoint>(r: Result<E::Response, HostErr<WireError>>) -> Result<E::Response, CallError> {
    match r {
        Ok(r) => Ok(r),
        Err(HostErr::Wire(WireError::UnknownKey)) => Err(CallError::UnknownKey(E::PATH)),
        Err(HostErr::Wire(e)) => Err(CallError::Wire(E::PATH, e)),
        Err(HostErr::Closed) => Err(CallError::Closed(E::PATH)),
        Err(e) => Err(CallError::BadAnswer(E::PATH, e.to_string())),
    }
}

/// A request watched for loss. Once it has gone unanswered for
/// [`PROBE_AFTER`], a status request follows it, and another every
/// [`probe_period`] until the answer comes. The head reads frames in the
/// order they arrive and answers a status poll at once, also while an
/// operation or a scan point runs, with that operation's state and the
/// number of requests it keeps for when it ends; so a probe answered with no
/// request kept and no operation of this request's kind running means the
/// request, or its answer, was lost on the link: that is reported at once as
/// [`CallError::Lost`]. A probe that finds the request kept or running shows
/// the head alive and working on it: the request's timeout counts from that
/// answer, not from the request. So the timeout bounds the head's silence,
/// never the operation's length, which the head bounds itself (homing
/// within the axis' travel, a move within twice its schedule: E402): a head
/// whose homing outlasts the timeout, slow stages or a slow emulated board,
/// is waited for while it answers. The probes double as the heartbeat the
/// head's host watch needs during long operations.
async fn watched<E: Endpoint>(client: &HostClient<WireError>, req: &E::Request, timeout: Duration) -> Result<E::Response, CallError>
where
    E::Request: Serialize + Schema,
    E::Response: DeserializeOwned + Schema,
{
    let answer = client.send_resp::<E>(req);
    tokio::pin!(answer);
    let period = probe_period(timeout);
    let mut heard = Instant::now();
    let mut next_probe = heard + PROBE_AFTER.min(period);
    loop {
        // A probe unanswered for a period may itself be lost: the next one
        // goes at once, so that neither the restarts nor the heartbeat stop.
        let probe = async {
            tokio::time::sleep_until(next_probe).await;
            tokio::time::timeout(period, client.send_resp::<StatusEndpoint>(&())).await
        };
        // Biased: when both answers have come in, the request's is taken (it
        // was delivered first).
        tokio::select! {
            biased;
            r = &mut answer => return answered::<E>(r),
            p = probe => {
                next_probe = Instant::now() + period;
                match p {
                    Ok(Ok(status)) if !may_hold(&status, E::PATH) => return Err(CallError::Lost(E::PATH)),
                    Ok(Ok(_)) => heard = Instant::now(),
                    Ok(Err(_)) => {}
                    Err(_) => next_probe = Instant::now(),
                }
            }
            () = tokio::time::sleep_until(heard + timeout) => return Err(CallError::Timeout(E::PATH, timeout.as_secs_f64())),
        }
    }
}

/// How often a pending request is probed: at least four probes within its
/// timeout, so that one late answer does not end a request the head holds,
/// and at most every [`HEARTBEAT`].
fn probe_period(timeout: Duration) -> Duration {
    (timeout / 4).min(HEARTBEAT)
}

/// Whether the head, as `status` shows it, may still answer the request
/// `path`: it keeps requests for when its operation ends, or it is running
/// this request's own operation (answered when it ends). A scan's own
/// request is answered as the scan starts, and a visit chunk is kept or
/// answered between points, so a scan found running with nothing kept
/// means the request was lost. A status request is never kept: answered
/// before the probe that follows it, or lost.
fn may_hold(status: &Status, path: &str) -> bool {
    if path == StatusEndpoint::PATH {
        return false;
    }
    let running = match status.state {
        HeadState::Homing => path == HomeEndpoint::PATH,
        HeadState::Moving => path == MoveEndpoint::PATH,
        HeadState::Measuring => path == MeasureEndpoint::PATH || path == LearnEndpoint::PATH,
        HeadState::Stopping => true,
        _ => false,
    };
    running || status.requests_held > 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::channel_client;
    use gonio_firmware::dispatch::{self, Midway};
    use gonio_shared::icd::{HomeReply, HomeRequest};
    use gonio_shared::wire::{check, framing};
    use gonio_shared::{AxisAngles, DetectionSettings};
    use postcard_rpc::header::{VarKeyKind, VarSeq};
    use postcard_rpc::Key;
    use std::sync::mpsc;
    use tokio::sync::mpsc as tmpsc;

    /// What the head in these tests does with a homing request: it answers
    /// every status poll with `state` until `silent_after`, but for the
    /// first `polls_lost` (lost on the link), and answers the homing at
    /// `answer_after` (never if `None`).
    struct Script {
        state: HeadState,
        silent_after: Duration,
        polls_lost: usize,
        answer_after: Option<Duration>,
    }

    fn status(state: HeadState) -> Status {
        Status {
            state,
            homed: false,
            laser_on: false,
            drivers_enabled: true,
            estop_open: false,
            axes: AxisAngles::default(),
            detection: DetectionSettings::default(),
            samples_sent: 0,
            samples_flagged: 0,
            samples_remeasured: 0,
            sanity_loaded: false,
            last_fault: None,
            laser_inhibited: None,
            uptime_us: 0,
            requests_held: 0,
        }
    }

    fn frame<T: Serialize>(key: Key, id: (VarSeq, VarKeyKind), msg: &T) -> Vec<u8> {
        let mut buf = vec![0u8; framing::MAX_FRAME];
        let n = dispatch::encode(key, id.1, id.0, msg, &mut buf).expect("a reply fits a frame");
        buf.truncate(n + check::LEN);
        check::seal(&mut buf, n).expect("room for the check");
        buf
    }

    /// The head's side of the link, on the test's paused clock.
    async fn head(from_host: mpsc::Receiver<Vec<u8>>, to_host: tmpsc::UnboundedSender<Vec<u8>>, script: Script) {
        let t0 = Instant::now();
        let mut homing = None;
        let mut polls_lost = 0;
        loop {
            while let Ok(sealed) = from_host.try_recv() {
                match dispatch::midway(&sealed) {
                    Midway::Status(..) if polls_lost < script.polls_lost => polls_lost += 1,
                    Midway::Status(seq, kind) if t0.elapsed() < script.silent_after => {
                        let _ = to_host.send(frame(StatusEndpoint::RESP_KEY, (seq, kind), &status(script.state)));
                    }
                    Midway::Status(..) => {}
                    _ => homing = dispatch::request_id(&sealed),
                }
            }
            if let (Some(id), Some(after)) = (homing, script.answer_after) {
                if t0.elapsed() >= after {
                    let reply: HomeReply = Ok(AxisAngles::default());
                    let _ = to_host.send(frame(HomeEndpoint::RESP_KEY, id, &reply));
                    homing = None;
                }
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    }

    /// Sends a homing request with `timeout` to a head following `script`.
    async fn home(script: Script, timeout: Duration) -> Result<HomeReply, CallError> {
        let (to_head, from_host) = mpsc::channel();
        let (to_host, from_head) = tmpsc::unbounded_channel();
        let (client, _workers) = channel_client(to_head, from_head);
        tokio::spawn(head(from_host, to_host, script));
        watched::<HomeEndpoint>(&client, &HomeRequest::ALL, timeout).await
    }

    const TIMEOUT: Duration = Duration::from_secs(300);

    #[tokio::test(start_paused = true)]
    async fn an_operation_the_head_reports_is_waited_for_past_the_timeout() {
        let script = Script {
            state: HeadState::Homing,
            silent_after: Duration::MAX,
            polls_lost: 0,
            answer_after: Some(TIMEOUT * 3),
        };
        let t0 = Instant::now();
        assert!(matches!(home(script, TIMEOUT).await, Ok(Ok(_))));
        assert!(t0.elapsed() >= TIMEOUT * 3);
    }

    #[tokio::test(start_paused = true)]
    async fn a_head_gone_silent_times_out_a_timeout_after_its_last_answer() {
        let silent_after = TIMEOUT * 2;
        let script = Script {
            state: HeadState::Homing,
            silent_after,
            polls_lost: 0,
            answer_after: None,
        };
        let t0 = Instant::now();
        assert!(matches!(home(script, TIMEOUT).await, Err(CallError::Timeout(..))));
        let waited = t0.elapsed();
        // The last answered probe went at most a period (and the head's
        // 10 ms turn) before the head fell silent.
        let earliest = silent_after + TIMEOUT - probe_period(TIMEOUT) - Duration::from_millis(10);
        assert!(waited >= earliest && waited <= silent_after + TIMEOUT, "{waited:?}");
    }

    #[tokio::test(start_paused = true)]
    async fn a_request_the_head_does_not_hold_is_lost_at_the_first_probe() {
        let script = Script {
            state: HeadState::Idle,
            silent_after: Duration::MAX,
            polls_lost: 0,
            answer_after: None,
        };
        let t0 = Instant::now();
        assert!(matches!(home(script, TIMEOUT).await, Err(CallError::Lost(_))));
        assert!(t0.elapsed() < PROBE_AFTER * 2);
    }

    #[tokio::test(start_paused = true)]
    async fn a_short_timeout_is_probed_often_enough_to_be_restarted() {
        let script = Script {
            state: HeadState::Homing,
            silent_after: Duration::MAX,
            polls_lost: 0,
            answer_after: Some(QUICK * 4),
        };
        assert!(matches!(home(script, QUICK).await, Ok(Ok(_))));
    }

    #[tokio::test(start_paused = true)]
    async fn a_lost_probe_does_not_end_the_probing() {
        let script = Script {
            state: HeadState::Homing,
            silent_after: Duration::MAX,
            polls_lost: 2,
            answer_after: Some(TIMEOUT * 3),
        };
        assert!(matches!(home(script, TIMEOUT).await, Ok(Ok(_))));
    }
}
