//! A simulated head driven frame by frame, without a client: each call
//! serves a batch of frames from the host as one link session (the link
//! closes after the last, so the head ends in its safe state, as when a
//! cable is pulled), and returns the head's frames. The fuzzers and the
//! command-validation property test drive the firmware's dispatch with it
//! and look at the virtual hardware in between.

use super::{board::SimBoard, build, SimConfig, World};
use gonio_firmware::link::{Link, LinkError};
use gonio_firmware::Head;
use std::cell::{Ref, RefCell, RefMut};
use std::collections::VecDeque;
use std::rc::Rc;

struct Batch {
    inbound: VecDeque<Vec<u8>>,
    outbound: Vec<Vec<u8>>,
}

fn take(frame: Vec<u8>, buf: &mut [u8]) -> usize {
    let n = frame.len().min(buf.len());
    buf[..n].copy_from_slice(&frame[..n]);
    n
}

impl Link for Batch {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.inbound.pop_front().map(|f| take(f, buf)).ok_or(LinkError::Closed)
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        Some(self.inbound.pop_front().map(|f| take(f, buf)).ok_or(LinkError::Closed))
    }

    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.outbound.push(frame.to_vec());
        Ok(())
    }
}

/// A firmware head on virtual hardware, served batch by batch.
pub struct FrameHead {
    head: Head<SimBoard>,
    world: Rc<RefCell<World>>,
}

impl FrameHead {
    pub fn new(cfg: &SimConfig) -> Self {
        let (head, world) = build(cfg);
        FrameHead { head, world }
    }

    /// Serves `frames` (sealed, as on the wire), then the link closes;
    /// returns what the head sent.
    pub fn serve(&mut self, frames: impl IntoIterator<Item = Vec<u8>>) -> Vec<Vec<u8>> {
        let mut link = Batch {
            inbound: frames.into_iter().collect(),
            outbound: Vec::new(),
        };
        futures::executor::block_on(self.head.serve(&mut link));
        link.outbound
    }

    pub fn world(&self) -> Ref<'_, World> {
        self.world.borrow()
    }

    pub fn world_mut(&self) -> RefMut<'_, World> {
        self.world.borrow_mut()
    }
}
