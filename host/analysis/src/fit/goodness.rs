//! Whether a fit is adequate within the stated uncertainties: χ², the sum of
//! the residuals squared each in units of its sample's σ (the cost itself
//! under `--weights sigma`), which a right model with right σ draws from the
//! χ² distribution of N − k degrees of freedom; and how the parameters'
//! estimates move together (their correlation matrix from the covariance).

use super::Dataset;
use gonio_brdf::Directions;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// A fit is consistent with the data when a χ² at least as large as its
/// own would arise this often from a right model with right σ (a test at
/// the 1 % level). With thousands of samples this is strict: a model that
/// misses by a tenth of the budget everywhere fails it, as it should before
/// it may carry a value where the data end.
pub const ADEQUATE_P: f64 = 0.01;

/// What the data say of a fit, for a model to carry a coefficient beyond
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Adequacy {
    /// χ²'s p-value at least [`ADEQUATE_P`].
    Adequate,
    /// Below it: the model misses the data by more than their uncertainty.
    Inadequate,
    /// The data carry no uncertainties (a file without them): nothing to
    /// judge the residuals against.
    NotJudged,
}

impl Adequacy {
    pub fn of(goodness: Option<&Goodness>) -> Adequacy {
        match goodness {
            Some(g) if g.p_value >= ADEQUATE_P => Adequacy::Adequate,
            Some(_) => Adequacy::Inadequate,
            None => Adequacy::NotJudged,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Adequacy::Adequate => "adequate",
            Adequacy::Inadequate => "inadequate",
            Adequacy::NotJudged => "not judged",
        }
    }
}

/// χ² of a fit against the samples' σ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Goodness {
    pub chi2: f64,
    /// N − k: samples less free parameters.
    pub dof: usize,
    /// χ² / dof: about 1 for an adequate model with right uncertainties.
    pub reduced_chi2: f64,
    /// The chance of a χ² at least this large were the model right and the
    /// σ right: small (< 0.01) says the model misses the data by more than
    /// their uncertainty.
    pub p_value: f64,
}

impl Goodness {
    /// From the weighted cost `chi2` of `samples` with `free` parameters;
    /// `None` without a degree of freedom.
    pub fn of(chi2: f64, samples: usize, free: usize) -> Option<Goodness> {
        // A model that overflows somewhere has no finite χ² to test (and
        // JSON no number to keep it in).
        let dof = samples.checked_sub(free).filter(|&d| d > 0 && chi2.is_finite())?;
        let p_value = ChiSquared::new(dof as f64).ok()?.sf(chi2);
        Some(Goodness {
            chi2,
            dof,
            reduced_chi2: chi2 / dof as f64,
            p_value,
        })
    }

    /// Any BRDF `f_r` with `free` fitted coefficients against the data's
    /// own σ, however it was fitted: `None` where a sample has none (or
    /// none is positive), or without a degree of freedom.
    pub fn of_brdf(data: &Dataset, free: usize, f_r: impl Fn(&Directions) -> f64) -> Option<Goodness> {
        let mut chi2 = 0.0;
        for o in &data.observations {
            let s = o.sigma.filter(|s| *s > 0.0 && s.is_finite())?;
            chi2 += ((o.unit_factor(data.units) * f_r(&o.directions()) - o.value) / s).powi(2);
        }
        Goodness::of(chi2, data.observations.len(), free)
    }

    /// Which of two fits the data favour: the larger p-value, and where
    /// both vanish (a p of 0 to double precision) the smaller reduced χ².
    pub fn closer(&self, other: &Goodness) -> std::cmp::Ordering {
        self.p_value
            .total_cmp(&other.p_value)
            .then(other.reduced_chi2.total_cmp(&self.reduced_chi2))
    }

    /// The central interval holding `level` of reduced χ² values for this
    /// many degrees of freedom (a right model with right σ).
    pub fn interval(dof: usize, level: f64) -> (f64, f64) {
        let Ok(d) = ChiSquared::new(dof.max(1) as f64) else {
            return (0.0, f64::INFINITY);
        };
        let tail = (1.0 - level) / 2.0;
        (d.inverse_cdf(tail) / dof as f64, d.inverse_cdf(1.0 - tail) / dof as f64)
    }
}

/// The free parameters' correlation matrix, with their names.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlation {
    pub names: Vec<&'static str>,
    pub rho: DMatrix<f64>,
}

impl Correlation {
    /// Pairs beyond |ρ| > `limit`, named: `("k1", "k2", 0.97)`.
    pub fn strong(&self, limit: f64) -> Vec<(&'static str, &'static str, f64)> {
        strongly_correlated(&self.rho, limit)
            .into_iter()
            .map(|(a, b, r)| (self.names[a], self.names[b], r))
            .collect()
    }
}

/// The correlation matrix of the parameters `free` (indices into the
/// covariance, `models.md` order), `None` where a variance is not positive.
pub fn correlation(covariance: &DMatrix<f64>, free: &[usize]) -> Option<DMatrix<f64>> {
    let sd: Vec<f64> = free.iter().map(|&i| covariance[(i, i)].sqrt()).collect();
    if sd.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    Some(DMatrix::from_fn(free.len(), free.len(), |a, b| {
        covariance[(free[a], free[b])] / (sd[a] * sd[b])
    }))
}

/// Pairs of parameters correlated beyond `limit` in |ρ|: (a, b, ρ).
fn strongly_correlated(rho: &DMatrix<f64>, limit: f64) -> Vec<(usize, usize, f64)> {
    let mut pairs = Vec::new();
    for a in 0..rho.nrows() {
        for b in a + 1..rho.ncols() {
            if rho[(a, b)].abs() > limit {
                pairs.push((a, b, rho[(a, b)]));
            }
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_at_its_mean_is_middling_and_far_above_it_is_unlikely() {
        let g = Goodness::of(98.0, 100, 2).unwrap();
        assert_eq!((g.dof, g.reduced_chi2), (98, 1.0));
        assert!((0.4..0.6).contains(&g.p_value), "{}", g.p_value);
        assert!(Goodness::of(200.0, 100, 2).unwrap().p_value < 1e-6);
        assert_eq!(Goodness::of(1.0, 3, 3), None);
        // χ²(0.005; 100) = 67.328, χ²(0.995; 100) = 140.169 (NIST tables).
        let (lo, hi) = Goodness::interval(100, 0.99);
        assert!(
            (lo * 100.0 - 67.328).abs() < 0.01 && (hi * 100.0 - 140.169).abs() < 0.01,
            "{lo} {hi}"
        );
    }

    #[test]
    fn correlation_of_a_covariance() {
        let c = DMatrix::from_row_slice(3, 3, &[4.0, 0.0, 3.96, 0.0, 0.0, 0.0, 3.96, 0.0, 4.0]);
        let rho = correlation(&c, &[0, 2]).unwrap();
        assert!((rho[(0, 1)] - 0.99).abs() < 1e-12 && rho[(0, 0)] == 1.0);
        assert_eq!(strongly_correlated(&rho, 0.95), [(0, 1, rho[(0, 1)])]);
        assert!(correlation(&c, &[0, 1]).is_none(), "a fixed parameter has no correlation");
    }
}
