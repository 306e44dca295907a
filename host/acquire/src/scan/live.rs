//! A running scan as others see and steer it: the live page and `gonio
//! pause DIR` / `gonio continue DIR` in another terminal. The scan loop
//! publishes what it stores and where it stands; the operator's requests
//! (pause, continue, abort) come back through [`Live::pause`],
//! [`Live::resume`] and [`Live::abort`]: the loop obeys a pause between two
//! positions, the head held (laser off between points, the stages at rest)
//! and kept awake; an abort ends the scan as Ctrl-C does.
//! Everything here is in memory and bounded: the samples of the scan so
//! far (a late page draws them all), and a broadcast of the updates.

use serde::Serialize;
use std::sync::{Arc, Mutex};
use tokio::sync::{broadcast, watch};

/// Updates a page has not read yet, at most: a slower page misses some
/// and redraws from [`Live::snapshot`].
const UPDATES: usize = 4096;

/// One thing that happened in the scan.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Update {
    /// A position measured: where, and what the detector read there.
    Sample {
        theta_i_deg: f32,
        theta_o_deg: f32,
        dphi_deg: f32,
        /// The lock-in's amplitude (V) and the transimpedance gain (V/A).
        signal_v: f32,
        gain_v_per_a: f32,
    },
    /// Where the scan stands.
    Progress {
        done: u32,
        of: u32,
        measured: u32,
        unreachable: u32,
        /// Head time left (s), as the progress bar shows it.
        left_s: f64,
    },
    /// What the scan is doing, in the operator's words (`scanning`,
    /// `paused`, `recovering: …`, `finished`, `interrupted: …`).
    State { state: String },
}

/// What the operator asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Request {
    #[default]
    Run,
    Pause,
    Abort,
}

/// The scan's side and the pages' side of one live scan.
#[derive(Clone)]
pub struct Live {
    requests: watch::Sender<Request>,
    updates: broadcast::Sender<Update>,
    seen: Arc<Mutex<Seen>>,
    /// Where its page is served, once it is.
    served: Option<Served>,
}

/// Where a live scan's page is served and the token that admits its user.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Served {
    /// The page, with its token: what the user opens.
    pub url: String,
    /// `http://127.0.0.1:PORT`, the page's origin, where the requests go.
    pub origin: String,
    pub token: String,
}

/// What a page joining late needs: every sample, the last progress and state.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Seen {
    pub samples: Vec<Update>,
    pub progress: Option<Update>,
    pub state: Option<Update>,
}

impl Default for Live {
    fn default() -> Self {
        Live {
            requests: watch::channel(Request::Run).0,
            updates: broadcast::channel(UPDATES).0,
            seen: Arc::default(),
            served: None,
        }
    }
}

impl Live {
    /// The same live scan, its page served as `served` says.
    pub fn served_at(mut self, served: Served) -> Live {
        self.served = Some(served);
        self
    }

    /// Writes where the page is, and its token, into the scan directory
    /// (`ScanDir::live`), readable by the user alone, until the returned
    /// guard is dropped, the scan over.
    pub fn announce(&self, dir: &std::path::Path) -> anyhow::Result<Announced> {
        use anyhow::Context;
        use std::io::Write;
        let path = gonio_scan_dir::ScanDir::new(dir).live();
        if let Some(served) = &self.served {
            let mut text = serde_json::to_value(served)?;
            text["pid"] = std::process::id().into();
            let mut options = std::fs::OpenOptions::new();
            options.write(true).create(true).truncate(true);
            #[cfg(unix)]
            std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
            options
                .open(&path)
                .and_then(|mut f| f.write_all(text.to_string().as_bytes()))
                .with_context(|| format!("writing {}", path.display()))?;
        }
        Ok(Announced(self.served.as_ref().map(|_| path)))
    }

    /// Publishes an update to every page.
    pub fn publish(&self, u: Update) {
        if let Ok(mut seen) = self.seen.lock() {
            match &u {
                Update::Sample { .. } => seen.samples.push(u.clone()),
                Update::Progress { .. } => seen.progress = Some(u.clone()),
                Update::State { .. } => seen.state = Some(u.clone()),
            }
        }
        // No page listening is not an error.
        let _ = self.updates.send(u);
    }

    pub fn state(&self, state: impl Into<String>) {
        self.publish(Update::State { state: state.into() });
    }

    /// Everything so far, and the updates from now on (subscribed first, so
    /// that none falls between the two).
    pub fn subscribe(&self) -> (Seen, broadcast::Receiver<Update>) {
        let rx = self.updates.subscribe();
        let seen = self.seen.lock().map(|s| s.clone()).unwrap_or_default();
        (seen, rx)
    }

    /// The last state published, without the samples.
    pub fn current_state(&self) -> Option<Update> {
        self.seen.lock().ok().and_then(|s| s.state.clone())
    }

    /// Asks the scan to hold before its next position.
    pub fn pause(&self) {
        self.requests.send_replace(Request::Pause);
    }

    /// Asks a held scan to go on.
    pub fn resume(&self) {
        self.requests.send_replace(Request::Run);
    }

    /// Asks the scan to stop (as Ctrl-C does: resumable).
    pub fn abort(&self) {
        self.requests.send_replace(Request::Abort);
    }

    /// Resolves once an abort is asked for.
    pub async fn aborted(&self) {
        let mut rx = self.requests.subscribe();
        let _ = rx.wait_for(|r| *r == Request::Abort).await;
    }

    /// Whether a pause is asked for.
    pub fn pause_requested(&self) -> bool {
        *self.requests.borrow() == Request::Pause
    }

    /// Resolves once a pause is asked for (at once if it is).
    pub async fn paused(&self) {
        let mut rx = self.requests.subscribe();
        let _ = rx.wait_for(|r| *r == Request::Pause).await;
    }

    /// Resolves once the scan is no longer held (asked to go on, or to stop).
    pub async fn resumed(&self) {
        let mut rx = self.requests.subscribe();
        let _ = rx.wait_for(|r| *r != Request::Pause).await;
    }
}

/// The scan directory's `live.json`, removed when dropped.
pub struct Announced(Option<std::path::PathBuf>);

impl Drop for Announced {
    fn drop(&mut self) {
        if let Some(p) = &self.0 {
            let _ = std::fs::remove_file(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_late_page_gets_everything_so_far_then_the_rest() {
        let live = Live::default();
        let sample = |t: f32| Update::Sample {
            theta_i_deg: 30.0,
            theta_o_deg: t,
            dphi_deg: 0.0,
            signal_v: 0.1,
            gain_v_per_a: 1e6,
        };
        live.publish(sample(1.0));
        live.state("scanning");
        let (seen, mut rx) = live.subscribe();
        assert_eq!(seen.samples, [sample(1.0)]);
        assert_eq!(seen.state, Some(Update::State { state: "scanning".into() }));
        assert_eq!(live.current_state(), seen.state);
        live.publish(sample(2.0));
        assert_eq!(rx.recv().await.unwrap(), sample(2.0));
    }

    #[tokio::test]
    async fn requests_wait_for_each_other() {
        let live = Live::default();
        assert!(!live.pause_requested());
        live.resumed().await; // runs: at once
        let waiting = tokio::spawn({
            let live = live.clone();
            async move { live.paused().await }
        });
        live.pause();
        waiting.await.unwrap();
        assert!(live.pause_requested());
        live.resume();
        live.resumed().await;
        live.pause();
        live.abort();
        live.resumed().await; // an abort ends the hold too
        live.aborted().await;
    }
}
