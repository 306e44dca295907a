//! `gonio sim`: a simulated head on a pseudo-terminal.

use crate::brdf::{Material, ModelId};
use crate::sim::{serve_pty, SimConfig};
use anyhow::Result;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Path of the symbolic link to the head's terminal (pass it to `gonio scan --port`).
    #[arg(long, default_value = "/tmp/gonio-sim")]
    pub link: PathBuf,
    /// Virtual material: a model id of models.md.
    #[arg(long, default_value = "retro-phong")]
    pub material: String,
    /// Its parameters, NAME=V,... (default: a retroreflective tape).
    #[arg(long)]
    pub params: Option<String>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn sim(a: SimArgs) -> Result<()> {
    let model = ModelId::parse(&a.material)?;
    let material = match &a.params {
        Some(p) => Material::parse(model, p)?,
        None if model == ModelId::RetroPhong => Material::tape(),
        None => anyhow::bail!("--params is required for --material {}", model.name()),
    };
    let cfg = SimConfig {
        material,
        seed: a.seed,
        ..SimConfig::default()
    };
    serve_pty(cfg, &a.link, |p| {
        eprintln!("simulated head listening on {} (Ctrl-C to stop)", p.display());
    })
}
