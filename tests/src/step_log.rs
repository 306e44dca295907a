//! The step executor against a clock that jumps from event to event, with
//! pins that log every edge: the host model of the step-timer interrupt used
//! by the motion tests and the motion benchmark.

use embedded_hal::digital::{ErrorType, OutputPin};
use gonio_firmware::motion::executor::Executor;
use std::cell::{Cell, RefCell};
use std::convert::Infallible;
use std::rc::Rc;

/// One pin edge: which pin, when (ticks or ns, per the clock), rising or not.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    pub pin: &'static str,
    pub index: usize,
    pub at: u64,
    pub high: bool,
}

/// A shared clock and the log of every edge, in time order.
#[derive(Clone, Default)]
pub struct Scope {
    pub clock: Rc<Cell<u64>>,
    pub edges: Rc<RefCell<Vec<Edge>>>,
}

impl Scope {
    pub fn pin(&self, pin: &'static str, index: usize) -> LogPin {
        LogPin {
            pin,
            index,
            scope: self.clone(),
        }
    }

    /// Rising edges of one pin.
    pub fn rises(&self, pin: &'static str, index: usize) -> Vec<u64> {
        self.edges
            .borrow()
            .iter()
            .filter(|e| e.pin == pin && e.index == index && e.high)
            .map(|e| e.at)
            .collect()
    }

    /// Pulse widths (rise to fall) of one pin.
    pub fn widths(&self, pin: &'static str, index: usize) -> Vec<u64> {
        let e = self.edges.borrow();
        let mine: Vec<&Edge> = e.iter().filter(|e| e.pin == pin && e.index == index).collect();
        mine.windows(2)
            .filter(|w| w[0].high && !w[1].high)
            .map(|w| w[1].at - w[0].at)
            .collect()
    }
}

/// An output pin that logs its edges against the scope's clock.
pub struct LogPin {
    pin: &'static str,
    index: usize,
    scope: Scope,
}

impl ErrorType for LogPin {
    type Error = Infallible;
}

impl LogPin {
    fn log(&mut self, high: bool) {
        let at = self.scope.clock.get();
        self.scope.edges.borrow_mut().push(Edge {
            pin: self.pin,
            index: self.index,
            at,
            high,
        });
    }
}

impl OutputPin for LogPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.log(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.log(true);
        Ok(())
    }
}

/// An executor on three logging STEP pins.
pub fn executor(scope: &Scope, pulse_ticks: u64) -> Executor<LogPin> {
    Executor::new([0, 1, 2].map(|i| scope.pin("step", i)), pulse_ticks)
}

/// Runs the executor to the end; the interrupt takes `isr_ticks` to service,
/// so an event due while the previous one is handled waits. The clock reads
/// `origin + tick · tick_scale`. Returns the number of interrupts.
pub fn run(exec: &mut Executor<LogPin>, scope: &Scope, origin: u64, tick_scale: u64, isr_ticks: u64) -> u64 {
    let (mut next, mut busy_until, mut fires) = (exec.start(), 0u64, 0u64);
    while let Some(t) = next {
        let now = (t as u64).max(busy_until);
        scope.clock.set(origin + now * tick_scale);
        next = exec.fire(now.min(u32::MAX as u64) as u32);
        busy_until = now + isr_ticks;
        fires += 1;
    }
    fires
}
