//! Options shared by the commands that start a simulated head.

use anyhow::{bail, Context, Result};
use gonio_analysis::uncertainty::HeadUncertainty;
use gonio_brdf::{Material, ModelId, Specimen};
use gonio_sim::{Imperfections, SimConfig, PLATE_RHO, PLATE_RHO_U};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

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

/// A simulated head's material by name: `glass-beads` (no parameters: a
/// physical retroreflector none of the models is) or a model id with its
/// parameters (retro-phong's default: a retroreflective tape).
pub fn specimen(material: &str, params: Option<&str>) -> Result<Specimen> {
    if material == "glass-beads" {
        if params.is_some() {
            bail!("--material glass-beads takes no --params (its parameters are fixed: docs/architecture.md#the-simulated-head)");
        }
        return Ok(Specimen::default());
    }
    let model = ModelId::parse(material).context("--material: glass-beads or a model id")?;
    Ok(Specimen::Model(match params {
        Some(p) => Material::parse(model, p)?,
        None if model == ModelId::RetroPhong => Material::tape(),
        None => bail!("--params is required for --material {}", model.name()),
    }))
}

impl SimHeadArgs {
    pub fn config(&self) -> Result<SimConfig> {
        let material = specimen(&self.material, self.params.as_deref())?;
        if !(0.0..0.5).contains(&self.laser_drift) {
            bail!("--laser-drift {} must be in [0, 0.5)", self.laser_drift);
        }
        if !(self.clock_start_s.is_finite() && self.clock_start_s >= 0.0) {
            bail!("--clock-start-s must be a finite time ≥ 0");
        }
        if !(self.pace.is_finite() && (0.0..=100.0).contains(&self.pace)) {
            bail!(
                "--pace {}: wall-clock seconds per simulated second, from 0 (as fast as it can) to 100",
                self.pace
            );
        }
        let mut cfg = SimConfig {
            material,
            seed: self.seed,
            clock_start_s: self.clock_start_s,
            pace: self.pace,
            ..SimConfig::default()
        };
        cfg.photodiode.laser_drift = self.laser_drift;
        if self.imperfect {
            cfg.imperfections = Box::new(drawn_imperfections(self.seed, &HeadUncertainty::default(), PLATE_RHO_U));
        }
        if let Some(f) = &self.inject {
            cfg.faults = gonio_sim::faults::Faults::parse(f).context("--inject")?;
        }
        Ok(cfg)
    }
}

/// One head drawn from the stated uncertainties: zeros and gains normal,
/// stray light uniform within its bound, backlash as stated, the plate's
/// reflectance normal about its certificate (standard uncertainty
/// `plate_rho_u`). The same seed gives the same head.
pub fn drawn_imperfections(seed: u64, u: &HeadUncertainty, plate_rho_u: f64) -> Imperfections {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x1a9e_77e3_5eed_0b1d);
    let mut normal = |sd: f64| Normal::new(0.0, sd.max(0.0)).map_or(0.0, |d| d.sample(&mut rng));
    let zero_offset_deg = [0, 1, 2].map(|a| normal(u.zero_deg[a]));
    let gain_scale = [0; 4].map(|_| 1.0 + normal(u.gain_rel));
    let plate_rho = (PLATE_RHO + normal(plate_rho_u)).min(1.0);
    let stray_a = rng.random_range(-1.0..=1.0) * u.stray_a;
    Imperfections {
        zero_offset_deg,
        backlash_deg: u.backlash_deg,
        gain_scale,
        stray_a,
        plate_rho,
    }
}
