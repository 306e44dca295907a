//! `gonio fit` and `gonio compare`: models fitted to a data file (ALTA `.dat`
//! or the calibrated sample CSV).

use super::fitting::{write_drawn, CompareArgs, FitArgs, FitOptions};
use anyhow::{bail, Result};
use gonio_acquire::operator::Operator;
use gonio_analysis::coefficients::Support;
use gonio_analysis::fit;
use gonio_analysis::fit::compared::ComparedFit;
use gonio_analysis::fit::comparison::{model_fit, Comparison};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::selection::Selection;
use gonio_analysis::rational::RationalSpec;
use gonio_analysis::rounding::{figure, significant};
use gonio_brdf::ModelId;
use serde_json::Value;

pub fn fit_cmd(a: FitArgs) -> Result<()> {
    if a.model == gonio_analysis::rational::file::MODEL {
        return super::rational::fit_cmd(a);
    }
    if a.rational.given() {
        bail!(
            "--segments, --max-degree and --no-cosine are options of --model rational, not of {}",
            a.model
        );
    }
    let model = ModelId::parse(&a.model)
        .map_err(|e| anyhow::anyhow!("{e}, or `{}` (the rational function)", gonio_analysis::rational::file::MODEL))?;
    let d = a.options.select(&a.file)?;
    let (f, holdout) = model_fit(&d, &a.options.settings(&a.fix)?, model, false)?;
    let mut v = fit::file::to_json(&f, d.train.units, holdout.as_ref());
    if !d.train.warnings.is_empty() {
        v["warnings"] = serde_json::json!(d.train.warnings);
    }
    if let Some(out) = &a.out {
        fit::file::write_with_support(out, &v, &Support::of(&d.train)?)?;
    }
    write_drawn(&FittedBrdf::Model(f.material.clone()), &a, &d.train)?;
    if a.options.json {
        println!("{v}");
        return Ok(());
    }
    println!("{} ({} samples, {:.2} s)", model.name(), f.samples, f.seconds);
    for (k, n) in model.param_names().iter().enumerate() {
        let fixed = a.fix.iter().any(|s| s.split('=').next().map(str::trim) == Some(n));
        println!("  {n:>8} = {}{}", f.parameter_text(k), if fixed { " (fixed)" } else { "" });
    }
    println!("  {}  AIC {:.1}  BIC {:.1}", f.metrics.summary(), f.aic, f.bic);
    if let Some(g) = &f.goodness {
        println!("  {}", goodness_text(g));
    }
    if let Some(c) = &f.correlation {
        for (a, b, r) in c.strong(STRONG_CORRELATION) {
            println!(
                "  {a} and {b} are correlated, ρ = {}: the data tell mostly their combination",
                figure(r, 3)
            );
        }
    }
    for (name, b) in &f.widened {
        eprintln!(
            "note: {name} ended on the edge of its default box, which is no physical limit: the box grew to [{}, {}] and the fit went on",
            significant(b.lo, 3),
            significant(b.hi, 3)
        );
    }
    for name in &f.at_bound {
        eprintln!(
            "warning: {name} ended on the edge of its search box: the optimum may lie beyond it (widen the box with --bounds {name}=LO:HI)"
        );
    }
    if let Some(h) = &holdout {
        println!("  held out θi {:?}°: {}", a.options.holdout_theta_i, h.summary());
    }
    Ok(())
}

/// |ρ| beyond which two parameters are named as correlated.
const STRONG_CORRELATION: f64 = 0.95;

/// χ² in words: its degrees of freedom, the reduced value against its 99 %
/// interval for a right model with right σ, and the p-value.
fn goodness_text(g: &Goodness) -> String {
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

/// Every model fitted to the same data, in catalogue order, then the
/// rational function if asked for (`None`: models only), with progress
/// bars. A rational function that no degree allowed can make is a note,
/// not a failure of the comparison: the models still stand.
pub fn compare(d: &Selection, o: &FitOptions, rational: Option<&RationalSpec>) -> Result<Comparison> {
    let bar = Operator::for_json(o.json).bar(ModelId::ALL.len() as u64, "fitting", "models");
    let mut done = 0;
    let mut comparison = Comparison::of_models(d, &o.settings(&[])?, |model| {
        bar.set_message(model.name());
        bar.set_position(done);
        done += 1;
    })?;
    bar.finish_and_clear();
    if let Some(spec) = rational {
        match super::rational::row(d, spec, o.units.unwrap_or(d.train.units), o.weights, o.json) {
            Ok(row) => comparison.rows.push(row.into()),
            Err(e) => comparison.unfitted.push(format!("{e:#}")),
        }
    }
    Ok(comparison)
}

pub fn compare_cmd(a: CompareArgs) -> Result<()> {
    if let Some(dir) = a.report.as_ref().filter(|d| d.join("report.html").exists() && !a.force) {
        bail!("{} already holds a report; choose another --report or pass --force", dir.display());
    }
    let rational = a.rational.spec(a.options.param)?;
    let d = a.options.select(&a.file)?;
    let comparison = compare(&d, &a.options, Some(&rational))?;
    if let Some(dir) = &a.report {
        let mut facts = vec![("data".to_string(), a.file.display().to_string())];
        facts.extend(d.train.metadata.iter().map(|m| ("metadata".to_string(), m.clone())));
        let path = comparison.report(dir, format!("Model comparison: {}", a.file.display()), facts, &d, &[])?;
        if !a.options.json {
            eprintln!("report: {}", path.display());
        }
    }
    let ranks = comparison.ranks();
    let Comparison { rows, unfitted } = comparison;
    if a.options.json {
        let fits: Vec<Value> = rows
            .into_iter()
            .zip(&ranks)
            .map(|(r, k)| {
                let mut v = r.json;
                v["rank"] = serde_json::json!({"rmse": k[0], "aic": k[1], "bic": k[2]});
                v
            })
            .collect();
        println!("{}", serde_json::json!({"fits": fits, "unfitted": unfitted}));
        return Ok(());
    }
    println!(
        "{} samples ({}); best first by RMSE, with the ranks by AIC and BIC (which charge each coefficient)",
        d.train.observations.len(),
        d.train.units.label()
    );
    println!(
        "{:<18} {:>6} {:>12} {:>12} {:>9} {:>13} {:>13} {:>4} {:>4} {:>8} {:>8}  at bound",
        "model", "coeffs", "RMSE", "NRMSE", "NCC", "AIC", "BIC", "#AIC", "#BIC", "s", "χ²/dof"
    );
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
                format!("(degree {}, segments {})", fit.function.degree, fit.segments),
            ),
        };
        println!(
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
        );
    }
    for why in &unfitted {
        eprintln!("note: not fitted: {why}");
    }
    Ok(())
}
