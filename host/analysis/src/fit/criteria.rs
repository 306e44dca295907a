//! What weighs fits of different sizes against each other: each sample's
//! weight in the least-squares sum, and Akaike's and Bayes' information
//! criteria of the weighted sum. A parametric fit and the rational function
//! (which is not a least-squares fit, yet is ranked beside them in
//! `compare`) are charged by the same rule.

use super::{area, Dataset, Units, Weighting};
use anyhow::{bail, Result};
use gonio_brdf::Directions;
use serde::Serialize;

/// Each sample's weight in the sum of squares, the data in the units the
/// residuals are taken in.
pub fn weights(data: &Dataset, weighting: Weighting) -> Result<Vec<f64>> {
    let y: Vec<f64> = data.observations.iter().map(|o| o.value).collect();
    let floor = 1e-3 * y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let solid = match weighting {
        Weighting::Area => area::solid_angles(&data.observations),
        _ => Vec::new(),
    };
    let mut weight = Vec::with_capacity(y.len());
    for (k, o) in data.observations.iter().enumerate() {
        weight.push(match weighting {
            Weighting::Uniform => 1.0,
            Weighting::Area => solid[k].sqrt(),
            Weighting::Relative => 1.0 / y[k].abs().max(floor).max(f64::MIN_POSITIVE),
            Weighting::Sigma => match o.sigma {
                Some(s) if s > 0.0 && s.is_finite() => 1.0 / s,
                _ => bail!(
                    "--weights sigma needs a positive uncertainty on every sample (sample {} has none)",
                    k + 1
                ),
            },
        });
    }
    Ok(weight)
}

/// `N·ln(S/N) + 2k` and `N·ln(S/N) + k·ln N`, `S` the weighted sum of
/// squares over `N` samples and `k` the coefficients: lower is better, and
/// each extra coefficient must earn its place.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    pub aic: f64,
    pub bic: f64,
}

impl Criteria {
    pub fn of(cost: f64, samples: usize, coefficients: usize) -> Criteria {
        let (n, k) = (samples as f64, coefficients as f64);
        let log_mean = (cost / n).max(f64::MIN_POSITIVE).ln();
        Criteria {
            aic: n * log_mean + 2.0 * k,
            bic: n * log_mean + k * n.ln(),
        }
    }

    /// The criteria of any BRDF on `data`, its residuals taken in `units`
    /// and weighed as a fit with `weighting` weighs them: how a function
    /// that was not fitted by least squares is ranked beside those that were.
    pub fn of_brdf(
        data: &Dataset,
        units: Units,
        weighting: Weighting,
        coefficients: usize,
        f_r: impl Fn(&Directions) -> f64,
    ) -> Result<Criteria> {
        let data = data.in_units(units)?;
        let w = weights(&data, weighting)?;
        let cost: f64 = data
            .observations
            .iter()
            .zip(&w)
            .map(|(o, w)| (w * (o.unit_factor(units) * f_r(&o.directions()) - o.value)).powi(2))
            .sum();
        Ok(Criteria::of(cost, data.observations.len(), coefficients))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{fit, FitSpec};
    use gonio_brdf::{Material, ModelId};

    #[test]
    fn a_brdf_is_charged_as_its_fit_is() {
        // A model's fit and the same material judged as a plain BRDF give
        // the same criteria, under every weighting.
        let truth = Material::parse(ModelId::Lambert, "kd=0.4").unwrap();
        let mut observations = Vec::new();
        for k in 0..40 {
            let (ti, to, dphi) = (
                (5.0 + k as f64).to_radians(),
                (2.0 * k as f64).to_radians(),
                (9.0 * k as f64).to_radians(),
            );
            let d = Directions::from_angles(ti, to, dphi);
            observations.push(crate::fit::Observation {
                theta_i: ti,
                theta_o: to,
                dphi,
                value: truth.eval(&d) * (1.0 + 0.03 * ((k * 7 % 5) as f64 - 2.0)),
                sigma: Some(0.002 + 0.0001 * k as f64),
                shared: Default::default(),
            });
        }
        let data = Dataset::new(Units::Fr, observations);
        for weighting in [Weighting::Uniform, Weighting::Sigma, Weighting::Relative, Weighting::Area] {
            let f = fit(
                &data,
                &FitSpec {
                    weighting,
                    ..FitSpec::new(ModelId::Lambert)
                },
            )
            .unwrap();
            let c = Criteria::of_brdf(&data, Units::Fr, weighting, 1, |d| f.material.eval(d)).unwrap();
            assert!(
                (c.aic - f.aic).abs() <= 1e-9 * f.aic.abs().max(1.0),
                "{weighting:?}: {} against {}",
                c.aic,
                f.aic
            );
            assert!((c.bic - f.bic).abs() <= 1e-9 * f.bic.abs().max(1.0), "{weighting:?}");
        }
    }
}
