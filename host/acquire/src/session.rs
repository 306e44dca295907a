//! A session with a head for a scan: connect, prepare it (detection
//! settings, homing, the detector's reference learned, the host watch), and find it
//! again after the link was lost: the same head (by serial number) on the
//! same port or, for a real head plugged back in, on whichever port it came
//! back on; then prepare it again, since it may have been power-cycled.

use crate::client::{is_link_loss, HeadClient};
use crate::operator::Operator;
use crate::target::Target;
use anyhow::{bail, Context, Result};
use gonio_shared::icd::{
    AbortEndpoint, DetectionEndpoint, HomeEndpoint, HomeRequest, LearnEndpoint, MoveEndpoint, SafetyEndpoint, StatusEndpoint,
};
use gonio_shared::{DetectionReport, DetectionSettings, Geometry, LearnReport, LearnRequest, Reference, SafetySettings};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the host looks for a head that went away.
const RECONNECT_WINDOW: Duration = Duration::from_secs(60);
const RECONNECT_PAUSE: Duration = Duration::from_millis(500);

/// Host silence a real head tolerates during a scan; the host polls its
/// status at a quarter of it. Simulated heads keep their own time and are
/// not watched (their clock runs a thousand times faster than the host's).
pub const HOST_TIMEOUT_S: f32 = 20.0;

/// What preparing the head means.
#[derive(Debug, Clone)]
pub struct Setup {
    pub settings: DetectionSettings,
    /// Where to learn the detection chain (matched reference), if anywhere.
    pub learn_at: Option<Geometry>,
    pub learning_periods: u16,
}

pub struct Session {
    pub target: Arc<dyn Target>,
    setup: Setup,
    head: Option<HeadClient>,
    serial: String,
    /// Where notices of the preparation and of recoveries go.
    pub operator: Operator,
    pub detection: Option<DetectionReport>,
    pub learned: Option<LearnReport>,
    /// Times the link was found again.
    pub reconnections: u32,
}

impl Session {
    /// Connects (nothing else: a head that cannot be reached leaves no trace).
    pub async fn connect(target: Arc<dyn Target>, setup: Setup, operator: Operator) -> Result<Session> {
        let head = HeadClient::connect(target.as_ref()).await?;
        Ok(Session {
            serial: head.identity().serial.to_string(),
            target,
            setup,
            head: Some(head),
            operator,
            detection: None,
            learned: None,
            reconnections: 0,
        })
    }

    pub fn head(&self) -> &HeadClient {
        // Present from connect on, except inside `reconnect`.
        self.head.as_ref().expect("a connected head")
    }

    /// Stops whatever the head was doing, then detection settings, homing,
    /// the detector's reference learned, the host watch.
    async fn prepare(&mut self) -> Result<()> {
        let head = self.head();
        // A head found again may still be running the scan whose answer was
        // lost (its events then went nowhere): stop it first, or every
        // setting below would be refused as busy.
        head.request::<AbortEndpoint>(&()).await?;
        // The chop timing is set first: a learned reference holds for that timing.
        head.request::<DetectionEndpoint>(&DetectionSettings {
            reference: Reference::Square,
            ..self.setup.settings
        })
        .await?;
        head.request::<HomeEndpoint>(&HomeRequest::ALL).await?;
        let learned = match self.setup.learn_at {
            Some(g) => {
                head.request::<MoveEndpoint>(&g)
                    .await
                    .context("moving to where the reference is learned")?;
                let c = head
                    .request::<LearnEndpoint>(&LearnRequest {
                        periods: self.setup.learning_periods,
                    })
                    .await?;
                self.operator.notice(format_args!(
                    "reference learned: phase {:.1}°, {:.3} V at gain {}, SNR {:.0}",
                    c.phase_deg, c.amplitude_v, c.gain_index, c.snr
                ));
                Some(c)
            }
            None => None,
        };
        let detection = head.request::<DetectionEndpoint>(&self.setup.settings).await?;
        // What the head reports of itself, whatever link it is on (a
        // simulated head on a pseudo-terminal too): a watch kept on a
        // simulated clock would trip between the host's wall-clock messages.
        let watch = if head.identity().simulated { 0.0 } else { HOST_TIMEOUT_S };
        head.request::<SafetyEndpoint>(&SafetySettings {
            host_timeout_s: watch,
            ..SafetySettings::default()
        })
        .await?;
        self.detection = Some(detection);
        if learned.is_some() {
            self.learned = learned;
        }
        Ok(())
    }

    /// How often the host must show it is there during a scan.
    pub fn heartbeat(&self) -> Duration {
        Duration::from_secs_f32(HOST_TIMEOUT_S / 4.0)
    }

    /// Prepares the head for a scan; a request lost on the way (no answer,
    /// the link closed) costs a reconnection, not the scan.
    pub async fn start(&mut self) -> Result<()> {
        match self.prepare().await {
            Err(e) if is_link_loss(&e) => {
                self.operator.notice(format_args!("preparing the head: {e:#}"));
                self.reconnect().await
            }
            r => r,
        }
    }

    /// Finds the head again after the link was lost and prepares it; a link
    /// lost again while preparing is one more try within the window.
    pub async fn reconnect(&mut self) -> Result<()> {
        self.let_go().await;
        self.operator
            .notice(format_args!("link to the head lost; looking for head {} again", self.serial));
        let t0 = Instant::now();
        let mut last_err = None;
        while t0.elapsed() < RECONNECT_WINDOW {
            for target in self.candidates() {
                match HeadClient::connect(target.as_ref()).await {
                    Ok(h) if h.identity().serial.as_str() == self.serial => {
                        self.head = Some(h);
                        self.reconnections += 1;
                        if self.holds_a_scan().await {
                            return Ok(());
                        }
                        match self.prepare().await {
                            Ok(()) => return Ok(()),
                            Err(e) if is_link_loss(&e) => {
                                last_err = Some(e);
                                self.let_go().await;
                            }
                            Err(e) => return Err(e.context("preparing the head again after reconnecting")),
                        }
                    }
                    Ok(h) => {
                        last_err = Some(anyhow::anyhow!("found head {} instead of {}", h.identity().serial, self.serial));
                        h.close().await;
                    }
                    Err(e) => last_err = Some(e),
                }
            }
            tokio::time::sleep(RECONNECT_PAUSE).await;
        }
        match last_err {
            Some(e) => Err(e.context(format!(
                "head {} not found again within {} s",
                self.serial,
                RECONNECT_WINDOW.as_secs()
            ))),
            None => bail!("head {} not found again", self.serial),
        }
    }

    /// Whether the head found again holds this session's scan: it stopped
    /// when the link went (laser off, motion braked, position kept) and kept
    /// its settings, so it needs no preparing, and the scan continues where
    /// it stopped without replanning.
    async fn holds_a_scan(&self) -> bool {
        self.detection.is_some()
            && self
                .head()
                .request::<StatusEndpoint>(&())
                .await
                .is_ok_and(|st| st.homed && matches!(st.state, gonio_shared::HeadState::Paused { .. }))
    }

    /// Where to look for the head: its target, and wherever else the target
    /// says the same head may be now.
    fn candidates(&self) -> Vec<Arc<dyn Target>> {
        let mut c = vec![self.target.clone()];
        c.extend(self.target.elsewhere(&self.serial));
        c
    }

    pub async fn close(mut self) {
        self.let_go().await;
    }

    /// Closes the link to the head, if there is one.
    async fn let_go(&mut self) {
        if let Some(h) = self.head.take() {
            h.close().await;
        }
    }
}
