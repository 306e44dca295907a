//! `gonio fit --model rational`: the rational function through every
//! sample's segment (`gonio_analysis::rational`), as text or JSON, and its
//! fit file.

use super::fit::{domain, FitArgs, ParamArg};
use anyhow::{bail, Context, Result};
use gonio_acquire::operator::Operator;
use gonio_analysis::coefficients::Support;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::{self, Weighting};
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::{self, RationalSpec, SegmentSource};
use gonio_analysis::rounding::significant;

pub fn fit_cmd(a: FitArgs) -> Result<()> {
    let o = &a.options;
    if !a.fix.is_empty() || !o.bounds.is_empty() || o.weights != Weighting::Uniform {
        bail!("--fix, --bounds and --weights are options of the parametric models: a rational function has no parameters to hold or box, and no least-squares sum to weigh (its --segments say how close it must pass)");
    }
    let segments: SegmentSource = a.segments.as_deref().unwrap_or("sigma").parse()?;
    let spec = RationalSpec {
        parametrization: match o.param {
            ParamArg::Back => Parametrization::Back,
            ParamArg::View => Parametrization::LightView,
        },
        segments,
        max_degree: a.max_degree.unwrap_or(RationalSpec::MAX_DEGREE),
    };
    let d = domain(&a.file, o)?;
    let bar = Operator::for_json(o.json).bar(spec.max_degree as u64, "fitting rational", "degree");
    let f = rational::fit_observed(&d.train, &spec, |degree| {
        bar.set_position(degree as u64);
        bar.set_message(format!("degree {degree}"));
    })
    .context("fitting rational")?;
    bar.finish_and_clear();
    let holdout = d.holdout.as_ref().map(|h| f.function.against(h).0);
    let mut v = rational::file::to_json(&f, d.train.units, holdout.as_ref());
    if !d.train.warnings.is_empty() {
        v["warnings"] = serde_json::json!(d.train.warnings);
    }
    if let Some(out) = &a.out {
        fit::file::write_with_support(out, &v, &Support::of(&d.train)?)?;
    }
    super::fit::write_drawn(&FittedBrdf::Rational(f.function.clone()), &a, &d.train)?;
    if o.json {
        println!("{v}");
        return Ok(());
    }
    let r = &f.function;
    println!(
        "rational in the {} plane ({} samples, {:.2} s)",
        r.parametrization.name(),
        f.samples,
        f.seconds
    );
    println!(
        "  degree {}: {} coefficients ({} over {}); every segment held, segments {}",
        r.degree,
        r.coefficients(),
        r.numerator.len(),
        r.denominator.len(),
        f.segments
    );
    let tried: Vec<String> = f
        .attempts
        .iter()
        .map(|t| {
            format!(
                "{} ({} coefficients, {})",
                t.degree,
                t.coefficients,
                if t.feasible { "held" } else { "not held" }
            )
        })
        .collect();
    println!("  degrees tried: {}", tried.join(", "));
    println!("  {}  L∞ {}", f.metrics.summary(), significant(f.linf, 4));
    if let Some(h) = &holdout {
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
    Ok(())
}
