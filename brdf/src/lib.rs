//! BRDF models of `docs/models.md` §2, in f64, with the parameter
//! names of the contract. The simulated head's virtual material is one of
//! these; the fitting engine builds on the same evaluations.

mod abc_retro;
pub mod aperture;
mod beckmann_retro;
mod blinn_retro;
mod catalog;
pub mod dhr;
mod five_param;
pub mod frame;
pub mod geometry;
mod glass_beads;
mod lafortune;
mod lambert;
mod oren_nayar;
mod retro_phong;
pub mod scalar;

pub use catalog::{Bound, HandGradient, ModelId, Spread};
pub use frame::{Directions, Param};
pub use geometry::GeometryTerms;
pub use glass_beads::GlassBeads;
pub use retro_phong::energy_sum as retro_phong_energy_sum;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

/// What a simulated head measures: a model of `models.md` with its
/// parameters, or a physical reflector that none of the models is (the
/// default, as a real material). Serialised untagged: a model is written
/// as before (`scan.json` of older scans still reads).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Specimen {
    Model(Material),
    /// Boxed: a head's configuration stays small.
    GlassBeads(Box<GlassBeads>),
}

impl Default for Specimen {
    fn default() -> Self {
        Specimen::GlassBeads(Box::default())
    }
}

impl Specimen {
    /// A specimen by name: `glass-beads` (no parameters: a physical
    /// retroreflector none of the models is) or a model id with its
    /// parameters, `NAME=V,...` (retro-phong's default: a retroreflective
    /// tape), as `gonio scan --sim --material` takes them.
    pub fn named(material: &str, params: Option<&str>) -> Result<Specimen> {
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

    /// `f_r` (sr⁻¹) for a pair of directions.
    pub fn eval(&self, d: &Directions) -> f64 {
        match self {
            Specimen::Model(m) => m.eval(d),
            Specimen::GlassBeads(g) => g.eval(d),
        }
    }

    /// The model, if the specimen is one.
    pub fn model(&self) -> Option<&Material> {
        match self {
            Specimen::Model(m) => Some(m),
            Specimen::GlassBeads(_) => None,
        }
    }

    /// What it is, in a line.
    pub fn describe(&self) -> String {
        match self {
            Specimen::Model(m) => format!("{} {}", m.model.name(), m.params_string()),
            Specimen::GlassBeads(_) => {
                "glass-bead retroreflector (n = 1.9 beads in a white binder, glossy top): a physical material, none of the models".into()
            }
        }
    }
}

/// A model id and its parameters, in the order of `models.md`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub model: ModelId,
    pub params: Vec<f64>,
    /// Cosine of the retro lobe (`retro-phong`'s published form is `view`).
    pub param: Param,
}

impl Material {
    /// A retroreflective tape: sharp retro lobe (≈ 40 sr⁻¹ at θi = 60°) over a
    /// 0.016 sr⁻¹ diffuse floor, a weak mirror lobe; `kd + ks + kr < 1` up to
    /// θi = 60°.
    pub fn tape() -> Self {
        Material {
            model: ModelId::RetroPhong,
            params: vec![0.05, 500.0, 0.8, 0.1, 0.02, 3.0],
            param: Param::View,
        }
    }

    /// Parses `NAME=V,NAME=V,...` for a model; every parameter must be given.
    pub fn parse(model: ModelId, spec: &str) -> Result<Self> {
        let names = model.param_names();
        let mut params = vec![f64::NAN; names.len()];
        for item in spec.split(',').filter(|s| !s.trim().is_empty()) {
            let (k, v) = item.split_once('=').with_context(|| format!("`{item}` is not NAME=VALUE"))?;
            let Some(i) = names.iter().position(|n| *n == k.trim()) else {
                bail!("unknown parameter `{}` for {}; valid: {}", k.trim(), model.name(), names.join(", "));
            };
            let v: f64 = v.trim().parse().with_context(|| format!("parameter {k}: `{v}` is not a number"))?;
            if !v.is_finite() {
                bail!("parameter {k} must be finite");
            }
            params[i] = v;
        }
        if let Some(i) = params.iter().position(|p| p.is_nan()) {
            bail!("parameter `{}` of {} missing", names[i], model.name());
        }
        Ok(Material {
            model,
            params,
            param: Param::View,
        })
    }

    /// `f_r` (sr⁻¹) for a pair of directions.
    pub fn eval(&self, d: &Directions) -> f64 {
        self.model.eval(&GeometryTerms::new(d), &self.params, self.param)
    }

    /// The model as the head's sanity check evaluates it, if the head has it
    /// (`lambert`, `retro-phong` with the view cosine, `abc-retro`).
    pub fn sanity_model(&self) -> Option<gonio_shared::SanityModel> {
        use gonio_shared::{SanityKind, SanityModel};
        let kind = match (self.model, self.param) {
            (ModelId::Lambert, _) => SanityKind::Lambert,
            (ModelId::RetroPhong, Param::View) => SanityKind::RetroPhong,
            (ModelId::RetroPhong, Param::Back) => return None,
            (ModelId::AbcRetro, p) => SanityKind::AbcRetro { back: p == Param::Back },
            _ => return None,
        };
        let p: Vec<f32> = self.params.iter().map(|x| *x as f32).collect();
        SanityModel::from_params(kind, &p)
    }

    /// `NAME=V,...` as accepted by [`Material::parse`].
    pub fn params_string(&self) -> String {
        let names = self.model.param_names();
        names
            .iter()
            .zip(&self.params)
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(",")
    }
}
