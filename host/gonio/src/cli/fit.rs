//! `gonio fit` and `gonio compare`: models fitted to a data file (ALTA `.dat`
//! or the calibrated sample CSV).

use super::rational::RationalArgs;
use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::{Coefficient, Source, Support};
use gonio_analysis::fit::compared::ComparedFit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::{self, data::theta_in, Dataset, Fit, FitSpec, Units, Weighting};
use gonio_analysis::rational::RationalSpec;
use gonio_analysis::rounding::{figure, significant};
use gonio_brdf::{ModelId, Param};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Which samples a fit sees, and how they are weighed.
#[derive(Debug, Clone, clap::Args)]
pub struct FitOptions {
    /// Cosine of the retro lobes: `back` (cos_B) or `view` (cos_R = l·v).
    #[arg(long, value_enum, default_value = "view")]
    pub param: ParamArg,
    /// Fit the retro half-space only (|Δφ| ≤ 90°).
    #[arg(long)]
    pub retro_only: bool,
    /// Fit only these incidence angles (degrees, comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub theta_i: Vec<f64>,
    /// Leave these incidence angles (degrees) out of the fit and report how
    /// well the fit predicts them (cross-validation, as Zhang et al.).
    #[arg(long, value_delimiter = ',')]
    pub holdout_theta_i: Vec<f64>,
    /// Sample weights in the least-squares sum.
    #[arg(long, value_enum, default_value = "uniform")]
    pub weights: Weighting,
    /// Units the residuals are taken in (default: the file's own); for a file
    /// that does not say what its values are (ALTA without #PARAM_OUT), also
    /// what they are.
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Seed of the global search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Search boxes replacing the defaults, NAME=LO:HI,... (in `compare`,
    /// each model takes the names it has).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_name = "NAME=LO:HI")]
    pub bounds: Vec<String>,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

impl Default for FitOptions {
    /// The command line's defaults: the whole data set, uniform weights,
    /// the view cosine, the file's units.
    fn default() -> Self {
        FitOptions {
            param: ParamArg::View,
            retro_only: false,
            theta_i: Vec::new(),
            holdout_theta_i: Vec::new(),
            weights: Weighting::Uniform,
            units: None,
            seed: 1,
            bounds: Vec::new(),
            instrument: Default::default(),
            json: false,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ParamArg {
    Back,
    View,
}

impl From<ParamArg> for Param {
    fn from(p: ParamArg) -> Param {
        match p {
            ParamArg::Back => Param::Back,
            ParamArg::View => Param::View,
        }
    }
}

#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Model id (models.md): lambert, retro-phong, abc-retro, abc-retro-per-lobe, beckmann-retro, blinn-retro, lafortune, oren-nayar, five-param,
    /// or `rational` (a rational function through every sample's segment; its plane is --param: back or view, the light-view plane).
    #[arg(long)]
    pub model: String,
    #[command(flatten)]
    pub rational: RationalArgs,
    /// Hold a parameter at a value, NAME=V (repeatable).
    #[arg(long)]
    pub fix: Vec<String>,
    /// Write the fit as JSON to this file as well.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the fit as a Disney BRDF Explorer shader (.brdf) as well.
    #[arg(long)]
    pub brdf: Option<PathBuf>,
    /// Write the fit as an RGL .bsdf for Mitsuba 3 and pbrt-v4 as well, at
    /// `gonio export`'s default resolution (a warning on stderr if too coarse).
    #[arg(long)]
    pub bsdf: Option<PathBuf>,
    /// Draw the data and the fit into this directory (PNG and SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub options: FitOptions,
}

#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Write DIR/report.html: the comparison table, every fit as JSON and
    /// BRDF Explorer shader (DIR/fits), pictures of the best fits (DIR/plots).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Overwrite a report already in the --report directory.
    #[arg(long, requires = "report")]
    pub force: bool,
    /// The rational function's row (its segments: the samples' σ unless
    /// --segments says otherwise; where none holds them all, a note says why).
    #[command(flatten)]
    pub rational: RationalArgs,
    #[command(flatten)]
    pub options: FitOptions,
}

/// The data a fit sees (domain restriction applied), and the held-out part.
pub struct Domain {
    pub(super) train: Dataset,
    pub(super) holdout: Option<Dataset>,
}

pub fn domain(path: &Path, o: &FitOptions) -> Result<Domain> {
    let data = super::load_data(path, o.units, &o.instrument)?;
    // What the file holds, for the messages below: the restrictions may
    // leave nothing to name.
    let held = degrees(&data.incidence_angles_deg());
    let data = data.filter(|s| (!o.retro_only || s.on_retro_side()) && (o.theta_i.is_empty() || theta_in(s.theta_i, &o.theta_i)));
    let (train, holdout) = if o.holdout_theta_i.is_empty() {
        (data, None)
    } else {
        let h = data.filter(|s| theta_in(s.theta_i, &o.holdout_theta_i));
        if h.observations.is_empty() {
            bail!(
                "no samples to hold out at θi = {}: {} holds θi = {held}",
                degrees(&o.holdout_theta_i),
                path.display()
            );
        }
        (data.filter(|s| !theta_in(s.theta_i, &o.holdout_theta_i)), Some(h))
    };
    if train.observations.is_empty() {
        bail!(
            "no samples left to fit after the restrictions (--theta-i, --retro-only, --holdout-theta-i): {} holds θi = {held}",
            path.display()
        );
    }
    Ok(Domain { train, holdout })
}

/// `15°, 30°, 60°`.
fn degrees(angles: &[f64]) -> String {
    angles.iter().map(|a| format!("{a}°")).collect::<Vec<_>>().join(", ")
}

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

/// One fit of a comparison, its held-out metrics and its fit file's JSON.
pub struct Outcome {
    pub fit: ComparedFit,
    pub holdout: Option<fit::Metrics>,
    pub json: Value,
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

/// What `--brdf`, `--bsdf` and `--plot` ask of a fit: its shader, its
/// renderer's file, its pictures over `data`.
pub fn write_drawn(fitted: &FittedBrdf, a: &FitArgs, data: &Dataset) -> Result<()> {
    let origin = format!("a fit to {}", a.file.display());
    if let Some(out) = &a.brdf {
        super::export::write_brdf(fitted, &origin, out)?;
    }
    if let Some(out) = &a.bsdf {
        let opt = gonio_analysis::formats::rgl::Options::default();
        let written = super::export::write_bsdf(&|d| fitted.eval(d), fitted.name(), &origin, out, &opt)?;
        if let Some(w) = super::export::coarse_warning(&written.accuracy) {
            eprintln!("{w}");
        }
    }
    if let Some(dir) = &a.plot {
        gonio_analysis::plot::render(data, std::slice::from_ref(fitted), dir, &Default::default())?;
    }
    Ok(())
}

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
