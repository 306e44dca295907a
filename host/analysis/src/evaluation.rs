//! A BRDF evaluated where the user asks: at one geometry, as its own value
//! and as the reference head's detector would read it, and over the
//! hemisphere (its directional-hemispherical reflectance and energy check).

use crate::fit::file::{read_fitted, FittedBrdf};
use crate::rational;
use anyhow::{bail, Result};
use gonio_brdf::aperture::{diameter_deg, field_average};
use gonio_brdf::{dhr, retro_phong_energy_sum, Directions, Material, ModelId, Specimen};
use gonio_firmware::config::REFERENCE;
use serde::Serialize;
use std::fmt;
use std::path::Path;

/// A BRDF by where it comes from: a fit file, or a specimen (a model with
/// its parameters, or a simulated head's material).
pub enum Brdf {
    Fit(FittedBrdf),
    Specimen(Specimen),
}

impl Brdf {
    /// A fit file's BRDF.
    pub fn fitted(path: &Path) -> Result<Brdf> {
        Ok(Brdf::Fit(read_fitted(path)?))
    }

    pub fn eval(&self, d: &Directions) -> f64 {
        match self {
            Brdf::Fit(f) => f.eval(d),
            Brdf::Specimen(s) => s.eval(d),
        }
    }

    /// Its model with parameters, if it has one (a rational function and
    /// glass beads have none).
    pub fn model(&self) -> Option<&Material> {
        match self {
            Brdf::Fit(FittedBrdf::Model(m)) => Some(m),
            Brdf::Fit(FittedBrdf::Rational(_)) => None,
            Brdf::Specimen(s) => s.model(),
        }
    }

    /// Its name: the model's id, `rational`, or what the specimen is.
    pub fn name(&self) -> String {
        match self {
            Brdf::Fit(FittedBrdf::Rational(_)) => rational::file::MODEL.into(),
            Brdf::Fit(FittedBrdf::Model(m)) | Brdf::Specimen(Specimen::Model(m)) => m.model.name().into(),
            Brdf::Specimen(Specimen::GlassBeads(_)) => "glass-beads".into(),
        }
    }
}

/// An angle of the upper hemisphere in degrees, `[0, 90)`.
fn polar(name: &str, v: f64) -> Result<f64> {
    if !(0.0..90.0).contains(&v) {
        bail!("--{name} {v}: must be in [0, 90) degrees");
    }
    Ok(v)
}

/// A BRDF at one geometry.
#[derive(Debug, Serialize)]
pub struct Value {
    pub model: String,
    /// `f_r` (sr⁻¹) at the nominal directions, and times cosθo.
    pub fr: f64,
    pub fr_cos: f64,
    /// What the reference head's detector reads there: the average over
    /// its field, which a simulated scan's values are.
    pub fr_seen: f64,
    pub detector_field_sr: f64,
}

/// `brdf` at (θi, θo, Δφ), in degrees.
pub fn at(brdf: &Brdf, theta_i_deg: f64, theta_o_deg: f64, dphi_deg: f64) -> Result<Value> {
    let (ti, to) = (polar("theta-i", theta_i_deg)?, polar("theta-o", theta_o_deg)?);
    if !dphi_deg.is_finite() {
        bail!("--dphi must be finite");
    }
    let d = Directions::from_degrees(ti, to, dphi_deg);
    let fr = brdf.eval(&d);
    let model = brdf.name();
    if fr.is_nan() {
        bail!("{model} is not defined at this geometry: a rational fit's denominator is not positive there (held so only at its samples and a grid)");
    }
    let field = REFERENCE.optics.detector_sr as f64;
    Ok(Value {
        model,
        fr,
        fr_cos: fr * d.cos_o(),
        fr_seen: field_average(field, &d, |d| brdf.eval(d)),
        detector_field_sr: field,
    })
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "f_r = {:.9e} sr⁻¹  (f_r·cosθo = {:.9e})", self.fr, self.fr_cos)?;
        writeln!(
            f,
            "seen by the reference head's detector ({:.2}° field): {:.9e} sr⁻¹",
            diameter_deg(self.detector_field_sr),
            self.fr_seen
        )
    }
}

/// A BRDF's directional-hemispherical reflectance at one incidence.
#[derive(Debug, Serialize)]
pub struct Reflectance {
    pub model: String,
    pub theta_i_deg: f64,
    pub dhr: f64,
    pub energy_conserving: bool,
    /// RetroPhong's `kd + ks(θi) + kr(θi)`, Spieringhs §8's check.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kd_ks_kr: Option<f64>,
}

/// `brdf`'s reflectance at θi (degrees).
pub fn reflectance(brdf: &Brdf, theta_i_deg: f64) -> Result<Reflectance> {
    let ti = polar("theta-i", theta_i_deg)?;
    let rho = dhr::dhr(|d| brdf.eval(d), ti.to_radians());
    let model = brdf.name();
    if rho.is_nan() {
        bail!(
            "{model} is not defined everywhere over the hemisphere at θi = {ti}°: a rational fit's denominator is not positive somewhere"
        );
    }
    Ok(Reflectance {
        model,
        theta_i_deg: ti,
        dhr: rho,
        energy_conserving: rho <= 1.0,
        kd_ks_kr: brdf
            .model()
            .filter(|m| m.model == ModelId::RetroPhong)
            .map(|m| retro_phong_energy_sum(&m.params, ti.to_radians().cos())),
    })
}

impl fmt::Display for Reflectance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let conserving = match self.energy_conserving {
            true => "energy conserving",
            false => "reflects more than it receives",
        };
        writeln!(f, "ρ(θi = {}°) = {:.6}  ({conserving})", self.theta_i_deg, self.dhr)?;
        if let Some(s) = self.kd_ks_kr {
            let fails = if s < 1.0 { "" } else { "  (≥ 1: Spieringhs' check fails)" };
            writeln!(f, "kd + ks(θi) + kr(θi) = {s:.6}{fails}")?;
        }
        Ok(())
    }
}
