//! How a scan's results are given: the live page every scan serves, and
//! what it did, as text or one JSON object (`gonio scan` and the demo).

use anyhow::Result;
use gonio_scan_dir::run::ScanOutcome;
use gonio_shared::ScanSpec;
use std::path::Path;

/// Where every scan serves its live page, on this machine (so that `gonio
/// pause DIR` reaches it from another terminal); `--live` says where, for a
/// browser.
#[derive(Debug, Clone, clap::Args)]
pub struct LiveArgs {
    /// Print the address of the scan's live page (the hemisphere map filling
    /// in, signal, gain, state, time left; pause, continue and abort
    /// buttons) to open in a browser.
    #[arg(long)]
    pub live: bool,
    /// Where the live page and `gonio pause|continue|abort DIR` reach the
    /// scan: this machine only, any free port unless given.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:0")]
    pub live_addr: std::net::SocketAddr,
}

/// How results are written.
#[derive(Debug, clap::Args)]
pub struct OutputArgs {
    /// Overwrite a scan already in the output directory.
    #[arg(long)]
    pub force: bool,
    /// Print the summary as one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// Prints what the scan did (one JSON object with `json`).
pub fn summarise(spec: &ScanSpec, o: &ScanOutcome, samples: &Path, json: bool) -> Result<()> {
    match json {
        true => println!("{}", serde_json::to_string_pretty(o)?),
        false => print!("{}", o.summary(spec, samples)),
    }
    Ok(())
}
