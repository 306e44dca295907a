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

/// Timeouts of the three [`Latency`] classes: prompt requests, the ones that
/// move the stages, homing. A lost request is found much sooner than these
/// (see [`watched`]).
const QUICK: Duration = Duration::from_secs(5);
const HOMING: Duration = Duration::from_secs(300);
const MOTION: Duration = Duration::from_secs(120);
/// How long a request may go unanswered before the host sends a probe.
const PROBE_AFTER: Duration = Duration::from_secs(1);
/// While a long request runs, a status request this often shows the head
/// that the host is still there (its host watch runs during moves and
/// homing too: `SafetySettings::host_timeout_s`, 4× this on a real head).
pub const HEARTBEAT: Duration = Duration::from_secs(5);

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
    #[error("no answer from the head to {0} within {1:.0} s")]
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
        Ok(Ok(r)) => Ok(r),
        Ok(Err(HostErr::Wire(WireError::UnknownKey))) => Err(CallError::UnknownKey(E::PATH)),
        Ok(Err(HostErr::Wire(e))) => Err(CallError::Wire(E::PATH, e)),
        Ok(Err(HostErr::Closed)) => Err(CallError::Closed(E::PATH)),
        Ok(Err(e)) => Err(CallError::BadAnswer(E::PATH, e.to_string())),
    }
}

/// A request watched for loss. Once it has gone unanswered for
/// [`PROBE_AFTER`], one status request follows it. The head reads frames in
/// the order they arrive and answers a status poll at once, also while an
/// operation or a scan point runs, with that operation's state and the
/// number of requests it keeps for when it ends; so a probe answered with
/// no request kept and no operation of this request's kind running means
/// the request, or its answer, was lost on the link: that is reported at
/// once as [`CallError::Lost`] instead of after the request's full timeout
/// (minutes for homing). A probe that finds the request possibly kept or
/// running, or is not answered, changes nothing: the request's own timeout
/// stands.
async fn watched<E: Endpoint>(client: &HostClient<WireError>, req: &E::Request, timeout: Duration) -> Result<E::Response, CallError>
where
    E::Request: Serialize + Schema,
    E::Response: DeserializeOwned + Schema,
{
    let answer = call::<E>(client, req, timeout);
    tokio::pin!(answer);
    tokio::select! {
        biased;
        r = &mut answer => return r,
        () = tokio::time::sleep(PROBE_AFTER) => {}
    }
    let probe = call::<StatusEndpoint>(client, &(), timeout);
    tokio::pin!(probe);
    // Biased: when both answers have come in, the request's is taken (it
    // was delivered first).
    let answer = tokio::select! {
        biased;
        r = &mut answer => return r,
        p = &mut probe => match p {
            Ok(status) if !may_hold(&status, E::PATH) => return Err(CallError::Lost(E::PATH)),
            _ => answer,
        },
        () = heartbeats(client) => unreachable!("heartbeats never end"),
    };
    tokio::select! {
        r = answer => r,
        () = heartbeats(client) => unreachable!("heartbeats never end"),
    }
}

/// Whether the head, as `status` shows it, may still answer the request
/// `path`: it keeps requests for when its operation ends, or it is running
/// this request's own operation (answered when it ends). A scan's own
/// request is answered as the scan starts, and a visit chunk is kept or
/// answered between points, so a scan found running with nothing kept
/// means the request was lost.
fn may_hold(status: &Status, path: &str) -> bool {
    let running = match status.state {
        HeadState::Homing => path == HomeEndpoint::PATH,
        HeadState::Moving => path == MoveEndpoint::PATH,
        HeadState::Measuring => path == MeasureEndpoint::PATH || path == LearnEndpoint::PATH,
        HeadState::Stopping => true,
        _ => false,
    };
    running || status.requests_held > 0
}

/// Sends a status request every [`HEARTBEAT`], answers unread, for as long
/// as it is polled.
async fn heartbeats(client: &HostClient<WireError>) {
    loop {
        tokio::time::sleep(HEARTBEAT).await;
        let c = client.clone();
        tokio::spawn(async move {
            let _ = tokio::time::timeout(MOTION, c.send_resp::<StatusEndpoint>(&())).await;
        });
    }
}
