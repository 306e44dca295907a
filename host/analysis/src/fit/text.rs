//! Fits as text for a terminal, as `gonio fit` and `compare` print them:
//! parameters rounded to their standard errors, χ² in words, the ranked
//! table. What the user should act on (a widened or binding search box)
//! comes apart as notes, for stderr.

use super::compared::ComparedFit;
use super::comparison::Comparison;
use super::goodness::Goodness;
use super::{Fit, Metrics, Units};
use crate::rounding::{figure, significant};
use std::fmt;

/// |ρ| beyond which two parameters are named as correlated.
const STRONG_CORRELATION: f64 = 0.95;

/// One model's fit: its parameters (`fixed` names those held), its metrics
/// and χ², the parameters it cannot tell apart, and how it predicts the
/// incidences held out.
pub struct FitText<'a> {
    pub fit: &'a Fit,
    pub fixed: &'a [String],
    pub holdout: Option<(&'a [f64], &'a Metrics)>,
}

impl fmt::Display for FitText<'_> {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        let f = self.fit;
        let model = f.material.model;
        writeln!(out, "{} ({} samples, {:.2} s)", model.name(), f.samples, f.seconds)?;
        for (k, n) in model.param_names().iter().enumerate() {
            let fixed = self.fixed.iter().any(|s| s == n);
            writeln!(out, "  {n:>8} = {}{}", f.parameter_text(k), if fixed { " (fixed)" } else { "" })?;
        }
        writeln!(out, "  {}  AIC {:.1}  BIC {:.1}", f.metrics.summary(), f.aic, f.bic)?;
        if let Some(g) = &f.goodness {
            writeln!(out, "  {}", goodness_text(g))?;
        }
        if let Some(c) = &f.correlation {
            for (a, b, r) in c.strong(STRONG_CORRELATION) {
                writeln!(
                    out,
                    "  {a} and {b} are correlated, ρ = {}: the data tell mostly their combination",
                    figure(r, 3)
                )?;
            }
        }
        if let Some((theta_i, h)) = self.holdout {
            writeln!(out, "  held out θi {theta_i:?}°: {}", h.summary())?;
        }
        Ok(())
    }
}

/// What the user should know of a fit's search boxes: boxes it widened
/// (notes), and parameters that ended on an edge (warnings).
pub fn box_notes(f: &Fit) -> Vec<String> {
    let widened = f.widened.iter().map(|(name, b)| {
        format!(
            "note: {name} ended on the edge of its default box, which is no physical limit: the box grew to [{}, {}] and the fit went on",
            significant(b.lo, 3),
            significant(b.hi, 3)
        )
    });
    let bound = f.at_bound.iter().map(|name| {
        format!(
            "warning: {name} ended on the edge of its search box: the optimum may lie beyond it (widen the box with --bounds {name}=LO:HI)"
        )
    });
    widened.chain(bound).collect()
}

/// χ² in words: its degrees of freedom, the reduced value against its 99 %
/// interval for a right model with right σ, and the p-value.
pub fn goodness_text(g: &Goodness) -> String {
    let (lo, hi) = Goodness::interval(g.dof, 0.99);
    let verdict = if g.reduced_chi2 > hi {
        "the model misses the data by more than their uncertainty"
    } else if g.reduced_chi2 < lo {
        "closer than the uncertainties allow: they are overstated"
    } else {
        "adequate within the stated uncertainties"
    };
    format!(
        "χ² = {} for {} degrees of freedom: reduced {} (99 % of a right fit: {}–{}), p = {}; {verdict}",
        significant(g.chi2, 4),
        g.dof,
        significant(g.reduced_chi2, 3),
        significant(lo, 2),
        significant(hi, 2),
        significant(g.p_value, 2)
    )
}

/// A comparison ranked best first by RMSE, with its ranks by AIC and BIC,
/// over `samples` samples in `units`.
pub struct ComparisonTable<'a> {
    pub comparison: &'a Comparison,
    pub samples: usize,
    pub units: Units,
}

impl fmt::Display for ComparisonTable<'_> {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rows = &self.comparison.rows;
        let ranks = self.comparison.ranks();
        writeln!(
            out,
            "{} samples ({}); best first by RMSE, with the ranks by AIC and BIC (which charge each coefficient)",
            self.samples,
            self.units.label()
        )?;
        writeln!(
            out,
            "{:<18} {:>6} {:>12} {:>12} {:>9} {:>13} {:>13} {:>4} {:>4} {:>8} {:>8}  at bound",
            "model", "coeffs", "RMSE", "NRMSE", "NCC", "AIC", "BIC", "#AIC", "#BIC", "s", "χ²/dof"
        )?;
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by_key(|&i| ranks[i][0]);
        for i in order {
            let f = &rows[i].fit;
            let (m, c) = (f.metrics(), f.criteria());
            let (goodness, at_bound) = match f {
                ComparedFit::Model(f) => (
                    f.goodness.map_or("–".to_string(), |g| significant(g.reduced_chi2, 3)),
                    f.at_bound.join(", "),
                ),
                ComparedFit::Rational { fit, .. } => (
                    "–".to_string(),
                    format!("(degree {}, segments {})", fit.function.degree, fit.segments_text()),
                ),
            };
            writeln!(
                out,
                "{:<18} {:>6} {:>12} {:>12} {:>9} {:>13.1} {:>13.1} {:>4} {:>4} {:>8.2} {:>8}  {at_bound}",
                f.name(),
                f.coefficients(),
                significant(m.rmse, 4),
                significant(m.nrmse, 4),
                figure(m.ncc, 5),
                c.aic,
                c.bic,
                ranks[i][1],
                ranks[i][2],
                f.seconds(),
                goodness,
            )?;
        }
        Ok(())
    }
}
