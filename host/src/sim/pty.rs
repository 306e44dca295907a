//! The simulated head as a separate process on a pseudo-terminal: COBS frames
//! on a byte stream, exactly as the real head's USB CDC-ACM port, so that
//! `gonio scan --port PATH` cannot tell the two apart except by identity.

use super::clock::{self, Idle};
use super::faulty_link::FaultyLink;
use super::{build, sentry, SimConfig, World};
use anyhow::{Context, Result};
use gonio_firmware::framing::{self, Decoder, MAX_ENCODED};
use gonio_firmware::link::{Link, LinkError};
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::path::Path;
use std::rc::Rc;
use std::task::Poll;

const WRITE_TIMEOUT_MS: u16 = 2000;

struct PtyLink {
    master: File,
    decoder: Decoder,
    frames: VecDeque<Vec<u8>>,
    world: Rc<RefCell<World>>,
}

impl PtyLink {
    /// Reads what is available (blocking up to `wait`, for ever for `None`),
    /// queueing whole frames; false when the wait ran out.
    fn pump(&mut self, wait: Option<std::time::Duration>) -> bool {
        let timeout = match wait {
            None => PollTimeout::NONE,
            Some(d) => PollTimeout::try_from(d).unwrap_or(PollTimeout::MAX),
        };
        let ready = {
            let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
            poll(&mut fds, timeout).map(|n| n > 0).unwrap_or(false)
        };
        if !ready {
            return false;
        }
        let mut buf = [0u8; 512];
        match self.master.read(&mut buf) {
            Ok(n) => {
                let frames = &mut self.frames;
                self.decoder.feed(&buf[..n], |f| frames.push_back(f.to_vec()));
            }
            // EIO or a spurious wake-up: wait and look again.
            Err(_) => std::thread::sleep(std::time::Duration::from_millis(20)),
        }
        true
    }

    fn pop(&mut self, buf: &mut [u8]) -> Option<usize> {
        let f = self.frames.pop_front()?;
        let n = f.len().min(buf.len());
        buf[..n].copy_from_slice(&f[..n]);
        Some(n)
    }
}

impl Link for PtyLink {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        std::future::poll_fn(|_| {
            if let Some(r) = self.try_recv(buf) {
                return Poll::Ready(r);
            }
            match clock::idle(&self.world) {
                Idle::Busy => {}
                Idle::Wait(wait) => {
                    if !self.pump(wait) && wait.is_some() {
                        clock::timed_out(&self.world);
                    }
                }
            }
            match self.pop(buf) {
                Some(n) => Poll::Ready(Ok(n)),
                None => Poll::Pending,
            }
        })
        .await
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        if self.frames.is_empty() {
            self.pump(Some(std::time::Duration::ZERO));
        }
        self.pop(buf).map(Ok)
    }

    /// Writes a frame; a host that stops reading for [`WRITE_TIMEOUT_MS`]
    /// counts as gone, as a USB host that stops polling would.
    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let mut out = [0u8; MAX_ENCODED];
        let n = framing::encode(frame, &mut out).ok_or(LinkError::Closed)?;
        let mut rest = &out[..n];
        while !rest.is_empty() {
            match self.master.write(rest) {
                Ok(k) => rest = &rest[k..],
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLOUT)];
                    if poll(&mut fds, PollTimeout::from(WRITE_TIMEOUT_MS)).unwrap_or(0) == 0 {
                        return Err(LinkError::Closed);
                    }
                }
                Err(_) => return Err(LinkError::Closed),
            }
        }
        Ok(())
    }
}

/// Serves a simulated head on a new pseudo-terminal, reachable at `link`
/// (a symbolic link to the terminal). Runs until the process is stopped.
pub fn serve_pty(cfg: SimConfig, link: &Path, on_ready: impl FnOnce(&Path)) -> Result<()> {
    let pty = openpty(None, None).context("opening a pseudo-terminal")?;
    // Raw mode: no echo, no line editing, all 256 byte values pass.
    let mut t = tcgetattr(&pty.slave).context("reading terminal attributes")?;
    cfmakeraw(&mut t);
    tcsetattr(&pty.slave, SetArg::TCSANOW, &t).context("setting raw mode")?;
    let slave_path = std::fs::read_link(format!("/proc/self/fd/{}", std::os::fd::AsRawFd::as_raw_fd(&pty.slave)))
        .context("finding the terminal's path")?;
    if link.symlink_metadata().is_ok() {
        std::fs::remove_file(link).with_context(|| format!("replacing {}", link.display()))?;
    }
    std::os::unix::fs::symlink(&slave_path, link).with_context(|| format!("creating {}", link.display()))?;
    on_ready(link);
    // Keep our own slave descriptor open so the master never reads EIO
    // between two host sessions.
    let _slave: OwnedFd = pty.slave;
    let flags = fcntl(&pty.master, FcntlArg::F_GETFL).context("reading descriptor flags")?;
    fcntl(&pty.master, FcntlArg::F_SETFL(OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK)).context("setting non-blocking mode")?;
    let (mut head, world) = build(&cfg);
    // A cut link (fault plan) leaves the head silent until the host's next request.
    let pty_link = PtyLink {
        master: File::from(pty.master),
        decoder: Decoder::new(),
        frames: VecDeque::new(),
        world: world.clone(),
    };
    let mut l = FaultyLink::new(pty_link, cfg.faults.clone());
    let mut sentry = sentry(&world);
    loop {
        clock::run(&world, head.serve(&mut l, &mut sentry));
    }
}
