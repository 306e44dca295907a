//! A link over in-process channels carrying sealed frames, in exactly the
//! bytes the USB link would carry: the host's end of a head served by a
//! thread of this process (the simulated head of `gonio-sim`).

use super::{config, WireClosed, Workers};
use postcard_rpc::host_client::{HostClient, WireRx, WireTx};
use postcard_rpc::standard_icd::WireError;
use std::sync::mpsc;
use tokio::sync::mpsc as tmpsc;

struct Tx(mpsc::Sender<Vec<u8>>);
struct Rx(tmpsc::UnboundedReceiver<Vec<u8>>);

impl WireTx for Tx {
    type Error = WireClosed;
    async fn send(&mut self, data: Vec<u8>) -> Result<(), WireClosed> {
        self.0
            .send(super::seal(data))
            .map_err(|_| WireClosed("the head's thread stopped".into()))
    }
}

impl WireRx for Rx {
    type Error = WireClosed;
    async fn receive(&mut self) -> Result<Vec<u8>, WireClosed> {
        loop {
            let sealed = self.0.recv().await.ok_or_else(|| WireClosed("the head's thread stopped".into()))?;
            if let Some(f) = super::open(sealed) {
                return Ok(f);
            }
        }
    }
}

/// A client over a pair of channels: frames to the head go into `to_head`,
/// the head's frames come out of `from_head`. Must be called within a tokio
/// runtime.
pub fn channel_client(to_head: mpsc::Sender<Vec<u8>>, from_head: tmpsc::UnboundedReceiver<Vec<u8>>) -> (HostClient<WireError>, Workers) {
    let workers = Workers::default();
    let client = HostClient::new_with_wire_and_config(Tx(to_head), Rx(from_head), workers.clone(), &config());
    (client, workers)
}
