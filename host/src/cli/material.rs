//! Options shared by the commands that start a simulated head.

use crate::brdf::{Material, ModelId};
use crate::sim::SimConfig;
use anyhow::{bail, Result};

#[derive(Debug, Clone, clap::Args)]
pub struct SimHeadArgs {
    /// Virtual material of the simulated head: a model id of models.md.
    #[arg(long, default_value = "retro-phong")]
    pub material: String,
    /// Its parameters, NAME=V,... (default for retro-phong: a retroreflective tape).
    #[arg(long)]
    pub params: Option<String>,
    /// Seed of the simulated head's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl SimHeadArgs {
    pub fn config(&self) -> Result<SimConfig> {
        let model = ModelId::parse(&self.material)?;
        let material = match &self.params {
            Some(p) => Material::parse(model, p)?,
            None if model == ModelId::RetroPhong => Material::tape(),
            None => bail!("--params is required for --material {}", model.name()),
        };
        Ok(SimConfig {
            material,
            seed: self.seed,
            ..SimConfig::default()
        })
    }
}
