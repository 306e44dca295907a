//! The host's side of the in-process link to a simulated head.

use super::{config, WireClosed, Workers};
use crate::sim::{spawn_in_process, SimConfig};
use postcard_rpc::host_client::{HostClient, WireRx, WireTx};
use postcard_rpc::standard_icd::WireError;
use std::sync::mpsc;
use std::thread::JoinHandle;
use tokio::sync::mpsc as tmpsc;

struct Tx(mpsc::Sender<Vec<u8>>);
struct Rx(tmpsc::UnboundedReceiver<Vec<u8>>);

impl WireTx for Tx {
    type Error = WireClosed;
    async fn send(&mut self, data: Vec<u8>) -> Result<(), WireClosed> {
        self.0
            .send(super::seal(data))
            .map_err(|_| WireClosed("simulated head stopped".into()))
    }
}

impl WireRx for Rx {
    type Error = WireClosed;
    async fn receive(&mut self) -> Result<Vec<u8>, WireClosed> {
        loop {
            let sealed = self.0.recv().await.ok_or_else(|| WireClosed("simulated head stopped".into()))?;
            if let Some(f) = super::open(sealed) {
                return Ok(f);
            }
        }
    }
}

/// Starts a simulated head in this process and connects a client to it.
/// Must be called within a tokio runtime.
pub fn in_process_client(cfg: SimConfig) -> (HostClient<WireError>, Workers, JoinHandle<()>) {
    let link = spawn_in_process(cfg);
    let workers = Workers::default();
    let client = HostClient::new_with_wire_and_config(Tx(link.to_head), Rx(link.from_head), workers.clone(), &config());
    (client, workers, link.thread)
}
