//! Transports from the host to a head, as postcard-rpc `HostClient` wires:
//! a byte stream carrying COBS frames (the head's USB CDC-ACM port, or the
//! simulated head's pseudo-terminal) and in-process channels (the simulated
//! head in a thread). Both use the firmware's own framing code.

mod inproc;
mod stream;

pub use inproc::in_process_client;
pub use stream::serial_client;

use postcard_rpc::header::VarSeqKind;
use postcard_rpc::host_client::{HostClientConfig, WireSpawn};
use postcard_rpc::standard_icd::ERROR_PATH;
use std::time::Duration;

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

/// Spawns the wire workers on the current tokio runtime.
struct TokioSpawn;

impl WireSpawn for TokioSpawn {
    fn spawn(&mut self, fut: impl std::future::Future<Output = ()> + Send + 'static) {
        drop(tokio::task::spawn(fut));
    }
}

/// A wire that has closed.
#[derive(Debug, thiserror::Error)]
#[error("link closed: {0}")]
pub struct WireClosed(String);
