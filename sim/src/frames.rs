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
    /// Simulated time (s) it was sent at.
    pub t_s: f64,
}

impl Sent {
    /// The head's state as it sends `frame`.
    fn now(world: &World, frame: &[u8]) -> Sent {
        Sent {
            frame: frame.to_vec(),
            laser: world.laser,
            drivers_enabled: world.enable_n.iter().any(|&off| !off),
            steps: world.steps,
            laser_ons: world.laser_ons,
            t_s: world.t_s,
        }
    }
}

/// What happens on the link at a moment of simulated time
/// ([`FrameHead::serve_timed`]).
#[derive(Debug, Clone)]
pub enum Cue {
    /// The host sends this (sealed) frame.
    Frame(Vec<u8>),
    /// The cable is pulled.
    Close,
}

/// A link that plays cues at their times: the head sees each frame when the
/// simulated clock reaches it; at rest, time runs on to the next cue (or to
/// what the head waits for), and the link closes at the end.
struct Timed {
    cues: VecDeque<(f64, Cue)>,
    until: f64,
    outbound: Vec<Sent>,
    world: Rc<RefCell<World>>,
    /// From when to when (s) the host does not read: a send waits.
    deaf: Option<(f64, f64)>,
}

impl Timed {
    /// The cue that is due, as the link delivers it.
    fn due(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        let now = self.world.borrow().t_s;
        if self.cues.front().is_none_or(|(t, _)| *t > now) {
            return None;
        }
        match self.cues.pop_front()?.1 {
            Cue::Frame(f) => Some(Ok(take(f, buf))),
            Cue::Close => {
                self.cues.clear();
                self.until = now;
                Some(Err(LinkError::Closed))
            }
        }
    }
}

impl Link for Timed {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        std::future::poll_fn(|_| {
            if let Some(r) = self.due(buf) {
                return Poll::Ready(r);
            }
            let next = self.cues.front().map_or(self.until, |(t, _)| *t);
            let mut w = self.world.borrow_mut();
            if w.t_s >= next {
                return Poll::Ready(Err(LinkError::Closed));
            }
            w.wake(next);
            if !clock::busy(&w) {
                // At rest: on to the next cue or to what the head waits for.
                let to = w.wake_at.map_or(next, |t| t.min(next));
                w.t_s = w.t_s.max(to);
                if w.wake_at.is_some_and(|t| t <= w.t_s) {
                    w.wake_at = None;
                }
            }
            Poll::Pending
        })
        .await
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        self.due(buf)
    }

    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let now = self.world.borrow().t_s;
        if let Some((_, to)) = self.deaf.filter(|&(from, to)| (from..to).contains(&now)) {
            clock::elapse(&self.world, to - now).await;
        }
        self.outbound.push(Sent::now(&self.world.borrow(), frame));
        Ok(())
    }
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
            None if clock::busy(&self.world.borrow()) => Poll::Pending,
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
        self.outbound.push(Sent::now(&self.world.borrow(), frame));
        Ok(())
    }
}

/// A firmware head on virtual hardware, served batch by batch.
pub struct FrameHead {
    head: Head<SimBoard>,
    world: Rc<RefCell<World>>,
    /// When the host of [`FrameHead::serve_timed`] does not read.
    deaf: Option<(f64, f64)>,
}

impl FrameHead {
    pub fn new(cfg: &SimConfig) -> Self {
        let (head, world) = build(cfg);
        FrameHead { head, world, deaf: None }
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

    /// Serves `cues` at their simulated times (s, absolute: see
    /// [`FrameHead::now`]); the link closes at `until` or at a
    /// [`Cue::Close`]. Returns what the head sent.
    pub fn serve_timed(&mut self, cues: impl IntoIterator<Item = (f64, Cue)>, until: f64) -> Vec<Sent> {
        let mut link = Timed {
            cues: cues.into_iter().collect(),
            until,
            outbound: Vec::new(),
            world: self.world.clone(),
            deaf: self.deaf,
        };
        clock::run(&self.world, self.head.serve(&mut link, &mut sentry(&self.world)));
        link.outbound
    }

    /// From `from_s` to `to_s` (the head's clock) the host of
    /// [`FrameHead::serve_timed`] reads nothing: the head's sends wait, as on
    /// a full USB queue.
    pub fn deaf_between(&mut self, from_s: f64, to_s: f64) {
        self.deaf = Some((from_s, to_s));
    }

    /// The head's clock (s).
    pub fn now(&self) -> f64 {
        self.world.borrow().t_s
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
