//! `gonio pause|continue|abort DIR`: a running scan steered from another
//! terminal, through its live view's requests (the page's buttons send the
//! same), found at `DIR/live.json`; and `gonio rearm`: a head whose E-STOP
//! was pressed, armed again once the input is closed.

use anyhow::{bail, Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_scan_dir::ScanDir;
use gonio_shared::icd::ContinueEndpoint;
use serde_json::Value;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct ControlArgs {
    /// The directory of the running scan (`scan --out DIR` or `demo --out DIR`).
    pub dir: PathBuf,
    /// Print one JSON object: the scan's state after the request (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Clone, Copy)]
pub enum Request {
    Pause,
    Continue,
    Abort,
}

impl Request {
    fn path(self) -> &'static str {
        match self {
            Request::Pause => "api/pause",
            Request::Continue => "api/continue",
            Request::Abort => "api/abort",
        }
    }

    fn done(self) -> &'static str {
        match self {
            Request::Pause => "pause asked: the head holds before its next position",
            Request::Continue => "continue asked: the scan goes on where it stopped",
            Request::Abort => "abort asked: the scan stops as on Ctrl-C, resumable with `gonio scan --resume DIR`",
        }
    }
}

pub fn control_cmd(what: Request, a: ControlArgs) -> Result<()> {
    let file = ScanDir::new(&a.dir).live();
    let text = std::fs::read_to_string(&file).with_context(|| {
        format!(
            "no scan is running in {} (no {}): pause, continue and abort act on a scan while it runs",
            a.dir.display(),
            file.file_name().unwrap_or_default().to_string_lossy()
        )
    })?;
    let announced: Value = serde_json::from_str(&text).with_context(|| format!("{} is not a live-view record", file.display()))?;
    let (Some(url), Some(token)) = (announced["origin"].as_str(), announced["token"].as_str()) else {
        bail!("{} names no address and token (a scan of an earlier gonio?)", file.display());
    };
    let body = ureq::post(format!("{url}/{}", what.path()))
        .header(crate::live::TOKEN_HEADER, token)
        .content_type("application/json")
        .send("{}")
        .map_err(|e| {
            anyhow::anyhow!(
                "the scan in {} does not answer at {url} ({e}): it ended without removing {} (killed?); resume it with `gonio scan --resume {}`",
                a.dir.display(),
                file.display(),
                a.dir.display()
            )
        })?
        .body_mut()
        .read_to_string()
        .context("the scan's answer")?;
    let answer: Value = serde_json::from_str(&body).context("the scan's answer")?;
    match a.json {
        true => println!(
            "{}",
            serde_json::json!({ "request": what.path().trim_start_matches("api/"), "answer": answer })
        ),
        false => eprintln!("{}", what.done()),
    }
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct RearmArgs {
    /// The head's serial port (or a `gonio sim` link).
    #[arg(long, value_name = "PATH")]
    pub port: String,
    /// Print one JSON object: the head's status (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// Arms a head again after its E-STOP: the head checks that the input reads
/// closed, then leaves the fault (laser and drivers stay off until a
/// command needs them); a scan cut by it resumes with `gonio scan --resume`.
pub async fn rearm_cmd(a: RearmArgs) -> Result<()> {
    let head = HeadClient::connect(&Port(a.port.clone())).await?;
    let status = head
        .request::<ContinueEndpoint>(&())
        .await
        .context("re-arming: is the E-STOP input closed?")?;
    match a.json {
        true => println!("{}", serde_json::to_string(&status)?),
        false => eprintln!("re-armed: the head is {:?}", status.state),
    }
    Ok(())
}
