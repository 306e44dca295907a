//! The simulated head in a thread of this process, linked by channels: what
//! `gonio demo` and the end-to-end tests use. Frames cross the channels in
//! exactly the bytes the USB link would carry.

use super::clock::{self, Idle};
use super::faulty_link::FaultyLink;
use super::{build, sentry, SimConfig, World};
use gonio_firmware::link::{Link, LinkError};
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::mpsc;
use std::task::Poll;
use std::thread::JoinHandle;
use tokio::sync::mpsc as tmpsc;

/// The head's end of the channels.
struct ChannelLink {
    rx: mpsc::Receiver<Vec<u8>>,
    tx: tmpsc::UnboundedSender<Vec<u8>>,
    world: Rc<RefCell<World>>,
}

fn take(frame: Vec<u8>, buf: &mut [u8]) -> usize {
    // Frames longer than the head's buffer are cut, as a real receive buffer
    // would; the decoder then refuses them.
    let n = frame.len().min(buf.len());
    buf[..n].copy_from_slice(&frame[..n]);
    n
}

impl Link for ChannelLink {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        std::future::poll_fn(|_| {
            if let Some(r) = self.try_recv(buf) {
                return Poll::Ready(r);
            }
            // At rest the sim thread has nothing else to do: blocking is fine.
            // Unpaced, the host's thinking takes no simulated time: the head
            // waits for its next frame however long the host computes, so a
            // run's clock (and the laser drift its samples see) does not
            // depend on how fast this machine plans. Paced, the wall clock
            // is the head's, and a deadline at rest passes as it would.
            let paced = self.world.borrow().pace > 0.0;
            let got = match clock::idle(&self.world) {
                Idle::Busy => return Poll::Pending,
                Idle::Wait(Some(d)) if paced => self.rx.recv_timeout(d),
                Idle::Wait(_) => self.rx.recv().map_err(|_| mpsc::RecvTimeoutError::Disconnected),
            };
            match got {
                Ok(f) => Poll::Ready(Ok(take(f, buf))),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    clock::timed_out(&self.world);
                    Poll::Pending
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => Poll::Ready(Err(LinkError::Closed)),
            }
        })
        .await
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        match self.rx.try_recv() {
            Ok(f) => Some(Ok(take(f, buf))),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => Some(Err(LinkError::Closed)),
        }
    }

    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.tx.send(frame.to_vec()).map_err(|_| LinkError::Closed)
    }
}

/// The host's ends of an in-process link.
pub struct InProcessLink {
    pub to_head: mpsc::Sender<Vec<u8>>,
    pub from_head: tmpsc::UnboundedReceiver<Vec<u8>>,
    /// Ends when the host side is dropped and the head has reached its safe state.
    pub thread: JoinHandle<()>,
}

/// Starts a simulated head in a new thread.
pub fn spawn_in_process(cfg: SimConfig) -> InProcessLink {
    let (to_head, rx) = mpsc::channel();
    let (tx, from_head) = tmpsc::unbounded_channel();
    let thread = std::thread::Builder::new()
        .name("sim-head".into())
        .spawn(move || {
            let (mut head, world) = build(&cfg);
            // The host's end sees the channels close when this thread ends:
            // when the host has gone, or the plan cut the link.
            let channels = ChannelLink {
                rx,
                tx,
                world: world.clone(),
            };
            let mut link = FaultyLink::new(channels, cfg.faults.clone());
            clock::run(&world, head.serve(&mut link, &mut sentry(&world)));
        })
        .expect("spawning the simulated head's thread");
    InProcessLink {
        to_head,
        from_head,
        thread,
    }
}
