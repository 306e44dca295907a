//! Whether a fit is adequate within the stated uncertainties: with every
//! residual weighted by its sample's σ (`--weights sigma`) the cost is χ²,
//! which a right model with right σ draws from the χ² distribution of
//! N − k degrees of freedom; and how the parameters' estimates move
//! together (their correlation matrix from the covariance).

use nalgebra::DMatrix;
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// χ² of a fit weighted by the samples' σ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
        let dof = samples.checked_sub(free).filter(|&d| d > 0)?;
        let p_value = ChiSquared::new(dof as f64).ok()?.sf(chi2);
        Some(Goodness {
            chi2,
            dof,
            reduced_chi2: chi2 / dof as f64,
            p_value,
        })
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
