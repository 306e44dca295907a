//! `gonio fit --model rational` and `compare`'s rational row: the rational function through every
//! sample's segment (`gonio_analysis::rational`), as text or JSON, and its
//! fit file.

use super::fitting::FitArgs;
use anyhow::{bail, Result};
use gonio_acquire::operator::Operator;
use gonio_analysis::fit::comparison::{rational_fit, RationalRow};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::selection::Selection;
use gonio_analysis::fit::{Units, Weighting};
use gonio_analysis::rational::text::{self, RationalText};
use gonio_analysis::rational::RationalSpec;

/// The rational function through `d`'s segments as a comparison ranks it
/// (its criteria in `units` under `weighting`), with a progress bar over
/// the coefficients tried.
pub fn row(d: &Selection, spec: &RationalSpec, units: Units, weighting: Weighting, json: bool) -> Result<RationalRow> {
    let most = 2 * gonio_analysis::rational::basis::Basis::size(spec.max_degree);
    let bar = Operator::for_json(json).bar(most as u64, "fitting rational", "coefficients");
    let row = rational_fit(d, spec, units, weighting, |coefficients| {
        bar.set_position(coefficients as u64);
        bar.set_message(format!("{coefficients} coefficients"));
    });
    bar.finish_and_clear();
    row
}

pub fn fit_cmd(a: FitArgs) -> Result<()> {
    let o = &a.options;
    if !a.fix.is_empty() || !o.bounds.is_empty() || o.weights != Weighting::Uniform {
        bail!("--fix, --bounds and --weights are options of the parametric models: a rational function has no parameters to hold or box, and no least-squares sum to weigh (its --segments say how close it must pass)");
    }
    let spec = a.rational.spec(o.param)?;
    let d = o.select(&a.file)?;
    let row = row(&d, &spec, o.units.unwrap_or(d.train.units), Weighting::Uniform, o.json)?;
    let (f, holdout) = (&row.fit, &row.holdout);
    let v = super::fitting::kept(&a, &d, row.to_json(), &FittedBrdf::Rational(f.function.clone()))?;
    if o.json {
        println!("{v}");
        return Ok(());
    }
    let holdout = holdout.as_ref().map(|h| (o.holdout_theta_i.as_slice(), h));
    print!("{}", RationalText { fit: f, holdout });
    for n in text::notes(f) {
        eprintln!("{n}");
    }
    Ok(())
}
