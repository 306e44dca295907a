//! How a model is fitted, as the user states it: the cosine of the retro
//! lobes, the residuals' units and weights, the global search's seed, boxes
//! replacing the defaults, and parameters held at a value; each named, as
//! on the command line (`NAME=LO:HI`, `NAME=VALUE`).

use super::{FitSpec, Units, Weighting};
use anyhow::{bail, Context, Result};
use gonio_brdf::{ModelId, Param};
use std::str::FromStr;

/// A search box by parameter name, `name ∈ [lo, hi]`.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedBox {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
}

impl FromStr for NamedBox {
    type Err = anyhow::Error;

    /// `NAME=LO:HI`.
    fn from_str(s: &str) -> Result<NamedBox> {
        let parsed = s.split_once('=').and_then(|(n, r)| {
            let (lo, hi) = r.split_once(':')?;
            Some((n.trim(), lo.trim().parse::<f64>().ok()?, hi.trim().parse::<f64>().ok()?))
        });
        let Some((name, lo, hi)) = parsed else {
            bail!("--bounds `{s}` is not NAME=LO:HI");
        };
        Ok(NamedBox { name: name.into(), lo, hi })
    }
}

/// A parameter held at a value, `NAME=VALUE`.
pub fn fixed(s: &str) -> Result<(String, f64)> {
    let (name, v) = s.split_once('=').with_context(|| format!("--fix `{s}` is not NAME=VALUE"))?;
    let v: f64 = v.trim().parse().with_context(|| format!("--fix {name}: `{v}` is not a number"))?;
    Ok((name.trim().to_string(), v))
}

/// How every model of a comparison (or one fit) is fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    pub param: Param,
    /// The residuals' units; the data's own where `None`.
    pub units: Option<Units>,
    pub weighting: Weighting,
    /// The global search's seed.
    pub seed: u64,
    /// Boxes replacing the defaults: in a comparison each model takes the
    /// names it has.
    pub bounds: Vec<NamedBox>,
    /// Parameters held at a value (one model's fit only).
    pub fixed: Vec<(String, f64)>,
}

impl Default for Settings {
    /// The command line's: the view cosine, the data's units, uniform
    /// weights, seed 1, the default boxes.
    fn default() -> Self {
        Settings {
            param: Param::View,
            units: None,
            weighting: Weighting::Uniform,
            seed: 1,
            bounds: Vec::new(),
            fixed: Vec::new(),
        }
    }
}

impl Settings {
    /// The fit of `model` to data in `units`. With `every_model` (a
    /// comparison), a box's name the model lacks is skipped, unless no
    /// model has it.
    pub fn fit_spec(&self, model: ModelId, units: Units, every_model: bool) -> Result<FitSpec> {
        let mut bounds = Vec::new();
        for b in &self.bounds {
            if !(b.lo.is_finite() && b.hi.is_finite() && b.lo < b.hi) {
                bail!("--bounds {}: the box [{}, {}] must be finite with LO < HI", b.name, b.lo, b.hi);
            }
            match model.param_index(&b.name) {
                Ok(i) => bounds.push((i, b.lo, b.hi)),
                Err(_) if every_model && ModelId::ALL.iter().any(|m| m.param_index(&b.name).is_ok()) => {}
                Err(e) => return Err(e.context("--bounds")),
            }
        }
        let fixed = self
            .fixed
            .iter()
            .map(|(name, v)| Ok((model.param_index(name)?, *v)))
            .collect::<Result<_>>()?;
        Ok(FitSpec {
            param: self.param,
            units: self.units.unwrap_or(units),
            weighting: self.weighting,
            fixed,
            bounds,
            seed: self.seed,
            ..FitSpec::new(model)
        })
    }
}
