//! A rational fit as one JSON object: the function whole (plane, degree,
//! box, coefficients), so that it can be read back and evaluated, with
//! the figures every fit reports and what the segments were.

use super::fit::RationalFit;
use super::function::Rational;
use crate::fit::criteria::Criteria;
use crate::fit::goodness::Goodness;
use crate::fit::{Metrics, Units};
use anyhow::{bail, Context, Result};
use serde_json::{json, Value};

/// The model name a rational fit carries in its file.
pub const MODEL: &str = "rational";

/// The JSON object of a fit, with its information criteria (under the
/// weighting it is ranked by) and the metrics of held-out samples if any.
pub fn to_json(f: &RationalFit, units: Units, criteria: &Criteria, goodness: Option<&Goodness>, holdout: Option<&Metrics>) -> Value {
    let r = &f.function;
    let mut v = json!({
        "model": MODEL,
        "parametrization": r.coordinates,
        "degree": r.degree,
        "terms": r.numerator.len(),
        "cosine": r.cosine,
        "quantity": r.quantity,
        "coefficients": r.coefficients(),
        "domain": r.domain,
        "order": r.order,
        "numerator": r.numerator,
        "denominator": r.denominator,
        "segments": f.segments,
        "segment_k": f.segment_k,
        "shifted_segments": f.shifted,
        "worst_violation": f.worst_violation,
        "precision": if f.single_precision { "single" } else { "double" },
        "rmse": f.metrics.rmse, "nrmse": f.metrics.nrmse, "ncc": f.metrics.ncc, "l2": f.metrics.l2,
        "linf": f.linf,
        "samples": f.samples, "seconds": f.seconds, "units": units,
        "aic": criteria.aic, "bic": criteria.bic,
        "attempts": f.attempts,
    });
    if let Some(c) = &f.capped {
        v["capped"] = json!(c);
    }
    if let Some(d) = &f.densified {
        v["densified"] = json!(d);
    }
    if let Some(g) = goodness {
        v["goodness"] = json!(g);
    }
    if let Some(h) = holdout {
        v["holdout"] = json!(h);
    }
    v
}

/// The function of a fit file's JSON (`model` = `rational`).
pub fn function_of(v: &Value) -> Result<Rational> {
    if v["model"] != MODEL {
        bail!("not a rational fit (model `{}`)", v["model"].as_str().unwrap_or("?"));
    }
    let r: Rational =
        serde_json::from_value(v.clone()).context("a rational fit needs parametrization, degree, domain, numerator and denominator")?;
    if r.degree > super::RationalSpec::HIGHEST_DEGREE {
        bail!(
            "degree {}: a rational fit is at most of degree {}",
            r.degree,
            super::RationalSpec::HIGHEST_DEGREE
        );
    }
    let n = r.numerator.len();
    if n == 0 || r.denominator.len() != n || super::basis::Basis::degree_of(n) != r.degree {
        bail!(
            "degree {} has from {} to {} terms, the same in numerator and denominator, but the numerator has {n} and the denominator {}",
            r.degree,
            super::basis::Basis::size(r.degree.saturating_sub(1)) + usize::from(r.degree > 0),
            super::basis::Basis::size(r.degree),
            r.denominator.len()
        );
    }
    if r.numerator.iter().chain(&r.denominator).any(|c| !c.is_finite()) || r.domain.lo.iter().zip(&r.domain.hi).any(|(l, h)| h <= l) {
        bail!("a coefficient is not a number, or the domain is empty");
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rational::basis::{Coordinates, Domain, TermOrder};

    #[test]
    fn a_function_survives_its_file_and_bad_files_are_refused() {
        let r = Rational {
            coordinates: Coordinates::LightView,
            degree: 1,
            cosine: true,
            quantity: Units::FrCos,
            domain: Domain {
                lo: [10.0, -5.0, -1.0],
                hi: [60.0, 5.0, 1.0],
            },
            order: TermOrder::Alta,
            numerator: vec![1.0, 0.1, 0.2, 0.3],
            denominator: vec![2.0, 0.0, 0.0, 0.1],
        };
        let mut v = serde_json::to_value(&r).unwrap();
        v["model"] = json!(MODEL);
        assert_eq!(function_of(&v).unwrap(), r);
        let d = gonio_brdf::Directions::from_degrees(30.0, 20.0, 10.0);
        assert_eq!(function_of(&v).unwrap().eval(&d), r.eval(&d));
        let mut short = v.clone();
        short["numerator"] = json!([1.0]);
        assert!(function_of(&short).unwrap_err().to_string().contains("from 2 to 4 terms"));
        // A file without `cosine` was fitted with the factor; one without
        // `order` has its terms in the order used before ALTA's, which at
        // degree 1 puts θi, x′, y′ alike.
        let mut old = v.clone();
        old.as_object_mut().unwrap().remove("cosine");
        old.as_object_mut().unwrap().remove("order");
        old.as_object_mut().unwrap().remove("quantity");
        let read = function_of(&old).unwrap();
        assert!(read.cosine);
        assert_eq!(read.quantity, Units::Fr);
        assert_eq!(read.order, TermOrder::FirstFalling);
        let mut other = v.clone();
        other["model"] = json!("lambert");
        assert!(function_of(&other).is_err());
        let mut empty = v;
        empty["domain"]["hi"][0] = json!(10.0);
        assert!(function_of(&empty).is_err());
    }
}
