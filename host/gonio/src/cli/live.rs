//! `--live` and `--live-addr` of `scan` and `demo`: every scan serves its
//! live view on this machine (so that `gonio pause DIR` reaches it from
//! another terminal); `--live` says where, for a browser.

use crate::live;
use anyhow::{bail, Result};
use gonio_acquire::operator::Operator;
use gonio_acquire::scan::live::Live;
use std::net::SocketAddr;

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
    pub live_addr: SocketAddr,
}

/// Serves a new live scan's page; says where with `--live`.
pub async fn start(a: &LiveArgs, operator: Operator) -> Result<Live> {
    if !a.live_addr.ip().is_loopback() {
        bail!(
            "--live-addr {}: the live page pauses and aborts the scan; it listens on this machine only (127.0.0.1 or [::1])",
            a.live_addr
        );
    }
    let live = Live::default();
    let served = live::serve(live.clone(), a.live_addr).await?;
    if a.live {
        operator.notice(format_args!("live view: {}", served.url));
    }
    Ok(live.served_at(served))
}
