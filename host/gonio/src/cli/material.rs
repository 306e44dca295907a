//! Options shared by the commands that start a simulated head.

use anyhow::{Context, Result};
use gonio_analysis::uncertainty::HeadUncertainty;
use gonio_brdf::Specimen;
use gonio_sim::{Imperfections, SimConfig, PLATE_RHO_U};

#[derive(Debug, Clone, clap::Args)]
pub struct SimHeadArgs {
    /// Virtual material of the simulated head: `glass-beads` (a physical
    /// retroreflector that none of the models is), or a model id of models.md.
    #[arg(long, default_value = "glass-beads")]
    pub material: String,
    /// A model's parameters, NAME=V,... (default for retro-phong: a retroreflective tape).
    #[arg(long)]
    pub params: Option<String>,
    /// Seed of the simulated head's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Laser power drift of the simulated head: relative amplitude of a
    /// one-hour sinusoid (0.05 = ±5 %).
    #[arg(long, default_value_t = 0.0)]
    pub laser_drift: f64,
    /// The simulated head's clock at power-up (s), to continue the time (and
    /// the drift) of an earlier run, e.g. the reference plate's.
    #[arg(long, default_value_t = 0.0)]
    pub clock_start_s: f64,
    /// Faults for the simulated head to suffer, KIND@N[:ARG],...: on the link
    /// at the N-th frame it sends (drop, corrupt, duplicate, reorder,
    /// delay:MS, disconnect) or, with a req- prefix, the N-th request it
    /// receives (req-drop, req-duplicate, ...), status requests and answers
    /// not counted; in the hardware from its N-th move (saturated,
    /// laser-dead, stall, overrun:BLOCKS) or from the start
    /// (switch-open:AXIS, switch-closed:AXIS).
    #[arg(long, value_name = "FAULTS")]
    pub inject: Option<String>,
    /// Give the simulated head the imperfections its uncertainty budget
    /// states (stage zeros, backlash, gain ranges, stray light) and a plate
    /// off its certificate, drawn from --seed.
    #[arg(long)]
    pub imperfect: bool,
    /// Wall-clock seconds per second of the simulated head's work: 1 runs
    /// it at the reference head's own pace (moves, settling, integrations),
    /// to try the live page, pause and continue without hardware; 0 (the
    /// default) as fast as this machine can.
    #[arg(long, value_name = "FACTOR", default_value_t = 0.0)]
    pub pace: f32,
}

impl SimHeadArgs {
    pub fn config(&self) -> Result<SimConfig> {
        let material = Specimen::named(&self.material, self.params.as_deref())?;
        let mut cfg = SimConfig {
            material,
            seed: self.seed,
            clock_start_s: self.clock_start_s,
            pace: self.pace,
            ..SimConfig::default()
        };
        cfg.photodiode.laser_drift = self.laser_drift;
        if self.imperfect {
            let u = HeadUncertainty::default();
            cfg.imperfections = Box::new(Imperfections::drawn(
                self.seed,
                u.zero_deg,
                u.backlash_deg,
                u.gain_rel,
                u.stray_a,
                PLATE_RHO_U,
            ));
        }
        if let Some(f) = &self.inject {
            cfg.faults = gonio_sim::faults::Faults::parse(f).context("--inject")?;
        }
        cfg.checked()
    }
}
