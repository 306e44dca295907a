//! The live page's requests sent from another terminal (`gonio
//! pause|continue|abort DIR`): the address and token are read from the
//! scan's `DIR/live.json`, and the request is the one the page's buttons send.

use super::TOKEN_HEADER;
use anyhow::{bail, Context, Result};
use gonio_scan_dir::ScanDir;
use serde_json::Value;
use std::path::Path;

/// What is asked of a running scan.
#[derive(Debug, Clone, Copy)]
pub enum Steer {
    Pause,
    Continue,
    Abort,
}

impl Steer {
    /// Its name, as `--json` reports it.
    pub fn name(self) -> &'static str {
        self.path().trim_start_matches("api/")
    }

    fn path(self) -> &'static str {
        match self {
            Steer::Pause => "api/pause",
            Steer::Continue => "api/continue",
            Steer::Abort => "api/abort",
        }
    }

    /// What was asked, in a sentence for the operator.
    pub fn done(self) -> &'static str {
        match self {
            Steer::Pause => "pause asked: the head holds before its next position",
            Steer::Continue => "continue asked: the scan goes on where it stopped",
            Steer::Abort => "abort asked: the scan stops as on Ctrl-C, resumable with `gonio scan --resume DIR`",
        }
    }
}

/// Sends `what` to the scan running in `dir`, found through `DIR/live.json`;
/// returns the scan's state after it.
pub fn ask(dir: &Path, what: Steer) -> Result<Value> {
    let file = ScanDir::new(dir).live();
    let text = std::fs::read_to_string(&file).with_context(|| {
        format!(
            "no scan is running in {} (no {}): pause, continue and abort act on a scan while it runs",
            dir.display(),
            file.file_name().unwrap_or_default().to_string_lossy()
        )
    })?;
    let announced: Value = serde_json::from_str(&text).with_context(|| format!("{} is not a live-view record", file.display()))?;
    let (Some(url), Some(token)) = (announced["origin"].as_str(), announced["token"].as_str()) else {
        bail!("{} names no address and token (a scan of an earlier gonio?)", file.display());
    };
    let body = ureq::post(format!("{url}/{}", what.path()))
        .header(TOKEN_HEADER, token)
        .content_type("application/json")
        .send("{}")
        .map_err(|e| {
            anyhow::anyhow!(
                "the scan in {} does not answer at {url} ({e}): it ended without removing {} (killed?); resume it with `gonio scan --resume {}`",
                dir.display(),
                file.display(),
                dir.display()
            )
        })?
        .body_mut()
        .read_to_string()
        .context("the scan's answer")?;
    serde_json::from_str(&body).context("the scan's answer")
}
