//! Transports from the host to a head, as postcard-rpc `HostClient` wires:
//! a byte stream carrying COBS frames (the head's USB CDC-ACM port, or the
//! simulated head's pseudo-terminal) and in-process channels (a head served
//! by a thread of this process). Both use the wire format of the message crate (`gonio_shared::wire`).

mod channel;
mod stream;

pub use channel::channel_client;
pub use stream::serial_client;

use postcard_rpc::header::VarSeqKind;
use postcard_rpc::host_client::{HostClientConfig, WireSpawn};
use postcard_rpc::standard_icd::ERROR_PATH;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::task::JoinHandle;

/// Depth of queues between the wire workers and the client.
const DEPTH: usize = 64;

/// Client settings shared by every transport. Topic subscribers get
/// back-pressure for up to this long instead of losing scan events.
fn config() -> HostClientConfig<'static> {
    HostClientConfig {
        seq_kind: VarSeqKind::Seq4,
        err_uri_path: ERROR_PATH,
        outgoing_depth: DEPTH,
        subscriber_timeout_if_full: Duration::from_secs(30),
    }
}

/// The wire tasks of a client, spawned on the current tokio runtime and kept
/// so that closing a client can wait until they have released the port.
#[derive(Clone, Default)]
pub struct Workers(Arc<Mutex<Vec<JoinHandle<()>>>>);

impl Workers {
    /// Waits for every wire task to end (call after `HostClient::close`).
    pub async fn join(self) {
        let handles = std::mem::take(&mut *self.0.lock().unwrap_or_else(|e| e.into_inner()));
        for h in handles {
            let _ = h.await;
        }
    }
}

impl WireSpawn for Workers {
    fn spawn(&mut self, fut: impl std::future::Future<Output = ()> + Send + 'static) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(tokio::task::spawn(fut));
    }
}

/// A frame with its check appended (`gonio_shared::wire::check`), as every wire sends it.
fn seal(mut frame: Vec<u8>) -> Vec<u8> {
    let n = frame.len();
    frame.resize(n + gonio_shared::wire::check::LEN, 0);
    // The buffer has room for the check by construction.
    let _ = gonio_shared::wire::check::seal(&mut frame, n);
    frame
}

/// The frame inside a received one, or `None` when its check fails: the
/// frame is dropped as if lost (requests time out, scan gaps are re-requested).
fn open(mut sealed: Vec<u8>) -> Option<Vec<u8>> {
    let n = gonio_shared::wire::check::open(&sealed)?.len();
    sealed.truncate(n);
    Some(sealed)
}

/// A wire that has closed.
#[derive(Debug, thiserror::Error)]
#[error("link closed: {0}")]
pub struct WireClosed(String);
