//! The head behind a chip's pins: the stages, the laser and the photodiode
//! of [`World`] driven by pin levels and sampled at conversion instants, for
//! the virtual STM32F405 board (`tests/chip/board/`), which runs the
//! unmodified image. Nothing here knows the firmware: a stage moves because
//! a STEP line rose with its driver enabled, the light follows the laser
//! enable and the chop line, and the photodiode is read when the board's
//! ADC samples it.
//!
//! The board reports pin changes as they happen, but it converts lazily:
//! the samples of a stretch of time are asked for after the changes that
//! followed them may have arrived. Changes therefore wait in a queue and are
//! applied in time order as the samples' instants pass them.

use super::world::World;
use super::SimConfig;
use std::collections::VecDeque;

/// What a pin of the reference board is wired to (`firmware/src/bin/head/chip/pins.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wire {
    Step(usize),
    Dir(usize),
    EnableN(usize),
    Gain(usize),
    LaserEnable,
    /// The laser's modulation input (TIM3 CH1).
    Chop,
}

/// The outputs the plant listens to.
pub const WIRING: [(&str, Wire); 13] = [
    ("PA6", Wire::Chop),
    ("PB0", Wire::LaserEnable),
    ("PB1", Wire::Gain(0)),
    ("PB2", Wire::Gain(1)),
    ("PC0", Wire::Step(0)),
    ("PC1", Wire::Dir(0)),
    ("PC2", Wire::EnableN(0)),
    ("PC4", Wire::Step(1)),
    ("PC5", Wire::Dir(1)),
    ("PC6", Wire::EnableN(1)),
    ("PC8", Wire::Step(2)),
    ("PC9", Wire::Dir(2)),
    ("PC10", Wire::EnableN(2)),
];

/// The home switches' lines, per axis: normally closed to ground, so high
/// (open) when pressed.
pub const SWITCHES: [&str; 3] = ["PC3", "PC7", "PC11"];

/// The photodiode's input on the reference board.
pub const PHOTODIODE: &str = "PA1";

/// A pin's change, waiting for time to reach it.
#[derive(Debug, Clone, Copy)]
struct Change {
    t: f64,
    wire: Wire,
    high: bool,
}

pub struct Plant {
    world: World,
    queue: VecDeque<Change>,
    chop: bool,
    /// The amplifier's output (V) at `amp_t` (s).
    amp_v: f64,
    amp_t: f64,
    /// The photocurrent (A) the light gives at the present positions with
    /// the laser on, recomputed when a stage moves.
    lit_a: Option<f64>,
    bits: u8,
}

impl Plant {
    /// A head as `sim` describes it, converted at `bits` bits, its stages
    /// where they powered up: at `power_up` (degrees) if given.
    pub fn new(sim: &SimConfig, bits: u8, power_up: Option<[f32; 3]>) -> Self {
        let mut world = World::new(sim.machine, sim);
        if let Some(deg) = power_up {
            world.steps = [0, 1, 2].map(|i| gonio_firmware::units::deg_to_steps(&sim.machine.axes[i], deg[i]));
        }
        let t = world.t_s;
        Plant {
            world,
            queue: VecDeque::new(),
            chop: false,
            amp_v: 0.0,
            amp_t: t,
            lit_a: None,
            bits,
        }
    }

    /// The wire of a pin name (`"PC0"`), if the plant listens to it.
    pub fn wire(pin: &str) -> Option<Wire> {
        WIRING.iter().find(|(p, _)| *p == pin).map(|&(_, w)| w)
    }

    /// `wire` went to `high` at `t` seconds. Changes arrive in time order.
    pub fn set(&mut self, t: f64, wire: Wire, high: bool) {
        self.queue.push_back(Change { t, wire, high });
    }

    /// The home switches' lines at `t` (true: open, the switch pressed).
    pub fn switches(&mut self, t: f64) -> [bool; 3] {
        self.run_to(t);
        [0, 1, 2].map(|i| self.world.home_pressed(i))
    }

    /// The codes of conversions sampled at `t0 + k·dt` seconds, k < n,
    /// appended to `out`.
    pub fn convert(&mut self, t0: f64, dt: f64, n: usize, out: &mut Vec<u16>) {
        for k in 0..n {
            let t = t0 + k as f64 * dt;
            self.run_to(t);
            let code = self.world.code(self.amp_v, t, self.bits);
            out.push(code);
        }
    }

    /// Applies the changes up to `t`, the amplifier following the light
    /// between them.
    fn run_to(&mut self, t: f64) {
        while let Some(c) = self.queue.front().copied().filter(|c| c.t <= t) {
            self.queue.pop_front();
            self.settle(c.t);
            self.apply(c);
        }
        self.settle(t);
    }

    /// The amplifier's first-order response to the light as it is, up to `t`.
    fn settle(&mut self, t: f64) {
        if t <= self.amp_t {
            return;
        }
        let target = self.world.transimpedance() * (self.light_a() + self.world.photodiode.ambient_a);
        let decay = (-(t - self.amp_t) / self.world.photodiode.tau_s).exp();
        self.amp_v = target + (self.amp_v - target) * decay;
        self.amp_t = t;
    }

    fn light_a(&mut self) -> f64 {
        if !(self.world.laser && self.chop) {
            return 0.0;
        }
        let lit = match self.lit_a {
            Some(a) => a,
            None => {
                let a = self.world.optical_a(&self.world.motors());
                self.lit_a = Some(a);
                a
            }
        };
        lit * self.world.photodiode.laser_factor(self.amp_t)
    }

    fn apply(&mut self, c: Change) {
        let w = &mut self.world;
        w.t_s = w.t_s.max(c.t);
        match c.wire {
            Wire::Step(i) => {
                if c.high {
                    w.step_edge(i);
                    self.lit_a = None;
                }
            }
            Wire::Dir(i) => w.dir_positive[i] = c.high,
            Wire::EnableN(i) => w.enable_n[i] = c.high,
            Wire::Gain(b) => w.gain_bits[b] = c.high,
            Wire::LaserEnable => w.set_laser(c.high),
            Wire::Chop => self.chop = c.high,
        }
    }
}
