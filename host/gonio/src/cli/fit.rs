//! `gonio fit` and `gonio compare`: models fitted to a data file (ALTA `.dat`
//! or the calibrated sample CSV).

use super::fitting::{domain, write_drawn, CompareArgs, Domain, FitArgs, FitOptions, Outcome};
use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::{Coefficient, Source, Support};
use gonio_analysis::fit::compared::ComparedFit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::{self, Dataset, Fit, FitSpec};
use gonio_analysis::rational::RationalSpec;
use gonio_analysis::rounding::{figure, significant};
use gonio_brdf::ModelId;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// `--bounds` for one model: `(index, lo, hi)`. With `every_model`
/// (`compare`), names the model lacks are skipped, unless no model has them.
fn boxes(model: ModelId, given: &[String], every_model: bool) -> Result<Vec<(usize, f64, f64)>> {
    let mut out = Vec::new();
    for g in given {
        let parsed = g.split_once('=').and_then(|(n, r)| {
            let (lo, hi) = r.split_once(':')?;
            Some((n.trim(), lo.trim().parse::<f64>().ok()?, hi.trim().parse::<f64>().ok()?))
        });
        let Some((name, lo, hi)) = parsed else {
            bail!("--bounds `{g}` is not NAME=LO:HI");
        };
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            bail!("--bounds {name}: the box [{lo}, {hi}] must be finite with LO < HI");
        }
        match model.param_index(name) {
            Ok(i) => out.push((i, lo, hi)),
            Err(_) if every_model && ModelId::ALL.iter().any(|m| m.param_index(name).is_ok()) => {}
            Err(e) => return Err(e.context("--bounds")),
        }
    }
    Ok(out)
}

fn spec(model: ModelId, fixes: &[String], o: &FitOptions, data: &Dataset, every_model: bool) -> Result<FitSpec> {
    let mut fixed = Vec::new();
    for f in fixes {
        let (name, v) = f.split_once('=').with_context(|| format!("--fix `{f}` is not NAME=VALUE"))?;
        let i = model.param_index(name.trim())?;
        let v: f64 = v.trim().parse().with_context(|| format!("--fix {name}: `{v}` is not a number"))?;
        fixed.push((i, v));
    }
    Ok(FitSpec {
        param: o.param.into(),
        units: o.units.unwrap_or(data.units),
        weighting: o.weights,
        fixed,
        bounds: boxes(model, &o.bounds, every_model)?,
        seed: o.seed,
        ..FitSpec::new(model)
    })
}

/// Every fit of a comparison, and the fits it tried and could not make.
pub struct Comparison {
    pub rows: Vec<Outcome>,
    pub unfitted: Vec<String>,
}

fn run_one(model: ModelId, fixes: &[String], o: &FitOptions, d: &Domain, every_model: bool) -> Result<(Fit, Option<fit::Metrics>)> {
    let spec = spec(model, fixes, o, &d.train, every_model)?;
    let f = fit::fit(&d.train, &spec).with_context(|| format!("fitting {}", model.name()))?;
    let holdout = d.holdout.as_ref().map(|h| fit::evaluate(&f.material, h));
    Ok((f, holdout))
}

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
    let d = domain(&a.file, &a.options)?;
    let (f, holdout) = run_one(model, &a.fix, &a.options, &d, false)?;
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
/// rational function if asked for (`None`: models only). A rational
/// function that no degree allowed can make is a note, not a failure of
/// the comparison: the models still stand.
pub fn compare(d: &Domain, o: &FitOptions, rational: Option<&RationalSpec>) -> Result<Comparison> {
    let bar = gonio_acquire::operator::Operator::for_json(o.json).bar(ModelId::ALL.len() as u64, "fitting", "models");
    let mut rows = Vec::new();
    for model in ModelId::ALL {
        bar.set_message(model.name());
        let (f, holdout) = run_one(model, &[], o, d, true)?;
        let fit = ComparedFit::Model(f);
        let json = fit.to_json(d.train.units, holdout.as_ref());
        rows.push(Outcome { fit, holdout, json });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut unfitted = Vec::new();
    if let Some(spec) = rational {
        match super::rational::compared(d, spec, o.units.unwrap_or(d.train.units), o.weights, o.json) {
            Ok(row) => rows.push(row),
            Err(e) => unfitted.push(format!("{e:#}")),
        }
    }
    Ok(Comparison { rows, unfitted })
}

/// R_A and R_L of a comparison, as its report gives them: from the data
/// where they hold the geometry, from the models' fits beyond.
pub fn coefficients(d: &Domain, rows: &[Outcome]) -> Result<Vec<Coefficient>> {
    let fits = rows.iter().map(|r| r.fit.fitted()).collect();
    let source = Source::measured(fits, Support::of(&d.train)?)?;
    gonio_analysis::coefficients::compute(&source, &gonio_analysis::coefficients::report_requests())
}

/// Writes `dir/report.html` of a comparison.
pub fn report(
    dir: &Path,
    title: String,
    facts: Vec<(String, String)>,
    d: &Domain,
    comparison: &Comparison,
    budget: &[gonio_analysis::calibration::IncidenceBudget],
) -> Result<PathBuf> {
    let rows = &comparison.rows;
    let fits: Vec<ComparedFit> = rows.iter().map(|r| r.fit.clone()).collect();
    let holdout: Vec<_> = rows.iter().map(|r| r.holdout).collect();
    gonio_analysis::report::write(
        dir,
        &gonio_analysis::report::Report {
            title,
            facts,
            data: &d.train,
            fits: &fits,
            unfitted: &comparison.unfitted,
            holdout: &holdout,
            budget,
        },
    )
}

pub fn compare_cmd(a: CompareArgs) -> Result<()> {
    if let Some(dir) = a.report.as_ref().filter(|d| d.join("report.html").exists() && !a.force) {
        bail!("{} already holds a report; choose another --report or pass --force", dir.display());
    }
    let rational = a.rational.spec(a.options.param)?;
    let d = domain(&a.file, &a.options)?;
    let comparison = compare(&d, &a.options, Some(&rational))?;
    if let Some(dir) = &a.report {
        let mut facts = vec![("data".to_string(), a.file.display().to_string())];
        facts.extend(d.train.metadata.iter().map(|m| ("metadata".to_string(), m.clone())));
        let path = report(dir, format!("Model comparison: {}", a.file.display()), facts, &d, &comparison, &[])?;
        if !a.options.json {
            eprintln!("report: {}", path.display());
        }
    }
    let Comparison { rows, unfitted } = comparison;
    let ranks = ranks(&rows);
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

/// Each fit's rank (1 = best) by RMSE, AIC and BIC.
fn ranks(rows: &[Outcome]) -> Vec<[usize; 3]> {
    let key = |f: &ComparedFit, c: usize| match c {
        0 => f.metrics().rmse,
        1 => f.criteria().aic,
        _ => f.criteria().bic,
    };
    let by = |c: usize| {
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by(|&a, &b| key(&rows[a].fit, c).total_cmp(&key(&rows[b].fit, c)));
        let mut rank = vec![0; rows.len()];
        for (r, i) in order.into_iter().enumerate() {
            rank[i] = r + 1;
        }
        rank
    };
    let (rmse, aic, bic) = (by(0), by(1), by(2));
    (0..rows.len()).map(|i| [rmse[i], aic[i], bic[i]]).collect()
}
