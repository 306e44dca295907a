//! Where a head is: the one interface through which the library reaches any
//! head. A head at a serial port ([`Port`]) is the library's own; a head the
//! caller builds (the simulated head of `gonio-sim`, wired by `cli/`) is
//! another implementation, so that nothing in the library asks whether a
//! head is simulated.

use crate::link::{self, Workers};
use crate::operator::Operator;
use anyhow::Result;
use postcard_rpc::host_client::HostClient;
use postcard_rpc::standard_icd::WireError;
use std::fmt::Debug;
use std::sync::Arc;
use std::thread::JoinHandle;

/// A link opened to a head.
pub struct Opened {
    pub client: HostClient<WireError>,
    pub workers: Workers,
    /// A thread of this process that serves the head, if any: joined when
    /// the link closes, so a closed head has reached its safe state.
    pub server: Option<JoinHandle<()>>,
}

/// What sits on the sample holder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Holder {
    ReferencePlate,
    Sample,
}

impl Holder {
    fn describe(self) -> &'static str {
        match self {
            Holder::ReferencePlate => "the reference plate",
            Holder::Sample => "the sample",
        }
    }
}

/// A head the host can reach.
pub trait Target: Send + Sync + Debug {
    /// Opens a link to the head (called again after the link was lost).
    fn open(&self) -> Result<Opened>;

    /// Puts `what` on the head's holder: the operator's hands at a real head.
    fn mount(&self, what: Holder, operator: Operator) -> Result<()>;

    /// Where the same head (serial `serial`) may be found when it is no
    /// longer where this target says, e.g. a USB head that came back on
    /// another port after its cable was pulled.
    fn elsewhere(&self, serial: &str) -> Option<Arc<dyn Target>> {
        let _ = serial;
        None
    }
}

/// A head at a serial port: the head's USB port, or a simulated head's
/// pseudo-terminal (`gonio sim`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port(pub String);

impl Target for Port {
    fn open(&self) -> Result<Opened> {
        let (client, workers) = link::serial_client(&self.0)?;
        Ok(Opened {
            client,
            workers,
            server: None,
        })
    }

    fn mount(&self, what: Holder, operator: Operator) -> Result<()> {
        operator.ask(format_args!("mount {} on the holder", what.describe()))
    }

    fn elsewhere(&self, serial: &str) -> Option<Arc<dyn Target>> {
        crate::usb::port_of_serial(serial)
            .filter(|q| *q != self.0)
            .map(|q| Arc::new(Port(q)) as Arc<dyn Target>)
    }
}
