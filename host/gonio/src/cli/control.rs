//! `gonio pause|continue|abort DIR`: a running scan steered from another
//! terminal, through its live view's requests (the page's buttons send the
//! same), found at `DIR/live.json`; and `gonio rearm`: a head whose E-STOP
//! was pressed, armed again once the input is closed.

use anyhow::{Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::scan::page::{self, Steer};
use gonio_acquire::target::Port;
use gonio_shared::icd::ContinueEndpoint;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct ControlArgs {
    /// The directory of the running scan (`scan --out DIR` or `demo --out DIR`).
    pub dir: PathBuf,
    /// Print one JSON object: the scan's state after the request (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn control_cmd(what: Steer, a: ControlArgs) -> Result<()> {
    let answer = page::ask(&a.dir, what)?;
    match a.json {
        true => println!("{}", serde_json::json!({ "request": what.name(), "answer": answer })),
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
