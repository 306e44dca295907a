//! `gonio eval` and `gonio dhr`: a model with given parameters at one
//! geometry, and its directional-hemispherical reflectance.

use super::fitting::ParamArg;
use super::material;
use anyhow::{bail, Result};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::{fit, rational, rational::Rational};
use gonio_brdf::{dhr, retro_phong_energy_sum, Directions, Material, ModelId, Specimen};
use gonio_firmware::config::REFERENCE;
use gonio_sim::field_average;
use serde_json::json;
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
    pub param: ParamArg,
}

/// What is evaluated: a model or a simulated head's material, or a
/// rational fit's function (which no head is made of).
enum Evaluated {
    Specimen(Specimen),
    Rational(Rational),
}

impl Evaluated {
    fn eval(&self, d: &Directions) -> f64 {
        match self {
            Evaluated::Specimen(s) => s.eval(d),
            Evaluated::Rational(r) => r.eval(d),
        }
    }

    fn model(&self) -> Option<&Material> {
        match self {
            Evaluated::Specimen(s) => s.model(),
            Evaluated::Rational(_) => None,
        }
    }
}

impl ModelArgs {
    /// What is evaluated, and its name.
    fn evaluated(&self) -> Result<(Evaluated, String)> {
        if let Some(path) = &self.fit {
            return Ok(match fit::file::read_fitted(path)? {
                FittedBrdf::Rational(r) => (Evaluated::Rational(r), rational::file::MODEL.into()),
                FittedBrdf::Model(m) => {
                    let name = m.model.name().to_string();
                    (Evaluated::Specimen(Specimen::Model(m)), name)
                }
            });
        }
        if let Some(name) = &self.material {
            return Ok((Evaluated::Specimen(material::specimen(name, self.params.as_deref())?), name.clone()));
        }
        let (Some(model), Some(params)) = (&self.model, &self.params) else {
            bail!("give --model M --params ..., --material NAME or --fit FIT.json");
        };
        let mut m = Material::parse(ModelId::parse(model)?, params)?;
        m.param = self.param.into();
        let name = m.model.name().to_string();
        Ok((Evaluated::Specimen(Specimen::Model(m)), name))
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
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn eval_cmd(a: EvalArgs) -> Result<()> {
    let (m, name) = a.model.evaluated()?;
    let (ti, to) = (polar("theta-i", a.theta_i)?, polar("theta-o", a.theta_o)?);
    if !a.dphi.is_finite() {
        bail!("--dphi must be finite");
    }
    let d = Directions::from_degrees(ti, to, a.dphi);
    let f = m.eval(&d);
    if f.is_nan() {
        bail!("{name} is not defined at this geometry: a rational fit's denominator is not positive there (held so only at its samples and a grid)");
    }
    // What the reference head's detector reads there: the average over its
    // field (a 0.39° disc), which a simulated scan's values are.
    let field = REFERENCE.optics.detector_sr as f64;
    let seen = field_average(field, &d, |d| m.eval(d));
    if a.json {
        println!(
            "{}",
            json!({"model": name, "fr": f, "fr_cos": f * d.cos_o(), "fr_seen": seen, "detector_field_sr": field})
        );
    } else {
        println!("f_r = {f:.9e} sr⁻¹  (f_r·cosθo = {:.9e})", f * d.cos_o());
        println!(
            "seen by the reference head's detector ({:.2}° field): {seen:.9e} sr⁻¹",
            gonio_brdf::aperture::diameter_deg(field)
        );
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
    let (m, name) = a.model.evaluated()?;
    let ti = polar("theta-i", a.theta_i)?;
    let rho = dhr::dhr(|d| m.eval(d), ti.to_radians());
    if rho.is_nan() {
        bail!("{name} is not defined everywhere over the hemisphere at θi = {ti}°: a rational fit's denominator is not positive somewhere");
    }
    // Spieringhs §8's check for RetroPhong: kd + ks(θi) + kr(θi) < 1.
    let sum = m
        .model()
        .filter(|m| m.model == ModelId::RetroPhong)
        .map(|m| retro_phong_energy_sum(&m.params, ti.to_radians().cos()));
    let conserving = rho <= 1.0;
    if a.json {
        let mut v = json!({"model": name, "theta_i_deg": ti, "dhr": rho, "energy_conserving": conserving});
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
