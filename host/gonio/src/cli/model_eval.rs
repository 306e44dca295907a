//! `gonio eval` and `gonio dhr`: a model with given parameters at one
//! geometry, and its directional-hemispherical reflectance.

use anyhow::{bail, Result};
use gonio_analysis::evaluation::{self, Brdf};
use gonio_brdf::{Material, ModelId, Param, Specimen};
use std::path::PathBuf;

#[derive(Debug, Clone, clap::Args)]
#[command(group(clap::ArgGroup::new("brdf").required(true).args(["model", "material", "fit"])))]
pub struct ModelArgs {
    /// Model id (models.md), with --params.
    #[arg(long, requires = "params")]
    pub model: Option<String>,
    /// Every parameter, NAME=V,NAME=V,... (with --material: a model's, as `gonio scan --sim` takes them).
    #[arg(long)]
    pub params: Option<String>,
    /// A simulated head's material (`glass-beads`, or a model id as `gonio
    /// scan --sim --material` takes it): its own values, the truth a
    /// simulated scan is checked against.
    #[arg(long, conflicts_with = "model")]
    pub material: Option<String>,
    /// A fit file (`gonio fit --out`): its model with its parameters, or
    /// its rational function.
    #[arg(long, value_name = "FIT.json", conflicts_with_all = ["model", "material"])]
    pub fit: Option<PathBuf>,
    /// Cosine of the retro lobes (a model's).
    #[arg(long, value_enum, default_value = "view")]
    pub param: Param,
}

impl ModelArgs {
    /// What is evaluated.
    fn brdf(&self) -> Result<Brdf> {
        if let Some(path) = &self.fit {
            return Brdf::fitted(path);
        }
        if let Some(name) = &self.material {
            return Ok(Brdf::Specimen(Specimen::named(name, self.params.as_deref())?));
        }
        let (Some(model), Some(params)) = (&self.model, &self.params) else {
            bail!("give --model M --params ..., --material NAME or --fit FIT.json");
        };
        let mut m = Material::parse(ModelId::parse(model)?, params)?;
        m.param = self.param;
        Ok(Brdf::Specimen(Specimen::Model(m)))
    }
}

#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Incidence polar angle θi (degrees).
    #[arg(long, allow_negative_numbers = true)]
    pub theta_i: f64,
    /// Viewing polar angle θo (degrees).
    #[arg(long, allow_negative_numbers = true)]
    pub theta_o: f64,
    /// Azimuth difference Δφ = φo − φi (degrees; 0 is the retro half-plane).
    #[arg(long, allow_negative_numbers = true)]
    pub dphi: f64,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn eval_cmd(a: EvalArgs) -> Result<()> {
    let v = evaluation::at(&a.model.brdf()?, a.theta_i, a.theta_o, a.dphi)?;
    match a.json {
        true => println!("{}", serde_json::to_value(&v)?),
        false => print!("{v}"),
    }
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct DhrArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Incidence polar angle θi (degrees).
    #[arg(long, allow_negative_numbers = true)]
    pub theta_i: f64,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn dhr_cmd(a: DhrArgs) -> Result<()> {
    let r = evaluation::reflectance(&a.model.brdf()?, a.theta_i)?;
    match a.json {
        true => println!("{}", serde_json::to_value(&r)?),
        false => print!("{r}"),
    }
    Ok(())
}
