//! The fitting engine: every model of `models.md`, bounded least squares
//! seeded by a global search (no starting point needed), per-sample weights,
//! domain restriction, fixed parameters, fitting in `f_r` or `f_r·cosθo`,
//! standard errors, and cross-validation by held-out incidence angles.

mod area;
pub mod compared;
pub mod comparison;
pub mod criteria;
pub mod data;
pub mod densify;
pub mod file;
mod global;
pub mod goodness;
mod local;
pub mod metrics;
mod problem;
pub mod selection;
pub mod settings;
pub mod settle;
pub mod text;
pub mod transform;

pub use data::{Dataset, Observation, Units};
pub use metrics::Metrics;
pub use problem::Problem;

use anyhow::{bail, Result};
use gonio_brdf::{Bound, Material, ModelId, Param};
use nalgebra::DMatrix;
use std::time::Instant;

/// How the samples are weighted in the least-squares sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Weighting {
    /// Every sample alike (the metrics' own weighting).
    Uniform,
    /// `1/σ` from each sample's uncertainty (the head's noise estimate).
    Sigma,
    /// `1/|y|`: relative errors, for data spanning decades.
    Relative,
    /// `√Ω`: each sample counted for the solid angle it stands for among
    /// those of its incidence ([`area::solid_angles`]), so scans that sample
    /// the hemisphere differently (a grid, a sweep scan's rows) fit the same
    /// integral.
    Area,
}

/// What to fit and how.
#[derive(Debug, Clone)]
pub struct FitSpec {
    pub model: ModelId,
    pub param: Param,
    /// Units the residuals are taken in.
    pub units: Units,
    pub weighting: Weighting,
    /// Parameters held at a value: `(index, value)`.
    pub fixed: Vec<(usize, f64)>,
    /// Search boxes given by the user: `(index, lo, hi)`, replacing the
    /// defaults (`ModelId::bounds_for` the data's median).
    pub bounds: Vec<(usize, f64, f64)>,
    /// Default boxes in place of the catalog's, `(index, lo, hi)`: unlike
    /// `bounds` they widen where the optimum ends on an open edge, as the
    /// catalog's do (how `fit-bench widen` shows the widening finds the
    /// optimum a wider box holds).
    pub default_boxes: Vec<(usize, f64, f64)>,
    /// Seed of the global search.
    pub seed: u64,
    /// Start here with a local fit only, instead of the global search.
    pub start: Option<Vec<f64>>,
}

impl FitSpec {
    pub fn new(model: ModelId) -> Self {
        FitSpec {
            model,
            param: Param::View,
            units: Units::Fr,
            weighting: Weighting::Uniform,
            fixed: Vec::new(),
            bounds: Vec::new(),
            default_boxes: Vec::new(),
            seed: 1,
            start: None,
        }
    }
}

/// A fitted model and how well it fits.
#[derive(Debug, Clone)]
pub struct Fit {
    pub material: Material,
    /// Standard error of each parameter; `None` for fixed ones or where the
    /// normal matrix is singular.
    pub stderr: Vec<Option<f64>>,
    /// Metrics on the fitted samples, in the data's units.
    pub metrics: Metrics,
    pub samples: usize,
    pub seconds: f64,
    /// Akaike's and Bayes' information criteria of the least-squares fit,
    /// `N·ln(S/N) + 2k` and `N·ln(S/N) + k·ln N` (`S` the weighted sum of
    /// squares, `k` the free parameters): lower is better, and each extra
    /// coefficient must earn its place.
    pub aic: f64,
    pub bic: f64,
    /// Free parameters that ended on (within 1e-6 of the box's width of) a
    /// bound of their search box: the optimum may lie outside it.
    pub at_bound: Vec<&'static str>,
    /// Weighted sum of squared residuals at the optimum.
    pub cost: f64,
    /// Covariance of the parameters (every parameter, in `models.md` order;
    /// rows and columns of fixed ones are zero): the samples' scatter and
    /// the inputs they share; `None` where the normal matrix is singular.
    pub covariance: Option<DMatrix<f64>>,
    /// Free parameters without a standard error, each with the reason
    /// (`covariance` is then conditional on them held at their values).
    pub undetermined: Vec<(&'static str, &'static str)>,
    /// Default boxes the fit widened, each time it ended on an edge that is
    /// not a physical limit: `(parameter, the box it ended in)`.
    pub widened: Vec<Widened>,
    /// The free parameters' correlations, from the covariance.
    pub correlation: Option<goodness::Correlation>,
    /// χ² against the samples' σ, its degrees of freedom and p-value
    /// (`None` where a sample has no σ); under `--weights sigma` the cost.
    pub goodness: Option<goodness::Goodness>,
}

impl Fit {
    /// Parameter `k` as text: rounded to its standard error, and marked
    /// where it ended on its search box (its ± then says how the fit bends
    /// there, not where the optimum lies) or has no standard error (why).
    pub fn parameter_text(&self, k: usize) -> String {
        let (name, value) = (self.material.model.param_names()[k], self.material.params[k]);
        let text = match self.stderr[k] {
            Some(u) => crate::rounding::with_uncertainty(value, u),
            None => crate::rounding::significant(value, 6),
        };
        let held = self.undetermined.iter().find(|(n, _)| *n == name).map(|(_, why)| *why);
        match (self.at_bound.contains(&name), held) {
            (_, Some(why)) => format!("{text} (no uncertainty: {why})"),
            (true, None) => format!("{text} (on its bound)"),
            (false, None) => text,
        }
    }
}

/// Builds the least-squares problem of a data set.
pub fn problem(data: &Dataset, spec: &FitSpec) -> Result<Problem> {
    let model = spec.model;
    let n = model.param_names().len();
    if data.observations.is_empty() {
        bail!("no samples to fit (after the domain restriction)");
    }
    let mut values: Vec<f64> = data
        .observations
        .iter()
        .map(|o| (o.value / o.unit_factor(data.units)).abs())
        .filter(|v| v.is_finite())
        .collect();
    values.sort_by(f64::total_cmp);
    let mut bounds_all = model.bounds_for(values.get(values.len() / 2).copied().unwrap_or(0.0));
    for &(i, lo, hi) in spec.default_boxes.iter().chain(&spec.bounds) {
        if i >= n || !(lo.is_finite() && hi.is_finite() && lo < hi) {
            bail!(
                "a search box must be one of {}, with finite lo < hi",
                model.param_names().join(", ")
            );
        }
        let d = model.bounds()[i];
        if d.spread == gonio_brdf::Spread::Log && lo <= 0.0 {
            bail!(
                "the box of {} must stay above 0 (it is searched in its logarithm)",
                model.param_names()[i]
            );
        }
        bounds_all[i] = gonio_brdf::Bound { lo, hi, ..d };
    }
    let mut template: Vec<f64> = bounds_all.iter().map(|b| (b.lo + b.hi) / 2.0).collect();
    for &(i, v) in &spec.fixed {
        if i >= n || !v.is_finite() {
            bail!("a fixed parameter must be one of {} and finite", model.param_names().join(", "));
        }
        let b = bounds_all[i];
        if !(b.lo..=b.hi).contains(&v) {
            bail!(
                "{} = {v} is outside its range [{}, {}] (widen it with --bounds)",
                model.param_names()[i],
                b.lo,
                b.hi
            );
        }
        template[i] = v;
    }
    let free: Vec<usize> = (0..n).filter(|i| !spec.fixed.iter().any(|(j, _)| j == i)).collect();
    if free.is_empty() {
        bail!("every parameter of {} is fixed: nothing to fit", model.name());
    }
    if data.observations.len() < free.len() {
        bail!(
            "{} samples for {} free parameters of {}: too few to fit",
            data.observations.len(),
            free.len(),
            model.name()
        );
    }
    if data.observations.iter().all(|o| o.value == 0.0) {
        bail!("every value is zero: there is nothing to fit");
    }
    let data = data.in_units(spec.units)?;
    let y: Vec<f64> = data.observations.iter().map(|o| o.value).collect();
    let weight = criteria::weights(&data, spec.weighting)?;
    Ok(Problem {
        model,
        param: spec.param,
        geos: data.observations.iter().map(Observation::geometry).collect(),
        scale: data.observations.iter().map(|o| o.unit_factor(spec.units)).collect(),
        shared: data
            .observations
            .iter()
            .zip(&weight)
            .map(|(o, w)| o.shared.map(|s| w * s))
            .collect(),
        y,
        weight,
        bounds_all,
        template,
        free,
    })
}

/// Fits a model to a data set.
pub fn fit(data: &Dataset, spec: &FitSpec) -> Result<Fit> {
    let t0 = Instant::now();
    let (problem, x, widened) = widening(data, spec)?;
    let material = Material {
        model: spec.model,
        params: problem.full(&x),
        param: spec.param,
    };
    let Spread { covariance, undetermined } = covariance(&problem, &x);
    let names = spec.model.param_names();
    let stderr = (0..material.params.len())
        .map(|i| {
            let v = covariance.as_ref()?[(i, i)];
            let held = undetermined.iter().any(|(n, _)| *n == names[i]);
            (problem.free.contains(&i) && !held && v.is_finite() && v >= 0.0).then(|| v.sqrt())
        })
        .collect();
    let cost = problem.cost(&x);
    let at_bound = problem
        .free
        .iter()
        .filter(|&&i| {
            let b = problem.bounds_all[i];
            let (v, tol) = (material.params[i], 1e-6 * (b.hi - b.lo));
            (v - b.lo).abs() <= tol || (b.hi - v).abs() <= tol
        })
        .map(|&i| names[i])
        .collect();
    let criteria = criteria::Criteria::of(cost, problem.y.len(), problem.free.len());
    let correlation = covariance
        .as_ref()
        .and_then(|c| goodness::correlation(c, &problem.free))
        .map(|rho| goodness::Correlation {
            names: problem.free.iter().map(|&i| names[i]).collect(),
            rho,
        });
    Ok(Fit {
        widened,
        goodness: goodness::Goodness::of_brdf(data, problem.free.len(), |d| material.eval(d)),
        correlation,
        aic: criteria.aic,
        bic: criteria.bic,
        at_bound,
        metrics: evaluate(&material, data),
        stderr,
        covariance,
        undetermined,
        samples: data.observations.len(),
        seconds: t0.elapsed().as_secs_f64(),
        cost,
        material,
    })
}

/// A default box a fit widened: the parameter and the box it ended in.
pub type Widened = (&'static str, Bound);

/// Widenings of one box at most: ×10⁴ in width.
const WIDENINGS: usize = 4;

/// The fit of `spec`, its default boxes widened where the optimum ends on an
/// edge that is not a physical limit (`Bound::open`), each time a new
/// search of the grown box with the optimum found among its candidates (a
/// local fit from it where the user gave a start), until it lies inside, a
/// limit holds it, or
/// `WIDENINGS` have been spent. A box the user gave (`--bounds`) is theirs
/// and stays. Returns the last problem, its optimum and the widened boxes.
fn widening(data: &Dataset, spec: &FitSpec) -> Result<(Problem, Vec<f64>, Vec<Widened>)> {
    let mut spec = spec.clone();
    let mut problem = problem(data, &spec)?;
    let mut x = solve(&problem, spec.start.as_deref(), spec.seed);
    let names = spec.model.param_names();
    let mut widened: Vec<Widened> = Vec::new();
    let given: Vec<usize> = spec.bounds.iter().map(|b| b.0).collect();
    for _ in 0..WIDENINGS {
        let full = problem.full(&x);
        let grown: Vec<(usize, Bound)> = problem
            .free
            .iter()
            .filter(|i| !given.contains(i))
            .filter_map(|&i| {
                let b = problem.bounds_all[i];
                let tol = 1e-6 * (b.hi - b.lo);
                b.widened(((full[i] - b.lo).abs() <= tol, (b.hi - full[i]).abs() <= tol))
                    .map(|w| (i, w))
            })
            .collect();
        if grown.is_empty() {
            break;
        }
        for (i, w) in grown {
            spec.bounds.retain(|b| b.0 != i);
            spec.bounds.push((i, w.lo, w.hi));
            widened.retain(|(n, _)| *n != names[i]);
            widened.push((names[i], w));
        }
        problem = self::problem(data, &spec)?;
        // Going on from the edge alone can stay in the basin the small box
        // forced (fit-bench widen: RMSE up to 8× the full box's): the edge
        // optimum enters the grown box's search as one more candidate.
        let edge = free_start(&problem, &full);
        x = match spec.start {
            Some(_) => local::minimize(&problem, &edge),
            None => global::search(&problem, spec.seed, vec![edge]),
        };
    }
    Ok((problem, x, widened))
}

/// Threads a fit runs on: rayon's pool, one per core unless
/// `RAYON_NUM_THREADS` says otherwise. The results do not depend on it.
pub fn threads() -> usize {
    rayon::current_num_threads()
}

/// The free parameters at the optimum: a local fit from `start` (every
/// parameter, clamped into the bounds), or the seeded global search.
pub fn solve(problem: &Problem, start: Option<&[f64]>, seed: u64) -> Vec<f64> {
    match start {
        Some(start) => local::minimize(problem, &free_start(problem, start)),
        None => global::search(problem, seed, Vec::new()),
    }
}

/// The free parameters of `full` (every parameter), held inside their boxes.
fn free_start(problem: &Problem, full: &[f64]) -> Vec<f64> {
    problem
        .free
        .iter()
        .zip(problem.bounds())
        .map(|(&i, b)| full[i].clamp(b.lo, b.hi))
        .collect()
}

/// The metrics of a material on a data set, in the data's units.
pub fn evaluate(material: &Material, data: &Dataset) -> Metrics {
    let measured: Vec<f64> = data.observations.iter().map(|o| o.value).collect();
    let model: Vec<f64> = data
        .observations
        .iter()
        .map(|o| o.unit_factor(data.units) * material.eval(&o.directions()))
        .collect();
    Metrics::new(&measured, &model)
}

/// `s²(JᵀJ)⁻¹ + Σ_a (JᵀJ)⁻¹Jᵀd_a·((JᵀJ)⁻¹Jᵀd_a)ᵀ`, spread over every
/// parameter (fixed ones zero); standard errors are the roots of its
/// diagonal. The first term is the samples' own scatter: `s² = Σr²/(N − p)`,
/// `J` the weighted Jacobian in the parameters themselves (not the
/// transformed ones). The second is what the samples share (the plate, the
/// stage zeros): `d_a` the weighted shifts of the targets when shared input
/// `a` is off by one standard uncertainty, and `(JᵀJ)⁻¹Jᵀd_a` the move of the
/// optimum it causes (one Gauss–Newton step): errors common to every sample
/// do not average out, however many samples there are.
///
/// A free parameter whose column of `J` is not finite where the residuals
/// are (a derivative that diverges on its bound) or is zero (the data do
/// not depend on it there) has no uncertainty: it is held at its
/// value, its row and column are zero, and the others' covariance is
/// conditional on it; `undetermined` says which and why. Where the rest is
/// still singular, nothing is stated.
fn covariance(problem: &Problem, x: &[f64]) -> Spread {
    let n = problem.template.len();
    let (r, mut j) = problem.residuals_and_jacobian(x);
    let names = problem.model.param_names();
    if r.iter().any(|v| !v.is_finite()) {
        return Spread {
            covariance: None,
            undetermined: problem.free.iter().map(|&i| (names[i], NO_VALUE)).collect(),
        };
    }
    // A lobe far from its peak overflows its power (`(1 + b(1 − c))^c` of
    // the ABC lobes at c ≈ 300): its value is 0 and so is its derivative,
    // which the arithmetic leaves as ∞/∞ = NaN. Such an entry moves
    // nothing; an infinite one is a derivative that diverges.
    for v in j.iter_mut().filter(|v| v.is_nan()) {
        *v = 0.0;
    }
    let mut undetermined = Vec::new();
    let mut kept = Vec::new();
    for (a, &i) in problem.free.iter().enumerate() {
        let col = j.column(a);
        if col.iter().any(|v| !v.is_finite()) {
            undetermined.push((names[i], NOT_FINITE));
        } else if col.iter().all(|v| *v == 0.0) {
            undetermined.push((names[i], NO_EFFECT));
        } else {
            kept.push(a);
        }
    }
    let everything = |why: &'static str| Spread {
        covariance: None,
        undetermined: problem.free.iter().map(|&i| (names[i], why)).collect(),
    };
    let Some(dof) = r.len().checked_sub(kept.len()).filter(|d| *d > 0) else {
        return everything(NO_DOF);
    };
    let j = j.select_columns(&kept);
    let s2 = r.iter().map(|v| v * v).sum::<f64>() / dof as f64;
    let normal: DMatrix<f64> = j.transpose() * &j;
    let Some(inv) = normal.try_inverse().filter(|m| m.iter().all(|v| v.is_finite())) else {
        return everything(SINGULAR);
    };
    let mut cov = &inv * s2;
    for a in 0..crate::uncertainty::SHARED.len() {
        let d = nalgebra::DVector::from_iterator(r.len(), problem.shared.iter().map(|s| s[a]));
        if d.iter().all(|v| *v == 0.0) {
            continue;
        }
        let shift = &inv * (j.transpose() * d);
        cov += &shift * shift.transpose();
    }
    let mut out = DMatrix::zeros(n, n);
    for (a, &ka) in kept.iter().enumerate() {
        for (b, &kb) in kept.iter().enumerate() {
            out[(problem.free[ka], problem.free[kb])] = cov[(a, b)];
        }
    }
    Spread {
        covariance: Some(out),
        undetermined,
    }
}

/// Why a free parameter has no standard error (`Fit::undetermined`).
const NOT_FINITE: &str = "the model's derivative in it is not finite at the optimum (on its bound): held there";
const NO_EFFECT: &str = "the data do not depend on it at the optimum: held there";
const NO_VALUE: &str = "the model has no finite value at some sample";
const NO_DOF: &str = "no degrees of freedom are left (as many free parameters as samples)";
const SINGULAR: &str = "the data do not determine the parameters separately (their normal matrix is singular)";

/// The covariance of a fit's parameters, and the free parameters it cannot
/// speak for.
struct Spread {
    covariance: Option<DMatrix<f64>>,
    undetermined: Vec<(&'static str, &'static str)>,
}
