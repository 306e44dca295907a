//! Simulated time for the firmware's futures, and the executor that polls
//! them.
//!
//! Virtual hardware advances the time in slices of at most [`SLICE_S`],
//! returning `Pending` after each, so that a watch raced against an
//! operation (the firmware's serve loop) is polled between slices, as the
//! chip's executor polls it on every interrupt. Whatever watches for a
//! moment (a host timeout, a scripted frame, the E-STOP) registers it with
//! [`World::wake`], and time stops there exactly: a stop is seen when it
//! happens, not at the end of a slice. When nothing advances the time (the
//! head at rest), the link waits: on the in-process link for the host's
//! next frame, the host's thinking taking no simulated time (unless paced:
//! then the wall clock stands in for the time to the next deadline); on a
//! pseudo-terminal, whose host is another program, with the wall clock
//! standing in; for the next scripted frame in tests.

use super::world::World;
use gonio_firmware::hw::{Sentry, Wake};
use std::cell::RefCell;
use std::future::Future;
use std::pin::pin;
use std::rc::Rc;
use std::task::{Context, Poll, Waker};
use std::time::Duration;

type Shared = Rc<RefCell<World>>;

/// Longest stretch of simulated time between two looks at the watch (s).
pub const SLICE_S: f64 = 1e-3;

/// A paced head sleeps once this much wall-clock time is owed (s).
const PACE_SLEEP_S: f64 = 2e-3;

/// Where the current slice ends: a slice on, or at the next wake-up; where
/// the time is, if something has run it in this poll already.
pub fn slice_end(w: &World) -> f64 {
    if w.busy {
        return w.t_s;
    }
    let end = w.t_s + SLICE_S;
    w.wake_at.filter(|&t| t > w.t_s).map_or(end, |t| t.min(end))
}

/// Ends a slice at `t`: the time is there, and the head was busy. A paced
/// head takes the slice on the wall clock too.
pub fn advance_to(world: &Shared, t: f64) {
    let mut w = world.borrow_mut();
    let dt = t - w.t_s;
    w.t_s = w.t_s.max(t);
    if w.wake_at.is_some_and(|at| at <= w.t_s) {
        w.wake_at = None;
    }
    w.busy = true;
    drop(w);
    owe(world, dt);
}

/// A paced head owes the wall clock `dt` seconds of simulated time that ran
/// (by [`advance_to`], or by hardware that moved the time itself event by
/// event within a slice); the debt is slept in pieces of a few milliseconds
/// (a sleep per slice would cost more than the slice).
pub fn owe(world: &Shared, dt: f64) {
    let mut w = world.borrow_mut();
    w.pace_owed_s += dt.max(0.0) * w.pace as f64;
    if w.pace_owed_s >= PACE_SLEEP_S {
        let owed = std::mem::take(&mut w.pace_owed_s);
        drop(w);
        std::thread::sleep(Duration::from_secs_f64(owed));
    }
}

/// Lets `dt` seconds pass, slice by slice. Raced against something else
/// that runs the time (a move's stall timeout against the move), it only
/// watches the time go by: time is advanced once per poll, by whoever is
/// polled first.
pub async fn elapse(world: &Shared, dt: f64) {
    let end = world.borrow().t_s + dt;
    loop {
        let to = {
            let w = world.borrow();
            if w.t_s >= end {
                return;
            }
            (!w.busy).then(|| slice_end(&w).min(end))
        };
        if let Some(to) = to {
            advance_to(world, to);
        }
        yield_once().await;
    }
}

/// Returns `Pending` once: the executor polls again at once.
async fn yield_once() {
    let mut done = false;
    std::future::poll_fn(|_| {
        if done {
            Poll::Ready(())
        } else {
            done = true;
            Poll::Pending
        }
    })
    .await
}

/// Polls without the time moving before [`run`] calls the head stuck.
const STUCK_POLLS: u32 = 10_000_000;

thread_local! {
    /// Set when a future of the head wakes itself (the firmware yields to the
    /// executor in long computations, `embassy_futures::yield_now`): the head
    /// has work to go on with, so a link at rest must not block.
    static WOKEN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The waker [`run`] polls with: it records a self-wake in [`WOKEN`].
struct SelfWake;

impl std::task::Wake for SelfWake {
    fn wake(self: std::sync::Arc<Self>) {
        WOKEN.with(|w| w.set(true));
    }
    fn wake_by_ref(self: &std::sync::Arc<Self>) {
        WOKEN.with(|w| w.set(true));
    }
}

/// Polls `f` to completion. Nothing in the simulated head sleeps on a
/// waker: what has nothing to do returns `Pending`, what yields wakes itself
/// (and is polled again at once), and what waits for the outside world (a
/// link at rest) blocks inside its poll. A head that waits
/// for time while nothing runs it (a firmware bug: the chip would sleep for
/// ever too) is reported instead of spinning.
pub fn run<F: Future>(world: &Shared, f: F) -> F::Output {
    let mut f = pin!(f);
    let waker = Waker::from(std::sync::Arc::new(SelfWake));
    let mut cx = Context::from_waker(&waker);
    let (mut last_t, mut still) = (f64::NAN, 0u32);
    loop {
        world.borrow_mut().busy = false;
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
        let t = world.borrow().t_s;
        still = if t == last_t { still + 1 } else { 0 };
        last_t = t;
        assert!(
            still < STUCK_POLLS,
            "simulated head stuck at t = {t} s: it waits for time that nothing runs"
        );
    }
}

/// Whether the head has work this poll: it ran the time, or a future of it
/// woke itself (a self-wake counts once).
pub fn busy(w: &World) -> bool {
    w.busy || WOKEN.with(|f| f.replace(false))
}

/// What a link with nothing to read does next.
pub enum Idle {
    /// The head is busy: return `Pending` and look again next poll.
    Busy,
    /// At rest: wait (for real) at most this long, or for ever.
    Wait(Option<Duration>),
}

/// See [`Idle`]; a wait that times out moves the time on to the wake-up.
pub fn idle(world: &Shared) -> Idle {
    let w = world.borrow();
    if busy(&w) {
        return Idle::Busy;
    }
    Idle::Wait(w.wake_at.map(|t| Duration::from_secs_f64((t - w.t_s).max(0.0))))
}

/// The wait of [`idle`] ran out: time jumps to the wake-up.
pub fn timed_out(world: &Shared) {
    let mut w = world.borrow_mut();
    if let Some(t) = w.wake_at.take() {
        w.t_s = w.t_s.max(t);
    }
}

/// The E-STOP input and the head's timer in simulated time.
pub struct SimSentry {
    pub(crate) world: Shared,
}

impl Sentry for SimSentry {
    fn estop_open(&mut self) -> bool {
        self.world.borrow().estop_open()
    }

    fn now_us(&self) -> u64 {
        self.world.borrow().now_us()
    }

    fn alive(&mut self) {
        let mut w = self.world.borrow_mut();
        let t = w.t_s;
        if let Some(last) = w.alive_at_s {
            w.alive_gap_max_s = w.alive_gap_max_s.max(t - last);
        }
        w.alive_at_s = Some(t);
    }

    async fn until(&mut self, deadline_us: Option<u64>, estop: bool) -> Wake {
        std::future::poll_fn(|_| {
            let mut w = self.world.borrow_mut();
            if estop && w.estop_open() {
                return Poll::Ready(Wake::EStop);
            }
            if deadline_us.is_some_and(|d| w.now_us() >= d) {
                return Poll::Ready(Wake::Deadline);
            }
            if let Some(d) = deadline_us {
                w.wake(d as f64 * 1e-6);
            }
            if let Some(t) = w.estop_at.filter(|_| estop) {
                w.wake(t);
            }
            Poll::Pending
        })
        .await
    }
}
