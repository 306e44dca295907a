//! The simulated head: the firmware core (`gonio_firmware::Head`) driven by
//! virtual hardware in simulated time. Moves and integrations take zero wall
//! time, so a six-hour scan runs in seconds, yet every sample comes out of
//! the firmware's own motion, auto-range and demodulation code.

mod board;
pub mod clock;
pub mod faults;
mod faulty_link;
mod frames;
mod imperfections;
#[cfg(feature = "in-process")]
mod inproc;
mod optics;
pub mod plant;
mod pty;
mod world;

pub use board::SimBoard;
pub use frames::{Cue, FrameHead, Sent};
pub use imperfections::Imperfections;
#[cfg(feature = "in-process")]
pub use inproc::spawn_in_process;
pub use optics::{seen_brdf, Photodiode};
pub use pty::serve_pty;
pub use world::World;

use gonio_brdf::Specimen;
use gonio_firmware::config::{HeadConfig, REFERENCE};
use gonio_firmware::head::HeadInfo;
use gonio_firmware::Head;
use gonio_shared::PROTOCOL_VERSION;
use std::cell::RefCell;
use std::rc::Rc;

/// What the simulated head is made of.
#[derive(Debug, Clone)]
pub struct SimConfig {
    pub material: Specimen,
    /// Side of the square sample (mm; `None`: larger than any footprint):
    /// at grazing incidence a footprint that overfills it loses light.
    pub sample_mm: Option<f64>,
    pub photodiode: Photodiode,
    /// Seed of the noise generator: the same seed gives the same samples.
    pub seed: u64,
    /// Protocol version the head claims (tests of the mismatch report).
    pub protocol_version: u16,
    /// Dust specks on the sample (see [`World::defect`]).
    pub dust: Vec<gonio_shared::Geometry>,
    /// The head's clock at power-up (s): a run that follows another on the
    /// same lab day (the reference plate, then the sample) continues its time,
    /// and with it the laser's drift.
    pub clock_start_s: f64,
    /// What is on the sample holder: the operator's hand in the simulation.
    pub mount: Mount,
    /// Faults to suffer on the link and in the hardware.
    pub faults: faults::Faults,
    /// Angle, gain, stray-light and plate errors the firmware does not know
    /// of (boxed: most heads have none, and the configuration stays small).
    pub imperfections: Box<Imperfections>,
    /// Wall-clock seconds per simulated second while the head works (1: a
    /// move takes as long as on the reference head), for tests that act on
    /// the head from outside in the middle of a move; 0 (the default) runs
    /// as fast as it can.
    pub pace: f32,
    /// The head's machine: gearing, travel, speeds, optics (the reference
    /// head's unless a test builds another).
    pub machine: HeadConfig,
}

/// Which target sits on the sample holder. Shared between the host (the
/// operator swapping the sample for the reference plate) and the simulated
/// head, which stays powered and homed meanwhile.
#[derive(Debug, Clone, Default)]
pub struct Mount(std::sync::Arc<std::sync::atomic::AtomicBool>);

/// Hemispherical reflectance of the simulated head's reference plate
/// (Spectralon), as its certificate states it...
pub const PLATE_RHO: f64 = 0.99;
/// ...with this standard uncertainty.
pub const PLATE_RHO_U: f64 = 0.005;

impl Mount {
    pub fn set_plate(&self, plate: bool) {
        self.0.store(plate, std::sync::atomic::Ordering::SeqCst);
    }

    pub fn plate(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::SeqCst)
    }
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            material: Specimen::default(),
            sample_mm: None,
            photodiode: Photodiode::default(),
            seed: 1,
            protocol_version: PROTOCOL_VERSION,
            dust: Vec::new(),
            clock_start_s: 0.0,
            mount: Mount::default(),
            faults: faults::Faults::default(),
            imperfections: Box::default(),
            pace: 0.0,
            machine: REFERENCE,
        }
    }
}

impl SimConfig {
    /// The configuration, refused where a user's value makes no head: a
    /// drift of half the laser's power or more, a clock before power-up, a
    /// pace beyond 100 wall-clock seconds per simulated second.
    pub fn checked(self) -> anyhow::Result<Self> {
        let drift = self.photodiode.laser_drift;
        if !(0.0..0.5).contains(&drift) {
            anyhow::bail!("--laser-drift {drift} must be in [0, 0.5)");
        }
        if !(self.clock_start_s.is_finite() && self.clock_start_s >= 0.0) {
            anyhow::bail!("--clock-start-s must be a finite time ≥ 0");
        }
        if !(self.pace.is_finite() && (0.0..=100.0).contains(&self.pace)) {
            anyhow::bail!(
                "--pace {}: wall-clock seconds per simulated second, from 0 (as fast as it can) to 100",
                self.pace
            );
        }
        Ok(self)
    }
}

/// The E-STOP input and timer of a head on `world`.
pub(crate) fn sentry(world: &Rc<RefCell<World>>) -> clock::SimSentry {
    clock::SimSentry { world: world.clone() }
}

/// Builds a firmware head on a fresh virtual world: the serve loop's head,
/// or one a test or benchmark drives directly ([`clock::run`]).
pub fn build(cfg: &SimConfig) -> (Head<board::SimBoard>, Rc<RefCell<World>>) {
    let world = Rc::new(RefCell::new(World::new(cfg.machine, cfg)));
    let hw = board::hardware(&world);
    let info = HeadInfo {
        board: "simulated STM32F405 head",
        serial: heapless::String::try_from("SIM-0001").unwrap_or_default(),
        simulated: true,
        protocol_version: cfg.protocol_version,
    };
    let mut head = Head::new(cfg.machine, hw, info);
    head.prepare();
    let expected_hz = gonio_firmware::config::CRYSTAL_HZ;
    let failed = |khz: &u32| !gonio_firmware::crystal::matches(khz.saturating_mul(1000), expected_hz);
    if let Some(measured_khz) = cfg.faults.crystal_khz().filter(failed) {
        let expected_khz = expected_hz / 1000;
        head.inhibit_laser(gonio_shared::Fault::Crystal {
            measured_khz,
            expected_khz,
        });
    }
    (head, world)
}
