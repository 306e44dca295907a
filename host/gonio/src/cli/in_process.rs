//! The simulated head (`gonio-sim`) as a [`Target`]: each link opened to it
//! starts it in a thread of this process, and the simulation's hand puts the
//! plate or the sample on its holder. This is where the command line, the
//! tests and the benchmarks plug the simulated head into the library.

use anyhow::Result;
use gonio_acquire::link;
use gonio_acquire::operator::Operator;
use gonio_acquire::target::{Holder, Opened, Port, Target};
use gonio_scan_dir::record::RecordedHead;
use gonio_sim::faults::Faults;
use gonio_sim::{spawn_in_process, SimConfig};
use std::sync::Arc;

/// The head a scan's record names; a simulated one suffers `faults` and
/// works at `pace` (`SimConfig::pace`; neither is part of the record: they
/// act on one run).
pub fn target(head: &RecordedHead, faults: Faults, pace: f32) -> Arc<dyn Target> {
    match head {
        RecordedHead::Sim(h) => Arc::new(Simulated(SimConfig {
            faults,
            pace,
            ..h.config()
        })),
        RecordedHead::Port { path } => Arc::new(Port(path.clone())),
    }
}

#[derive(Debug, Clone, Default)]
pub struct Simulated(pub SimConfig);

impl Target for Simulated {
    fn open(&self) -> Result<Opened> {
        let head = spawn_in_process(self.0.clone());
        let (client, workers) = link::channel_client(head.to_head, head.from_head);
        Ok(Opened {
            client,
            workers,
            server: Some(head.thread),
        })
    }

    fn mount(&self, what: Holder, _: Operator) -> Result<()> {
        self.0.mount.set_plate(what == Holder::ReferencePlate);
        Ok(())
    }
}
