//! A fitted rational function as a BRDF: `cosθi · cosθo · P(u)/Q(u)`,
//! the cosine factor of Belcour et al. 2014 §6.B (ALTA's
//! `rational_function_cosine`: the product of the light's and the view's
//! cosines), which takes the fall towards grazing out of what the
//! polynomials must follow; or `P(u)/Q(u)` alone (ALTA's
//! `rational_function_legendre`), which on a retro lobe over a flat floor
//! holds absolute segments with fewer terms (`fit-bench rational`).
//!
//! The function is of the quantity its samples held (`quantity`), as ALTA
//! fits a file's own numbers: `f_r`, or `f_r·cosθo` for the measured tapes
//! published in ALTA's format, whose ±0.5 segments (the paper's) are of
//! that quantity. `eval` is `f_r` either way.

use super::basis::{Basis, Coordinates, Domain, TermOrder};
use crate::fit::{Dataset, Metrics, Units};
use gonio_brdf::Directions;
use serde::{Deserialize, Serialize};

/// What a rational fit file without `cosine` was fitted with.
fn cosine_factor() -> bool {
    true
}

/// The quantity of a rational fit file without `quantity`.
fn f_r() -> Units {
    Units::Fr
}

/// The order of a rational fit file without `order`.
fn first_order() -> TermOrder {
    TermOrder::FirstFalling
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rational {
    /// What it is a function of (the file's `parametrization`, named so
    /// before the unwarped view plane existed).
    #[serde(rename = "parametrization")]
    pub coordinates: Coordinates,
    /// Total degree of numerator and denominator: that of their last term
    /// (`Basis::in_order`; both have as many terms).
    pub degree: usize,
    /// `f_r = cosθi·cosθo·P/Q` (true; files written before the choice
    /// existed) or `P/Q`.
    #[serde(default = "cosine_factor")]
    pub cosine: bool,
    /// What the cosine factor times `P/Q` is: `f_r`, or `f_r·cosθo` (the
    /// samples' quantity; files written before the choice existed: `f_r`).
    #[serde(default = "f_r")]
    pub quantity: Units,
    /// The coordinates' box, mapped onto [−1, 1]³.
    pub domain: Domain,
    /// The terms' order within a degree (files written before ALTA's
    /// order was adopted have none, and are in the first one).
    #[serde(default = "first_order")]
    pub order: TermOrder,
    pub numerator: Vec<f64>,
    pub denominator: Vec<f64>,
}

impl Rational {
    /// The number of coefficients, numerator and denominator.
    pub fn coefficients(&self) -> usize {
        self.numerator.len() + self.denominator.len()
    }

    /// `f_r` at `d` (sr⁻¹); NaN where the denominator is not positive.
    /// Outside the fitted box the coordinates are held at its edge
    /// (`Domain::unit`).
    pub fn eval(&self, d: &Directions) -> f64 {
        self.eval_with(&self.basis(), d)
    }

    /// The terms its coefficients multiply.
    pub fn basis(&self) -> Basis {
        Basis::in_order(self.numerator.len(), self.order)
    }

    /// The factor `P/Q` is multiplied by at `d` to give `f_r`: the cosine
    /// factor, over `cosθo` for a function of `f_r·cosθo` (which cancels
    /// the factor's, so that it stays finite at grazing views).
    pub fn factor(&self, d: &Directions) -> f64 {
        match (self.cosine, self.quantity) {
            (true, Units::Fr) => d.cos_i() * d.cos_o(),
            (true, Units::FrCos) => d.cos_i(),
            (false, Units::Fr) => 1.0,
            (false, Units::FrCos) => 1.0 / d.cos_o(),
        }
    }

    /// As `eval`, with the basis built once by the caller.
    pub fn eval_with(&self, basis: &Basis, d: &Directions) -> f64 {
        let u = self.domain.unit(self.coordinates.of(d));
        let q = basis.eval(&self.denominator, u);
        if q <= 0.0 {
            // A pole or worse: the denominator is held positive at the
            // samples and a grid, not proven so between.
            return f64::NAN;
        }
        self.factor(d) * basis.eval(&self.numerator, u) / q
    }

    /// The function at every observation of `data`, in `data`'s units.
    pub fn values(&self, data: &Dataset) -> Vec<f64> {
        let basis = self.basis();
        data.observations
            .iter()
            .map(|o| self.eval_with(&basis, &o.directions()) * o.unit_factor(data.units))
            .collect()
    }

    /// The figures every fit reports against `data`, and the largest
    /// |measured − fitted| (L∞), in `data`'s units.
    pub fn against(&self, data: &Dataset) -> (Metrics, f64) {
        let measured: Vec<f64> = data.observations.iter().map(|o| o.value).collect();
        let model = self.values(data);
        // A NaN anywhere is the answer, not skipped as f64::max would.
        let linf = measured
            .iter()
            .zip(&model)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, |m, e| if e > m || e.is_nan() { e } else { m });
        (Metrics::new(&measured, &model), linf)
    }
}
