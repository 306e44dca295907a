//! `gonio fit --model rational` and `compare`'s rational row: the rational function through every
//! sample's segment (`gonio_analysis::rational`), as text or JSON, and its
//! fit file.

use super::fitting::FitArgs;
use anyhow::{bail, Result};
use gonio_acquire::operator::Operator;
use gonio_analysis::coefficients::Support;
use gonio_analysis::fit::comparison::{rational_fit, RationalRow};
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::selection::Selection;
use gonio_analysis::fit::{self, Units, Weighting};
use gonio_analysis::rational::RationalSpec;
use gonio_analysis::rounding::significant;

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
    let mut v = row.to_json();
    let (f, holdout) = (&row.fit, &row.holdout);
    if !d.train.warnings.is_empty() {
        v["warnings"] = serde_json::json!(d.train.warnings);
    }
    if let Some(out) = &a.out {
        fit::file::write_with_support(out, &v, &Support::of(&d.train)?)?;
    }
    super::fitting::write_drawn(&FittedBrdf::Rational(f.function.clone()), &a, &d.train)?;
    if o.json {
        println!("{v}");
        return Ok(());
    }
    let r = &f.function;
    println!(
        "rational in the {} plane{} ({} samples, {:.2} s)",
        r.coordinates.name(),
        if r.cosine { ", times cosθi·cosθo" } else { "" },
        f.samples,
        f.seconds
    );
    println!(
        "  {} coefficients, degree {} ({} over {}); every segment held, segments {} of {}",
        r.coefficients(),
        r.degree,
        r.numerator.len(),
        r.denominator.len(),
        f.segments,
        r.quantity.label()
    );
    let tried: Vec<String> = f
        .attempts
        .iter()
        .map(|t| {
            let held = if t.feasible { "held" } else { "not held" };
            let precision = if t.single_precision { "" } else { " in double" };
            format!("{} ({held}{precision})", t.coefficients)
        })
        .collect();
    println!("  coefficients tried: {}", tried.join(", "));
    if let Some(d) = &f.densified {
        for w in &d.warnings {
            eprintln!("warning: {w}");
        }
        let m = &d.measured;
        println!(
            "  fitted to {} points of a {}° grid between the samples; it holds {} of the {} measured segments (worst miss {} of a segment's width){}",
            d.points,
            d.step_deg,
            m.held,
            m.of,
            significant(m.worst, 2),
            if m.undefined > 0 {
                format!(", and has a pole (Q ≤ 0) at {} of the samples", m.undefined)
            } else {
                String::new()
            }
        );
    }
    println!("  {}  L∞ {}", f.metrics.summary(), significant(f.linf, 4));
    if let Some(h) = holdout {
        println!("  held out θi {:?}°: {}", o.holdout_theta_i, h.summary());
    }
    if f.shifted > 0 {
        eprintln!(
            "note: {} value(s) were negative; their segments were clamped to [0, at least the half-width]: a BRDF is not negative",
            f.shifted
        );
    }
    if let Some(c) = &f.capped {
        eprintln!("note: {c}");
    }
    if !f.single_precision {
        eprintln!(
            "note: no function of up to {} coefficients holds every segment by the margin single precision needs ({:e}): this one holds them in double precision only, and a shader or renderer evaluating it in single precision may leave some",
            f.attempts.iter().map(|t| t.coefficients).max().unwrap_or(0),
            gonio_analysis::rational::qp::SINGLE_MARGIN
        );
    }
    Ok(())
}
