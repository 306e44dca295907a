//! What `gonio fit`, `compare` and the demo share: the options turned into
//! the library's settings and selection, the files a fit is kept as, and
//! the comparison with its progress bars.

use super::fit_args::{FitArgs, FitOptions};
use anyhow::Result;
use gonio_acquire::operator::Operator;
use gonio_analysis::coefficients::Support;
use gonio_analysis::fit::comparison::{rational_fit, Comparison, RationalRow};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::selection::{select, Restriction, Selection};
use gonio_analysis::fit::settings::{fixed, Settings};
use gonio_analysis::fit::{self, Units, Weighting};
use gonio_analysis::formats::export::Drawn;
use gonio_analysis::rational::RationalSpec;
use gonio_brdf::ModelId;
use indicatif::{MultiProgress, ProgressBar};
use serde_json::Value;
use std::path::Path;

impl FitOptions {
    /// How the models are fitted, `fixes` (`NAME=VALUE`) held.
    pub fn settings(&self, fixes: &[String]) -> Result<Settings> {
        Ok(Settings {
            param: self.param,
            units: self.units,
            weighting: self.weights,
            seed: self.seed,
            bounds: self.bounds.iter().map(|b| b.parse()).collect::<Result<_>>()?,
            fixed: fixes.iter().map(|f| fixed(f)).collect::<Result<_>>()?,
        })
    }

    /// The samples of `path` these options fit, and those they hold out.
    pub fn select(&self, path: &Path) -> Result<Selection> {
        let data = super::load_data(path, self.units, &self.instrument)?;
        let r = Restriction {
            retro_only: self.retro_only,
            theta_i_deg: self.theta_i.clone(),
            holdout_theta_i_deg: self.holdout_theta_i.clone(),
        };
        select(data, &r, &path.display().to_string())
    }
}

/// What `gonio fit` keeps of a fit (its file JSON `v`): the reader's
/// warnings in it, the file `--out` with the data's support, and what
/// `--brdf`, `--bsdf` and `--plot` ask; returns `v`.
pub fn kept(a: &FitArgs, d: &Selection, mut v: Value, fitted: &FittedBrdf) -> Result<Value> {
    if !d.train.warnings.is_empty() {
        v["warnings"] = serde_json::json!(d.train.warnings);
    }
    if let Some(out) = &a.out {
        fit::file::write_with_support(out, &v, &Support::of(&d.train)?)?;
    }
    let drawn = Drawn {
        brdf: a.brdf.clone(),
        bsdf: a.bsdf.clone(),
        plot: a.plot.clone(),
    };
    if let Some(w) = drawn.write(fitted, &format!("a fit to {}", a.file.display()), &d.train)? {
        eprintln!("{w}");
    }
    Ok(v)
}

/// Every model fitted to the same data, in catalogue order, then the
/// rational function if asked for (`None`: models only), with progress
/// bars. A rational function that no degree allowed can make is a note,
/// not a failure of the comparison: the models still stand.
pub fn compare(d: &Selection, o: &FitOptions, rational: Option<&RationalSpec>) -> Result<Comparison> {
    // The rational function's solver is one thread, the models' fits use
    // both cores: the two run side by side, each with its bar.
    let bars = MultiProgress::new();
    let shown = |bar: ProgressBar| if o.json { bar } else { bars.add(bar) };
    let bar = shown(Operator::for_json(o.json).bar(ModelId::ALL.len() as u64, "fitting", "models"));
    let units = o.units.unwrap_or(d.train.units);
    let (models, rational_row) = rayon::join(
        || {
            let mut done = 0;
            let comparison = Comparison::of_models(d, &o.settings(&[])?, |model| {
                bar.set_message(model.name());
                bar.set_position(done);
                done += 1;
            });
            bar.finish_and_clear();
            comparison
        },
        || rational.map(|spec| row(d, spec, units, o.weights, shown(rational_bar(spec, o.json)))),
    );
    let mut comparison = models?;
    match rational_row {
        Some(Ok(row)) => comparison.rows.push(row.into()),
        Some(Err(e)) => comparison.unfitted.push(format!("{e:#}")),
        None => {}
    }
    Ok(comparison)
}

/// The bar of a rational fit, over the coefficients its spec allows.
pub fn rational_bar(spec: &RationalSpec, json: bool) -> ProgressBar {
    let most = 2 * gonio_analysis::rational::basis::Basis::size(spec.max_degree);
    Operator::for_json(json).bar(most as u64, "fitting rational", "coefficients")
}

/// The rational function through `d`'s segments as a comparison ranks it
/// (its criteria in `units` under `weighting`), `bar` moving over the
/// coefficients tried.
pub fn row(d: &Selection, spec: &RationalSpec, units: Units, weighting: Weighting, bar: ProgressBar) -> Result<RationalRow> {
    let row = rational_fit(d, spec, units, weighting, |coefficients| {
        bar.set_position(coefficients as u64);
        bar.set_message(format!("{coefficients} coefficients"));
    });
    bar.finish_and_clear();
    row
}
