//! One fit of a model comparison (`gonio compare`, the report): a model
//! fitted by least squares, or the rational function through the samples'
//! segments (Belcour et al. 2014 compare them side by side, Table 1). Both
//! are ranked by RMSE and by the same information criteria.

use super::criteria::Criteria;
use super::file::FittedBrdf;
use super::goodness::Goodness;
use super::{Fit, Metrics, Units};
use crate::coefficients::Fitted;
use crate::rational::RationalFit;
use serde_json::Value;

#[derive(Debug, Clone)]
pub enum ComparedFit {
    Model(Fit),
    /// The rational function, with its criteria under the comparison's
    /// weighting (it was not fitted by least squares, so none of its own).
    Rational {
        fit: RationalFit,
        criteria: Criteria,
        /// χ² against the samples' σ, where they have one.
        goodness: Option<Goodness>,
    },
}

impl ComparedFit {
    /// The model's id, `rational` for the rational function.
    pub fn name(&self) -> &'static str {
        match self {
            ComparedFit::Model(f) => f.material.model.name(),
            ComparedFit::Rational { .. } => crate::rational::file::MODEL,
        }
    }

    /// Against the fitted samples, in the data's units.
    pub fn metrics(&self) -> &Metrics {
        match self {
            ComparedFit::Model(f) => &f.metrics,
            ComparedFit::Rational { fit, .. } => &fit.metrics,
        }
    }

    /// The coefficients the fit chose: a model's parameters (fixed ones
    /// too), the rational function's numerator and denominator.
    pub fn coefficients(&self) -> usize {
        match self {
            ComparedFit::Model(f) => f.material.params.len(),
            ComparedFit::Rational { fit, .. } => fit.function.coefficients(),
        }
    }

    pub fn criteria(&self) -> Criteria {
        match self {
            ComparedFit::Model(f) => Criteria { aic: f.aic, bic: f.bic },
            ComparedFit::Rational { criteria, .. } => *criteria,
        }
    }

    /// χ² against the samples' σ (`None` where they have none).
    pub fn goodness(&self) -> Option<&Goodness> {
        match self {
            ComparedFit::Model(f) => f.goodness.as_ref(),
            ComparedFit::Rational { goodness, .. } => goodness.as_ref(),
        }
    }

    pub fn seconds(&self) -> f64 {
        match self {
            ComparedFit::Model(f) => f.seconds,
            ComparedFit::Rational { fit, .. } => fit.seconds,
        }
    }

    /// The BRDF the fit found, to evaluate, draw and export.
    pub fn brdf(&self) -> FittedBrdf {
        match self {
            ComparedFit::Model(f) => FittedBrdf::Model(f.material.clone()),
            ComparedFit::Rational { fit, .. } => FittedBrdf::Rational(fit.function.clone()),
        }
    }

    /// What the coefficients of retroreflection weigh it by.
    pub fn fitted(&self) -> Fitted {
        match self {
            ComparedFit::Model(f) => Fitted::from(f),
            ComparedFit::Rational { fit, criteria, goodness } => Fitted {
                brdf: self.brdf(),
                covariance: None,
                rmse: fit.metrics.rmse,
                aic: criteria.aic,
                goodness: *goodness,
            },
        }
    }

    /// Its fit file's JSON (`gonio fit --out`'s), with the metrics of
    /// held-out samples if any.
    pub fn to_json(&self, units: Units, holdout: Option<&Metrics>) -> Value {
        match self {
            ComparedFit::Model(f) => super::file::to_json(f, units, holdout),
            ComparedFit::Rational { fit, criteria, goodness } => {
                crate::rational::file::to_json(fit, units, criteria, goodness.as_ref(), holdout)
            }
        }
    }
}

/// The indices of `keys` from the lowest (the best fit's RMSE, AIC or BIC)
/// to the highest: the order a comparison ranks and a report lists by.
pub fn best_first(keys: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..keys.len()).collect();
    order.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
    order
}
