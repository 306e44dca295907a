//! A model comparison (`gonio compare`, the demo's report): every model of
//! the catalogue fitted to one selection of samples, then the rational
//! function through their segments, each row with its held-out metrics and
//! its fit file's JSON; ranked by RMSE, AIC and BIC (Spieringhs Table 6,
//! Belcour Table 1), with R_A and R_L from the data and the fits beyond.

use super::compared::{best_first, ComparedFit};
use super::criteria::Criteria;
use super::goodness::Goodness;
use super::selection::Selection;
use super::settings::Settings;
use super::{Fit, Metrics, Units, Weighting};
use crate::calibration::IncidenceBudget;
use crate::coefficients::{self, Coefficient, Source, Support};
use crate::rational::{self, RationalSpec};
use anyhow::{Context, Result};
use gonio_brdf::ModelId;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One fit of a comparison, its held-out metrics and its fit file's JSON.
#[derive(Debug, Clone)]
pub struct Row {
    pub fit: ComparedFit,
    pub holdout: Option<Metrics>,
    pub json: Value,
}

/// `model` fitted to `s` (its held-out samples evaluated): one fit's, or
/// with `every_model` a comparison's row.
pub fn model_fit(s: &Selection, settings: &Settings, model: ModelId, every_model: bool) -> Result<(Fit, Option<Metrics>)> {
    let spec = settings.fit_spec(model, s.train.units, every_model)?;
    let f = super::fit(&s.train, &spec).with_context(|| format!("fitting {}", model.name()))?;
    let holdout = s.holdout.as_ref().map(|h| super::evaluate(&f.material, h));
    Ok((f, holdout))
}

/// A rational fit with what a comparison ranks it by: its criteria, its
/// χ² where the samples have σ, and its held-out metrics.
#[derive(Debug, Clone)]
pub struct RationalRow {
    pub fit: rational::RationalFit,
    pub criteria: Criteria,
    pub goodness: Option<Goodness>,
    pub holdout: Option<Metrics>,
}

impl RationalRow {
    /// Its fit file's JSON (in the samples' own units).
    pub fn to_json(&self) -> Value {
        rational::file::to_json(
            &self.fit,
            self.fit.function.quantity,
            &self.criteria,
            self.goodness.as_ref(),
            self.holdout.as_ref(),
        )
    }
}

impl From<RationalRow> for Row {
    fn from(r: RationalRow) -> Row {
        let json = r.to_json();
        Row {
            fit: ComparedFit::Rational {
                fit: r.fit,
                criteria: r.criteria,
                goodness: r.goodness,
            },
            holdout: r.holdout,
            json,
        }
    }
}

/// The rational function through `s`'s segments, its criteria in `units`
/// under `weighting`, as the models are ranked; `trying` hears of each
/// count of coefficients tried.
pub fn rational_fit(
    s: &Selection,
    spec: &RationalSpec,
    units: Units,
    weighting: Weighting,
    trying: impl FnMut(usize),
) -> Result<RationalRow> {
    let fit = rational::fit_observed(&s.train, spec, trying).context("fitting rational")?;
    let holdout = s.holdout.as_ref().map(|h| fit.function.against(h).0);
    let criteria = Criteria::of_brdf(&s.train, units, weighting, fit.function.coefficients(), |x| fit.function.eval(x))?;
    let goodness = Goodness::of_brdf(&s.train, fit.function.coefficients(), |x| fit.function.eval(x));
    Ok(RationalRow {
        fit,
        criteria,
        goodness,
        holdout,
    })
}

/// Every fit of a comparison, and the fits it tried and could not make.
pub struct Comparison {
    pub rows: Vec<Row>,
    pub unfitted: Vec<String>,
}

impl Comparison {
    /// Every model in catalogue order, `on_model` told of each before its
    /// fit; a model that cannot be fitted fails the comparison.
    pub fn of_models(s: &Selection, settings: &Settings, mut on_model: impl FnMut(ModelId)) -> Result<Comparison> {
        let mut rows = Vec::new();
        for model in ModelId::ALL {
            on_model(model);
            let (f, holdout) = model_fit(s, settings, model, true)?;
            let fit = ComparedFit::Model(f);
            let json = fit.to_json(s.train.units, holdout.as_ref());
            rows.push(Row { fit, holdout, json });
        }
        Ok(Comparison {
            rows,
            unfitted: Vec::new(),
        })
    }

    /// Each row's rank (1 = best) by RMSE, AIC and BIC.
    /// The row of the lowest RMSE (`None` when nothing was fitted).
    pub fn best(&self) -> Option<&Row> {
        self.rows
            .iter()
            .min_by(|x, y| x.fit.metrics().rmse.total_cmp(&y.fit.metrics().rmse))
    }

    /// The comparison as `gonio compare --json` prints it: every fit's
    /// file JSON with its `rank` by RMSE, AIC and BIC, and the notes of
    /// what was not fitted.
    pub fn into_json(self) -> Value {
        let ranks = self.ranks();
        let fits: Vec<Value> = self
            .rows
            .into_iter()
            .zip(&ranks)
            .map(|(r, k)| {
                let mut v = r.json;
                v["rank"] = serde_json::json!({"rmse": k[0], "aic": k[1], "bic": k[2]});
                v
            })
            .collect();
        serde_json::json!({"fits": fits, "unfitted": self.unfitted})
    }

    pub fn ranks(&self) -> Vec<[usize; 3]> {
        let rows = &self.rows;
        let key = |f: &ComparedFit, c: usize| match c {
            0 => f.metrics().rmse,
            1 => f.criteria().aic,
            _ => f.criteria().bic,
        };
        let by = |c: usize| {
            let keys: Vec<f64> = rows.iter().map(|r| key(&r.fit, c)).collect();
            let mut rank = vec![0; rows.len()];
            for (r, i) in best_first(&keys).into_iter().enumerate() {
                rank[i] = r + 1;
            }
            rank
        };
        let (rmse, aic, bic) = (by(0), by(1), by(2));
        (0..rows.len()).map(|i| [rmse[i], aic[i], bic[i]]).collect()
    }

    /// R_A and R_L as the report gives them: from the data where they hold
    /// the geometry, from the fits beyond.
    pub fn coefficients(&self, s: &Selection) -> Result<Vec<Coefficient>> {
        let fits = self.rows.iter().map(|r| r.fit.fitted()).collect();
        let source = Source::measured(fits, Support::of(&s.train)?)?;
        coefficients::compute(&source, &coefficients::report_requests())
    }

    /// Writes `dir/report.html`; returns its path.
    pub fn report(
        &self,
        dir: &Path,
        title: String,
        facts: Vec<(String, String)>,
        s: &Selection,
        budget: &[IncidenceBudget],
    ) -> Result<PathBuf> {
        let fits: Vec<ComparedFit> = self.rows.iter().map(|r| r.fit.clone()).collect();
        let holdout: Vec<_> = self.rows.iter().map(|r| r.holdout).collect();
        crate::report::write(
            dir,
            &crate::report::Report {
                title,
                facts,
                data: &s.train,
                fits: &fits,
                unfitted: &self.unfitted,
                holdout: &holdout,
                budget,
            },
        )
    }
}
