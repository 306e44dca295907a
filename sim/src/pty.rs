//! The simulated head as a separate process on a pseudo-terminal: COBS frames
//! on a byte stream, exactly as the real head's USB CDC-ACM port, so that
//! `gonio scan --port PATH` cannot tell the two apart except by identity.

use super::clock::{self, Idle};
use super::faulty_link::FaultyLink;
use super::{build, sentry, SimConfig, World};
use anyhow::{Context, Result};
use gonio_firmware::link::{Link, LinkError};
use gonio_shared::wire::framing::{self, Decoder, MAX_ENCODED};
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
    /// queueing whole frames; `Ok(false)` when the wait ran out, `Err` when
    /// the host has closed the port (no process holds the terminal open:
    /// the pseudo-terminal's hang-up, as a USB host's closing drops DTR).
    fn pump(&mut self, wait: Option<std::time::Duration>) -> Result<bool, LinkError> {
        let timeout = match wait {
            None => PollTimeout::NONE,
            Some(d) => PollTimeout::try_from(d).unwrap_or(PollTimeout::MAX),
        };
        let revents = {
            let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, timeout) {
                Ok(n) if n > 0 => fds[0].revents().unwrap_or(PollFlags::empty()),
                _ => PollFlags::empty(),
            }
        };
        if revents.contains(PollFlags::POLLHUP) && !revents.contains(PollFlags::POLLIN) {
            return Err(LinkError::Closed);
        }
        if revents.is_empty() {
            return Ok(false);
        }
        let mut buf = [0u8; 512];
        // An error is a spurious wake-up: look again.
        if let Ok(n) = self.master.read(&mut buf) {
            let frames = &mut self.frames;
            self.decoder.feed(&buf[..n], |f| frames.push_back(f.to_vec()));
        }
        Ok(true)
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
            if let Idle::Wait(wait) = clock::idle(&self.world) {
                match self.pump(wait) {
                    Err(e) => return Poll::Ready(Err(e)),
                    Ok(false) if wait.is_some() => clock::timed_out(&self.world),
                    Ok(_) => {}
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
            if let Err(e) = self.pump(Some(std::time::Duration::ZERO)) {
                return Some(Err(e));
            }
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
    // Our own slave descriptor closes: the terminal then hangs up whenever
    // no host holds it open, which is how the head sees a closed port.
    drop::<OwnedFd>(pty.slave);
    let flags = fcntl(&pty.master, FcntlArg::F_GETFL).context("reading descriptor flags")?;
    fcntl(&pty.master, FcntlArg::F_SETFL(OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK)).context("setting non-blocking mode")?;
    let (mut head, world) = build(&cfg);
    // A cut link (fault schedule) leaves the head silent until the host's next request.
    let pty_link = PtyLink {
        master: File::from(pty.master),
        decoder: Decoder::new(),
        frames: VecDeque::new(),
        world: world.clone(),
    };
    let mut l = FaultyLink::new(pty_link, cfg.faults.clone());
    let mut sentry = sentry(&world);
    loop {
        wait_for_host_on(&l.inner().master, &world);
        clock::run(&world, head.serve(&mut l, &mut sentry));
    }
}

/// Waits until a host opens the terminal (it stops hanging up); the time
/// the head spends at rest meanwhile passes on its clock.
fn wait_for_host_on(master: &File, world: &Rc<RefCell<World>>) {
    const LOOK_EVERY: std::time::Duration = std::time::Duration::from_millis(10);
    loop {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        let hung_up = matches!(poll(&mut fds, PollTimeout::ZERO), Ok(n) if n > 0)
            && fds[0]
                .revents()
                .is_some_and(|r| r.contains(PollFlags::POLLHUP) && !r.contains(PollFlags::POLLIN));
        if !hung_up {
            return;
        }
        std::thread::sleep(LOOK_EVERY);
        world.borrow_mut().t_s += LOOK_EVERY.as_secs_f64();
    }
}
