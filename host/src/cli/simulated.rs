//! The simulated head (`gonio-sim`) as a [`Target`]: each link opened to it
//! starts it in a thread of this process, and the simulation's hand puts the
//! plate or the sample on its holder. This is where the command line, the
//! tests and the benchmarks plug the simulated head into the library.

use crate::link;
use crate::operator::Operator;
use crate::target::{Holder, Opened, Target};
use anyhow::Result;
use gonio_sim::{spawn_in_process, SimConfig};

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
