//! A simulated head driven frame by frame, without a client: each call
//! serves a batch of frames from the host as one link session (the link
//! closes after the last, so the head ends in its safe state, as when a
//! cable is pulled), and returns the head's frames with the state of the
//! laser and the drivers when each was sent. The fuzzers, the
//! command-validation property test and the fault matrix drive the
//! firmware's dispatch with it and look at the virtual hardware.

use super::{board::SimBoard, build, clock, sentry, SimConfig, World};
use gonio_firmware::link::{Link, LinkError};
use gonio_firmware::Head;
use std::cell::{Ref, RefCell, RefMut};
use std::collections::VecDeque;
use std::rc::Rc;
use std::task::Poll;

/// A frame the head sent, and the state of the laser and the motor drivers
/// at that moment.
#[derive(Debug, Clone)]
pub struct Sent {
    pub frame: Vec<u8>,
    pub laser: bool,
    pub drivers_enabled: bool,
    /// Stage positions (microsteps) and times the laser was switched on so far.
    pub steps: [i32; 3],
    pub laser_ons: u64,
}

struct Batch {
    inbound: VecDeque<Vec<u8>>,
    outbound: Vec<Sent>,
    world: Rc<RefCell<World>>,
    /// Keep the link open (and silent) while a scan runs, instead of closing
    /// it once the frames are served.
    open: bool,
    /// The cable is pulled once the head has sent this many frames.
    cut_after: Option<usize>,
}

fn take(frame: Vec<u8>, buf: &mut [u8]) -> usize {
    let n = frame.len().min(buf.len());
    buf[..n].copy_from_slice(&frame[..n]);
    n
}

impl Link for Batch {
    /// The next frame; with none left, the link stays open while the head
    /// works and closes when it next waits for a request.
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        std::future::poll_fn(|_| match self.inbound.pop_front() {
            Some(f) => Poll::Ready(Ok(take(f, buf))),
            None if self.world.borrow().busy => Poll::Pending,
            None => Poll::Ready(Err(LinkError::Closed)),
        })
        .await
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        match self.inbound.pop_front() {
            Some(f) => Some(Ok(take(f, buf))),
            None if self.open => None,
            None => Some(Err(LinkError::Closed)),
        }
    }

    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        if self.cut_after.is_some_and(|n| self.outbound.len() >= n) {
            return Err(LinkError::Closed);
        }
        let w = self.world.borrow();
        self.outbound.push(Sent {
            frame: frame.to_vec(),
            laser: w.laser,
            drivers_enabled: w.enable_n.iter().any(|&off| !off),
            steps: w.steps,
            laser_ons: w.laser_ons,
        });
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
    pub fn serve(&mut self, frames: impl IntoIterator<Item = Vec<u8>>) -> Vec<Sent> {
        self.run(frames, false, None)
    }

    /// Serves `frames`, then keeps the link open but silent while a scan
    /// runs (to its end, or until the head stops it), then closes it.
    pub fn serve_open(&mut self, frames: impl IntoIterator<Item = Vec<u8>>) -> Vec<Sent> {
        self.run(frames, true, None)
    }

    /// As [`FrameHead::serve_open`], but the link is cut (a pulled cable)
    /// once the head has sent `n` frames.
    pub fn serve_cut(&mut self, frames: impl IntoIterator<Item = Vec<u8>>, n: usize) -> Vec<Sent> {
        self.run(frames, true, Some(n))
    }

    fn run(&mut self, frames: impl IntoIterator<Item = Vec<u8>>, open: bool, cut_after: Option<usize>) -> Vec<Sent> {
        let mut link = Batch {
            inbound: frames.into_iter().collect(),
            outbound: Vec::new(),
            world: self.world.clone(),
            open,
            cut_after,
        };
        clock::run(&self.world, self.head.serve(&mut link, &mut sentry(&self.world)));
        link.outbound
    }

    pub fn world(&self) -> Ref<'_, World> {
        self.world.borrow()
    }

    pub fn world_mut(&self) -> RefMut<'_, World> {
        self.world.borrow_mut()
    }
}
