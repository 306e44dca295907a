//! Virtual peripherals implementing the firmware's hardware traits over the
//! shared [`World`]. Time is simulated: a delay, a chop period or a move
//! advances it in slices ([`super::clock`]), so that what the firmware
//! watches meanwhile (the link, the E-STOP, the host timer) is looked at
//! as often as on the chip.

use super::clock::{advance_to, elapse, owe, slice_end};
use super::faults::HardwareFault;
use super::world::{Motors, World};
use gonio_firmware::hw::{AdcStream, Board, ChopTiming, Clock, Hardware, Overrun, QueueFull, StepBlock, StepTimer};
use gonio_firmware::motion::blocks;
use gonio_firmware::motion::executor::Executor;
use gonio_firmware::units;
use gonio_shared::Axis;
use std::cell::RefCell;
use std::convert::Infallible;
use std::rc::Rc;
use std::task::Poll;

type Shared = Rc<RefCell<World>>;

pub struct SimBoard;

impl Board for SimBoard {
    type Out = SimPin;
    type In = SimSwitch;
    type Adc = SimAdc;
    type Steps = SimSteps;
    type Delay = SimDelay;
    type Clock = SimClock;
}

/// What an output pin is wired to.
#[derive(Clone, Copy)]
enum Role {
    Step(usize),
    Dir(usize),
    EnableN(usize),
    Gain(usize),
    Laser,
}

pub struct SimPin {
    world: Shared,
    role: Role,
}

impl embedded_hal::digital::ErrorType for SimPin {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.set(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.set(true);
        Ok(())
    }
}

impl SimPin {
    fn set(&mut self, high: bool) {
        let mut w = self.world.borrow_mut();
        match self.role {
            Role::Step(i) => {
                if high {
                    w.step_edge(i);
                }
            }
            Role::Dir(i) => w.dir_positive[i] = high,
            Role::EnableN(i) => w.enable_n[i] = high,
            Role::Gain(b) => w.gain_bits[b] = high,
            Role::Laser => w.set_laser(high),
        }
    }
}

pub struct SimSwitch {
    world: Shared,
    axis: usize,
}

impl embedded_hal::digital::ErrorType for SimSwitch {
    type Error = Infallible;
}

impl embedded_hal::digital::InputPin for SimSwitch {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.world.borrow().home_pressed(self.axis))
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        self.is_high().map(|h| !h)
    }
}

/// The chop timer, the amplifier and the ADC.
pub struct SimAdc {
    world: Shared,
    /// Amplifier output state (V), for its first-order response.
    amp_v: f64,
}

impl AdcStream for SimAdc {
    /// The reference clock tree's APB1 timer clock (168 MHz / 4 × 2).
    fn timer_hz(&self) -> u32 {
        84_000_000
    }

    const BITS: u8 = 12;

    fn start(&mut self, timing: ChopTiming) {
        self.world.borrow_mut().chop = Some(timing);
    }

    fn stop(&mut self) {
        self.world.borrow_mut().chop = None;
    }

    async fn next_period(&mut self, out: &mut [u16]) -> Result<(), Overrun> {
        let Some(period) = self.begin_period() else {
            out.fill(0);
            return Err(Overrun);
        };
        elapse(&self.world, period.dt * out.len() as f64).await;
        self.convert(&period, out);
        if period.lost {
            return Err(Overrun);
        }
        Ok(())
    }
}

/// A chop period as it began: its timing, the faults it suffers, and where
/// the motors were.
struct Period {
    t0: f64,
    /// Time between two conversions (s).
    dt: f64,
    saturated: bool,
    dead: bool,
    lost: bool,
    laser: bool,
    laser_factor: f64,
    motors: Motors,
}

impl SimAdc {
    /// Starts a chop period now; `None` with the chop stopped.
    fn begin_period(&mut self) -> Option<Period> {
        let mut w = self.world.borrow_mut();
        let timing = w.chop?;
        let lost = w.faults.take_overrun(w.moves);
        w.period_edges.clear();
        Some(Period {
            t0: w.t_s,
            dt: timing.ticks_per_sample as f64 / self.timer_hz() as f64,
            saturated: w.faults.active(w.moves, |f| *f == HardwareFault::AdcSaturated),
            dead: w.faults.active(w.moves, |f| *f == HardwareFault::LaserDead),
            lost,
            laser: w.laser,
            laser_factor: w.photodiode.laser_factor(w.t_s),
            motors: w.motors(),
        })
    }

    /// The codes of a period that has run: each conversion sees the
    /// photodiode's signal with the motors where they were at its instant
    /// (the steps taken meanwhile replayed), through the amplifier.
    fn convert(&mut self, p: &Period, out: &mut [u16]) {
        let mut w = self.world.borrow_mut();
        let edges = std::mem::take(&mut w.period_edges);
        let m = out.len();
        let gain = w.transimpedance();
        let signal = |w: &World, motors: &Motors| {
            if p.laser && !p.dead {
                w.optical_a(motors) * p.laser_factor
            } else {
                0.0
            }
        };
        let mut motors = p.motors;
        let mut sig_a = signal(&w, &motors);
        let mut next = edges.iter().peekable();
        let alpha = 1.0 - (-p.dt / w.photodiode.tau_s).exp();
        let full = ((1u32 << <Self as AdcStream>::BITS) - 1) as u16;
        let mut seen = Vec::new();
        for (k, o) in out.iter_mut().enumerate() {
            let t = p.t0 + k as f64 * p.dt;
            let mut moved = false;
            while let Some(e) = next.next_if(|e| e.t <= t) {
                motors.step(e);
                moved = true;
            }
            if moved {
                sig_a = signal(&w, &motors);
            }
            if w.sample_log.is_some() {
                seen.push((t, w.motor_angles(&motors)));
            }
            let on = if k < m / 2 { 1.0 } else { 0.0 };
            let target = gain * (sig_a * on + w.photodiode.ambient_a);
            self.amp_v += (target - self.amp_v) * alpha;
            *o = if p.saturated {
                full
            } else {
                w.code(self.amp_v, t, <Self as AdcStream>::BITS)
            };
        }
        if let Some(log) = w.sample_log.as_mut() {
            log.extend(seen);
        }
    }
}

/// The step timer: the firmware's executor on virtual STEP pins, run
/// against simulated time from event to event, one time slice per poll;
/// every rising edge moves the motor (unless its driver is disabled or an
/// end stop blocks it).
pub struct SimSteps {
    world: Shared,
    exec: Executor<SimPin>,
    /// Simulated time (s) of the executor's tick 0, and its next event.
    origin_s: f64,
    next: Option<u32>,
    /// This move never ends (an injected stall).
    stalled: bool,
    /// Blocks queued for the next move: the chip plans them before it
    /// starts ([`blocks::plan_s`]).
    queued: usize,
}

impl SimSteps {
    fn tick_time(&self, tick: u32) -> f64 {
        self.origin_s + tick as f64 / Self::TICK_HZ as f64
    }
}

impl StepTimer for SimSteps {
    const TICK_HZ: u32 = 1_000_000;

    fn push(&mut self, axis: Axis, block: StepBlock) -> Result<(), QueueFull> {
        self.exec.push(axis, block)?;
        self.queued += usize::from(block.count > 0);
        Ok(())
    }

    fn start(&mut self) {
        let mut w = self.world.borrow_mut();
        if w.laser {
            w.moves += 1;
        }
        if w.chop.is_some() {
            w.moves_with_conversions += 1;
        }
        self.stalled = w.faults.take_stall(w.moves);
        // The first step waits for the chip to have planned the move.
        self.origin_s = w.t_s + blocks::plan_s(std::mem::take(&mut self.queued));
        drop(w);
        self.next = self.exec.start();
    }

    async fn finished(&mut self) -> [u32; 3] {
        std::future::poll_fn(|_| {
            if self.stalled {
                // The timer never finishes: the firmware's watchdog on the
                // move (its delay runs the time) has to give up on it.
                return Poll::Pending;
            }
            let (limit, start) = {
                let w = self.world.borrow();
                (slice_end(&w), w.t_s)
            };
            while let Some(t) = self.next {
                let at = self.tick_time(t);
                if at > limit {
                    break;
                }
                {
                    let mut w = self.world.borrow_mut();
                    w.t_s = w.t_s.max(at);
                    w.edge_at = Some(at);
                }
                self.next = self.exec.fire(t);
                self.world.borrow_mut().edge_at = None;
            }
            // The events ran the time themselves: a paced head owes it.
            let ran = self.world.borrow().t_s - start;
            owe(&self.world, ran);
            if self.next.is_none() {
                return Poll::Ready(self.exec.emitted());
            }
            advance_to(&self.world, limit);
            Poll::Pending
        })
        .await
    }

    fn emitted(&self) -> [u32; 3] {
        self.exec.emitted()
    }

    fn brake(&mut self, brake_ticks: [f32; 3]) {
        if self.next.is_some() {
            self.next = self.exec.brake(brake_ticks);
        }
    }

    fn clear(&mut self) {
        self.exec.clear();
        self.queued = 0;
        self.next = None;
        self.stalled = false;
    }
}

pub struct SimDelay {
    world: Shared,
}

impl embedded_hal_async::delay::DelayNs for SimDelay {
    async fn delay_ns(&mut self, ns: u32) {
        elapse(&self.world, ns as f64 * 1e-9).await;
    }
}

pub struct SimClock {
    world: Shared,
}

impl Clock for SimClock {
    fn now_us(&self) -> u64 {
        self.world.borrow().now_us()
    }
}

/// Wires a firmware `Hardware` set to the virtual world.
pub fn hardware(world: &Shared) -> Hardware<SimBoard> {
    let driver = world.borrow().cfg.driver;
    let pin = |role| SimPin {
        world: world.clone(),
        role,
    };
    Hardware {
        dir: [0, 1, 2].map(|i| pin(Role::Dir(i))),
        enable_n: [0, 1, 2].map(|i| pin(Role::EnableN(i))),
        home: [0, 1, 2].map(|axis| SimSwitch {
            world: world.clone(),
            axis,
        }),
        gain: [0, 1].map(|b| pin(Role::Gain(b))),
        laser: pin(Role::Laser),
        adc: SimAdc {
            world: world.clone(),
            amp_v: 0.0,
        },
        steps: SimSteps {
            world: world.clone(),
            exec: Executor::new(
                [0, 1, 2].map(|i| pin(Role::Step(i))),
                units::step_pulse_ticks(&driver, SimSteps::TICK_HZ),
            ),
            origin_s: 0.0,
            next: None,
            stalled: false,
            queued: 0,
        },
        delay: SimDelay { world: world.clone() },
        clock: SimClock { world: world.clone() },
    }
}
