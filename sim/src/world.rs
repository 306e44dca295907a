//! The physical state of the virtual head: simulated time, motor positions,
//! pin levels, the chop timer, and the photodiode front end.

use super::optics::Photodiode;
use super::SimConfig;
use gonio_brdf::{Directions, Material, Specimen};
use gonio_firmware::config::HeadConfig;
use gonio_firmware::hw::ChopTiming;
use gonio_firmware::units;
use gonio_shared::Geometry;
use rand::rngs::StdRng;
use rand::SeedableRng;

/// A dust speck reflects this many times the material's value...
pub const DUST_FACTOR: f64 = 5.0;
/// ...within this angle of its direction pair.
const DUST_TOLERANCE_DEG: f64 = 0.05;

/// Mechanical end stops lie this far beyond the home switch and the soft limit.
const HARD_STOP_MARGIN_DEG: f32 = 3.0;

/// One motor step: when, which axis, its direction and the change of
/// position (0 against an end stop).
#[derive(Debug, Clone, Copy)]
pub struct Edge {
    pub t: f64,
    pub axis: usize,
    pub dir: i32,
    pub change: i32,
}

/// Where the motors are: microstep positions and the direction of each
/// one's last step (the side backlash leaves the load on).
#[derive(Debug, Clone, Copy)]
pub struct Motors {
    pub steps: [i32; 3],
    pub last_step: [i32; 3],
}

impl Motors {
    /// After `e`.
    pub fn step(&mut self, e: &Edge) {
        self.steps[e.axis] += e.change;
        self.last_step[e.axis] = e.dir;
    }
}

pub struct World {
    pub cfg: HeadConfig,
    /// Simulated time (s).
    pub t_s: f64,
    /// True motor positions (microsteps); unknown to the firmware until homed.
    pub steps: [i32; 3],
    /// Microstep range the mechanics allow per axis (end stops).
    stops: [(i32, i32); 3],
    pub dir_positive: [bool; 3],
    /// Direction of each motor's last step (±1): the side backlash leaves the load on.
    last_step: [i32; 3],
    /// What the head gets wrong (angles, gains, stray light, the plate).
    pub imperfections: super::Imperfections,
    pub enable_n: [bool; 3],
    pub gain_bits: [bool; 2],
    pub laser: bool,
    /// Running chop timer and the time its current period started.
    pub chop: Option<ChopTiming>,
    pub material: Specimen,
    /// Side of the square sample (mm): a beam whose footprint overfills it
    /// loses the light that misses (`None`: a sample larger than any
    /// footprint).
    pub sample_mm: Option<f64>,
    /// The reference plate (Lambertian, `PLATE_RHO`) and whether it is mounted.
    pub plate: Specimen,
    pub mount: super::Mount,
    pub photodiode: Photodiode,
    /// Dust specks: direction pairs (θi, θo, |Δφ| in degrees) that reflect
    /// [`DUST_FACTOR`] times the material's value.
    pub dust: Vec<Geometry>,
    pub rng: StdRng,
    /// Injected faults (shared with the host and later heads).
    pub faults: super::faults::Faults,
    /// Moves the step timer has run with the laser on: from one scan point
    /// to the next (homing and the first approach are not counted), the
    /// clock of the hardware faults.
    pub moves: u64,
    /// Times the laser was switched on.
    pub laser_ons: u64,
    /// Something advanced the time in the current poll of the head (set by
    /// [`super::clock::elapse`] and the step timer, cleared by
    /// [`super::clock::run`]): a link that finds nothing to read then
    /// returns at once instead of waiting.
    pub busy: bool,
    /// The earliest time (s) something watches for (a host timeout, a
    /// scripted frame, the E-STOP): time advances to it exactly.
    pub wake_at: Option<f64>,
    /// The E-STOP input reads open (pressed or wire cut)...
    pub estop: bool,
    /// ...or will from this time on (s), as a test scripts it.
    pub estop_at: Option<f64>,
    /// Every rising STEP edge (axis, time in s) and every change of the
    /// laser enable (time, level), when a test records them.
    pub step_log: Option<Vec<(usize, f64)>>,
    /// The true motor angles (degrees) at every ADC sample (time, angles),
    /// when a test records them.
    pub sample_log: Option<Vec<(f64, [f64; 3])>>,
    /// The time of the step event being fired, which may lie before `t_s`
    /// when the conversions ran the time first in this poll.
    pub edge_at: Option<f64>,
    /// The motor steps taken while the current chop period ran: the ADC
    /// sees the positions at each of its samples.
    pub period_edges: Vec<Edge>,
    pub laser_log: Option<Vec<(f64, bool)>>,
    /// See [`super::SimConfig::pace`], and the wall-clock time owed to it.
    pub pace: f32,
    pub pace_owed_s: f64,
    /// When the serve loop last showed it was alive, and the longest time
    /// it went without (s): what the chip's watchdog watches.
    pub alive_at_s: Option<f64>,
    /// Moves started while the chop and the conversions ran: on the chip the
    /// ADC's DMA ring overruns during them.
    pub moves_with_conversions: u32,
    pub alive_gap_max_s: f64,
}

impl World {
    /// The target on the holder.
    pub fn target(&self) -> &Specimen {
        if self.mount.plate() {
            &self.plate
        } else {
            &self.material
        }
    }

    pub fn new(cfg: HeadConfig, sim: &SimConfig) -> Self {
        // Power-up: the stages are wherever they were left.
        let start = [12.3f32, -4.0, 33.0];
        let steps = [0, 1, 2].map(|i| units::deg_to_steps(&cfg.axes[i], start[i]));
        let stops = [0, 1, 2].map(|i| {
            let a = &cfg.axes[i];
            (
                units::deg_to_steps(a, a.home_deg - HARD_STOP_MARGIN_DEG),
                units::deg_to_steps(a, a.max_deg + HARD_STOP_MARGIN_DEG),
            )
        });
        World {
            cfg,
            t_s: sim.clock_start_s,
            steps,
            stops,
            dir_positive: [true; 3],
            last_step: [1; 3],
            imperfections: (*sim.imperfections).clone(),
            enable_n: [true; 3],
            gain_bits: [false; 2],
            laser: false,
            chop: None,
            material: sim.material.clone(),
            sample_mm: sim.sample_mm,
            plate: Specimen::Model(
                Material::parse(gonio_brdf::ModelId::Lambert, &format!("kd={}", sim.imperfections.plate_rho)).expect("a valid Lambertian"),
            ),
            mount: sim.mount.clone(),
            photodiode: sim.photodiode.clone(),
            dust: sim.dust.clone(),
            rng: StdRng::seed_from_u64(sim.seed),
            faults: sim.faults.clone(),
            moves: 0,
            laser_ons: 0,
            busy: false,
            wake_at: None,
            estop: false,
            estop_at: None,
            step_log: None,
            sample_log: None,
            edge_at: None,
            period_edges: Vec::new(),
            laser_log: None,
            pace: sim.pace,
            pace_owed_s: 0.0,
            alive_at_s: None,
            moves_with_conversions: 0,
            alive_gap_max_s: 0.0,
        }
    }

    /// The head's clock (µs), as the firmware reads it: time stopped at a
    /// deadline of `d` µs reads `d`.
    pub fn now_us(&self) -> u64 {
        (self.t_s * 1e6).round() as u64
    }

    /// Asks time to stop at `t` (s) on its way.
    pub fn wake(&mut self, t: f64) {
        if t > self.t_s {
            self.wake_at = Some(self.wake_at.map_or(t, |w| w.min(t)));
        }
    }

    /// The E-STOP input reads open now.
    pub fn estop_open(&self) -> bool {
        self.estop || self.estop_at.is_some_and(|t| self.t_s >= t)
    }

    /// Sets the laser enable.
    pub fn set_laser(&mut self, on: bool) {
        if on && !self.laser {
            self.laser_ons += 1;
        }
        if on != self.laser {
            let t = self.t_s;
            if let Some(log) = self.laser_log.as_mut() {
                log.push((t, on));
            }
        }
        self.laser = on;
    }

    /// A rising STEP edge: one microstep in the DIR direction, if the driver
    /// is enabled and the end stop allows.
    pub fn step_edge(&mut self, axis: usize) {
        if self.enable_n[axis] {
            return;
        }
        let (lo, hi) = self.stops[axis];
        let d = if self.dir_positive[axis] { 1 } else { -1 };
        let t = self.edge_at.unwrap_or(self.t_s);
        if let Some(log) = self.step_log.as_mut() {
            log.push((axis, t));
        }
        self.last_step[axis] = d;
        let before = self.steps[axis];
        self.steps[axis] = (before + d).clamp(lo, hi);
        if self.chop.is_some() {
            self.period_edges.push(Edge {
                t,
                axis,
                dir: d,
                change: self.steps[axis] - before,
            });
        }
    }

    /// True when the home switch of an axis is pressed.
    pub fn home_pressed(&self, axis: usize) -> bool {
        use super::faults::HardwareFault::{SwitchStuckClosed, SwitchStuckOpen};
        if self.faults.active(self.moves, |f| *f == SwitchStuckOpen(axis)) {
            return false;
        }
        if self.faults.active(self.moves, |f| *f == SwitchStuckClosed(axis)) {
            return true;
        }
        self.steps[axis] <= units::deg_to_steps(&self.cfg.axes[axis], self.cfg.axes[axis].home_deg)
    }

    /// True stage angles (degrees).
    pub fn angles(&self) -> [f64; 3] {
        self.motor_angles(&self.motors())
    }

    /// Where the motors are now.
    pub fn motors(&self) -> Motors {
        Motors {
            steps: self.steps,
            last_step: self.last_step,
        }
    }

    /// Motor angles (degrees) of positions `m`.
    pub fn motor_angles(&self, m: &Motors) -> [f64; 3] {
        [0, 1, 2].map(|i| units::steps_to_deg(&self.cfg.axes[i], m.steps[i]) as f64)
    }

    /// Angles of the loads the motors drive (degrees) with the motors at
    /// `m`: the motor's angle, the stage's zero error, and half the backlash
    /// behind the last step's direction (the load trails the motor).
    pub fn load_angles(&self, m: &Motors) -> [f64; 3] {
        let a = self.motor_angles(m);
        let im = &self.imperfections;
        [0, 1, 2].map(|i| a[i] + im.zero_offset_deg[i] - 0.5 * im.backlash_deg[i] * m.last_step[i] as f64)
    }

    /// Reflection factor at a direction pair: a speck of dust or one.
    pub fn defect(&self, d: &Directions) -> f64 {
        let (ti, to, dp) = d.angles();
        let (ti, to, dp) = (ti.to_degrees(), to.to_degrees(), dp.abs().to_degrees());
        let near = |a: f64, b: f32| (a - b as f64).abs() < DUST_TOLERANCE_DEG;
        let hit = self
            .dust
            .iter()
            .any(|g| near(ti, g.theta_i_deg) && near(to, g.theta_o_deg) && near(dp, g.dphi_deg.abs()));
        if hit {
            DUST_FACTOR
        } else {
            1.0
        }
    }

    /// Photocurrent (A) of the laser's light at nominal power with the
    /// motors at `m`: what the material sends into the detector, and stray light.
    pub fn optical_a(&self, m: &Motors) -> f64 {
        let angles = self.load_angles(m);
        self.photodiode.signal_a(self.target(), &self.cfg, angles, |d| self.defect(d)) * self.on_target(angles) + self.imperfections.stray_a
    }

    /// The share of the beam that lands on the mounted target at the true
    /// stage angles: the sample's finite size at grazing incidence; the
    /// plate is taken as large as any footprint its geometries make.
    fn on_target(&self, angles: [f64; 3]) -> f64 {
        let (Some(side), false) = (self.sample_mm, self.mount.plate()) else {
            return 1.0;
        };
        let Some(d) = gonio_brdf::Directions::from_stage(angles) else {
            return 0.0;
        };
        let theta_i = d.cos_i().clamp(-1.0, 1.0).acos().to_degrees();
        gonio_firmware::footprint::on_sample(theta_i, self.cfg.optics.beam_diameter_mm as f64, side)
    }

    /// The selected range's transimpedance (V/A), as the head truly has it.
    pub fn transimpedance(&self) -> f64 {
        let g = self.gain_index();
        self.cfg.detector.gains_v_per_a[g] as f64 * self.imperfections.gain_scale[g]
    }

    /// The code of a `bits`-bit conversion at time `t` of the amplifier's
    /// output `amp_v`: offset, pickup and noise added, quantised, clipped
    /// to the converter's range.
    pub fn code(&mut self, amp_v: f64, t: f64, bits: u8) -> u16 {
        let full = ((1u32 << bits) - 1) as f64;
        let vref = self.cfg.detector.adc_vref as f64;
        let World { photodiode, rng, .. } = self;
        let v = amp_v + photodiode.interference_v(t, rng);
        (v / vref * (full + 1.0)).round().clamp(0.0, full) as u16
    }

    pub fn gain_index(&self) -> usize {
        self.gain_bits[0] as usize | (self.gain_bits[1] as usize) << 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimConfig;
    use gonio_firmware::config::REFERENCE;

    /// At EN 1436's 88.76° a 1 mm beam draws a footprint 46 mm long: a
    /// 50 mm sample loses what overfills it, a 100 mm one nearly nothing,
    /// and the plate (taken as large as any footprint) nothing at all.
    #[test]
    fn a_footprint_that_overfills_the_sample_loses_its_light() {
        let reading = |sample_mm: Option<f64>, plate: bool| {
            let sim = SimConfig {
                sample_mm,
                ..SimConfig::default()
            };
            sim.mount.set_plate(plate);
            let w = World::new(REFERENCE, &sim);
            let angles = [88.76f32, 0.0, 1.05];
            let m = Motors {
                steps: [0, 1, 2].map(|i| units::deg_to_steps(&REFERENCE.axes[i], angles[i])),
                last_step: [1; 3],
            };
            w.optical_a(&m)
        };
        let whole = reading(None, false);
        assert!(whole > 0.0);
        let lost = 1.0 - reading(Some(50.0), false) / whole;
        let expected = 1.0 - gonio_firmware::footprint::on_sample(88.76, 1.0, 50.0);
        assert!((lost - expected).abs() < 1e-3 && lost > 0.01, "lost {lost}, expected {expected}");
        assert!(1.0 - reading(Some(100.0), false) / whole < gonio_firmware::footprint::LOST_MAX);
        assert_eq!(reading(Some(50.0), true), reading(None, true));
    }
}
