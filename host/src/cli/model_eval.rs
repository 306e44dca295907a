//! `gonio eval` and `gonio dhr`: a model with given parameters at one
//! geometry, and its directional-hemispherical reflectance.

use super::fit::ParamArg;
use anyhow::{bail, Result};
use gonio_brdf::{dhr, retro_phong_energy_sum, Directions, Material, ModelId};
use serde_json::json;

#[derive(Debug, Clone, clap::Args)]
pub struct ModelArgs {
    /// Model id (models.md).
    #[arg(long)]
    pub model: String,
    /// Every parameter, NAME=V,NAME=V,...
    #[arg(long)]
    pub params: String,
    /// Cosine of the retro lobes.
    #[arg(long, value_enum, default_value = "view")]
    pub param: ParamArg,
}

impl ModelArgs {
    fn material(&self) -> Result<Material> {
        let mut m = Material::parse(ModelId::parse(&self.model)?, &self.params)?;
        m.param = self.param.into();
        Ok(m)
    }
}

/// An angle of the upper hemisphere in degrees, `[0, 90)`.
fn polar(name: &str, v: f64) -> Result<f64> {
    if !(0.0..90.0).contains(&v) {
        bail!("--{name} {v}: must be in [0, 90) degrees");
    }
    Ok(v)
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
    #[arg(long)]
    pub json: bool,
}

pub fn eval_cmd(a: EvalArgs) -> Result<()> {
    let m = a.model.material()?;
    let (ti, to) = (polar("theta-i", a.theta_i)?, polar("theta-o", a.theta_o)?);
    if !a.dphi.is_finite() {
        bail!("--dphi must be finite");
    }
    let d = Directions::from_degrees(ti, to, a.dphi);
    let f = m.eval(&d);
    if a.json {
        println!("{}", json!({"model": m.model.name(), "fr": f, "fr_cos": f * d.cos_o()}));
    } else {
        println!("f_r = {f:.9e} sr⁻¹  (f_r·cosθo = {:.9e})", f * d.cos_o());
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
    #[arg(long)]
    pub json: bool,
}

pub fn dhr_cmd(a: DhrArgs) -> Result<()> {
    let m = a.model.material()?;
    let ti = polar("theta-i", a.theta_i)?;
    let rho = dhr::dhr(&m, ti.to_radians());
    // Spieringhs §8's check for RetroPhong: kd + ks(θi) + kr(θi) < 1.
    let sum = (m.model == ModelId::RetroPhong).then(|| retro_phong_energy_sum(&m.params, ti.to_radians().cos()));
    let conserving = rho <= 1.0;
    if a.json {
        let mut v = json!({"model": m.model.name(), "theta_i_deg": ti, "dhr": rho, "energy_conserving": conserving});
        if let Some(s) = sum {
            v["kd_ks_kr"] = json!(s);
        }
        println!("{v}");
    } else {
        println!(
            "ρ(θi = {ti}°) = {rho:.6}  ({})",
            if conserving {
                "energy conserving"
            } else {
                "reflects more than it receives"
            }
        );
        if let Some(s) = sum {
            println!(
                "kd + ks(θi) + kr(θi) = {s:.6}{}",
                if s < 1.0 { "" } else { "  (≥ 1: Spieringhs' check fails)" }
            );
        }
    }
    Ok(())
}
