//! `gonio fit --model rational` and `compare`'s rational row: the rational function through every
//! sample's segment (`gonio_analysis::rational`), as text or JSON, and its
//! fit file.

use super::fit_args::FitArgs;
use super::fitting::{rational_bar, row};
use anyhow::{bail, Result};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::Weighting;
use gonio_analysis::rational::text::{self, RationalText};

pub fn fit_cmd(a: FitArgs) -> Result<()> {
    let o = &a.options;
    if !a.fix.is_empty() || !o.bounds.is_empty() || o.weights != Weighting::Uniform {
        bail!("--fix, --bounds and --weights are options of the parametric models: a rational function has no parameters to hold or box, and no least-squares sum to weigh (its --segments say how close it must pass)");
    }
    let spec = a.rational.rational_spec(o.param)?;
    let d = o.select(&a.file)?;
    let row = row(
        &d,
        &spec,
        o.units.unwrap_or(d.train.units),
        Weighting::Uniform,
        rational_bar(&spec, o.json),
    )?;
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
