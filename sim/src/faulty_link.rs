//! The link faults of a fault schedule, applied to any link of the simulated
//! head (in-process channels, pseudo-terminal): frames the head sends and
//! requests it receives are dropped, corrupted, duplicated, reordered or
//! delayed, or the link is cut, at the frame numbers of the plan.
//!
//! Status requests and their answers are neither counted nor hit: they are
//! the host's polls and probes, sent after so much wall-clock time without
//! an answer, so how many there are depends on how busy the machine is. Left
//! out, a plan hits the same request or event on every run.

use super::faults::{Direction, Faults, LinkFault};
use gonio_firmware::link::{Link, LinkError};
use gonio_shared::icd::StatusEndpoint;
use gonio_shared::wire::check;
use gonio_shared::wire::key_is;
use postcard_rpc::header::VarHeader;
use postcard_rpc::Endpoint;
use std::collections::VecDeque;

pub struct FaultyLink<L> {
    inner: L,
    faults: Faults,
    /// A frame to the host held back to go after the next one.
    held_reply: Option<Vec<u8>>,
    /// Requests that arrived, faults applied, for the head to read.
    inbox: VecDeque<Vec<u8>>,
    /// A request held back to arrive after the next one.
    held_request: Option<Vec<u8>>,
}

impl<L: Link> FaultyLink<L> {
    /// The link the faults are applied to.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    pub fn new(inner: L, faults: Faults) -> Self {
        FaultyLink {
            inner,
            faults,
            held_reply: None,
            inbox: VecDeque::new(),
            held_request: None,
        }
    }

    /// A request meets the plan; what survives goes into the inbox. A cut
    /// link reports itself closed once (the head goes to its safe state and
    /// stops serving it).
    fn arrive(&mut self, frame: Vec<u8>) -> Result<(), LinkError> {
        let fault = self.fault_for(Direction::ToHead, &frame);
        let delivered = meet(fault, frame, &mut self.held_request)?;
        self.inbox.extend(delivered);
        Ok(())
    }

    /// Counts a frame travelling `way`, unless it is status traffic; returns
    /// the fault that hits it.
    fn fault_for(&self, way: Direction, frame: &[u8]) -> Option<LinkFault> {
        if is_status(frame) {
            return None;
        }
        self.faults.next_frame(way)
    }

    fn pop(&mut self, buf: &mut [u8]) -> Option<usize> {
        let f = self.inbox.pop_front()?;
        let n = f.len().min(buf.len());
        buf[..n].copy_from_slice(&f[..n]);
        Some(n)
    }
}

/// Whether a sealed frame is a status request or a status answer.
fn is_status(sealed: &[u8]) -> bool {
    check::open(sealed)
        .and_then(VarHeader::take_from_slice)
        .is_some_and(|(hdr, _)| key_is(StatusEndpoint::REQ_KEY, &hdr.key) || key_is(StatusEndpoint::RESP_KEY, &hdr.key))
}

/// A frame meets its fault, either way along the link: the frames that go
/// on, in order (none, the frame, twice, or followed by the one `held` back
/// for reordering), or the link cut.
fn meet(fault: Option<LinkFault>, mut frame: Vec<u8>, held: &mut Option<Vec<u8>>) -> Result<Vec<Vec<u8>>, LinkError> {
    let mut delivered = Vec::new();
    match fault {
        None => {}
        Some(LinkFault::Drop) => return Ok(delivered),
        Some(LinkFault::Corrupt) => corrupt(&mut frame),
        Some(LinkFault::Duplicate) => delivered.push(frame.clone()),
        Some(LinkFault::Reorder) => {
            *held = Some(frame);
            return Ok(delivered);
        }
        Some(LinkFault::Delay(ms)) => delay(ms),
        Some(LinkFault::Disconnect) => return Err(LinkError::Closed),
    }
    delivered.push(frame);
    delivered.extend(held.take());
    Ok(delivered)
}

/// Flips one bit in the middle of a frame: its check no longer holds.
fn corrupt(frame: &mut [u8]) {
    let i = frame.len() / 2;
    if let Some(b) = frame.get_mut(i) {
        *b ^= 0x10;
    }
}

/// A late frame: the simulated head waits, as a stalled USB transfer would hold it.
fn delay(ms: u32) {
    std::thread::sleep(std::time::Duration::from_millis(ms as u64));
}

impl<L: Link> Link for FaultyLink<L> {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        loop {
            if let Some(n) = self.pop(buf) {
                return Ok(n);
            }
            let n = self.inner.recv(buf).await?;
            self.arrive(buf[..n].to_vec())?;
        }
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        loop {
            if let Some(n) = self.pop(buf) {
                return Some(Ok(n));
            }
            let arrived = match self.inner.try_recv(buf)? {
                Ok(n) => self.arrive(buf[..n].to_vec()),
                Err(e) => Err(e),
            };
            if let Err(e) = arrived {
                return Some(Err(e));
            }
        }
    }

    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let fault = self.fault_for(Direction::ToHost, frame);
        for f in meet(fault, frame.to_vec(), &mut self.held_reply)? {
            self.inner.send(&f).await?;
        }
        Ok(())
    }
}
