//! Global search with no starting point: CMA-ES with increasing-population
//! restarts (IPOP; the `cmaes` crate) over the unit cube of the bounds, on a
//! thinned copy of the data; then a local fit on all of it from the best
//! point. The thinned cost keeps the search cheap: the basin is located on
//! a few hundred samples, the local fit does the rest.

use super::local;
use super::problem::Problem;
use super::transform::from_unit;
use cmaes::restart::{RestartOptions, RestartStrategy, IPOP};

/// Samples the global search looks at.
const GLOBAL_SAMPLES: usize = 600;
/// Budget of cost evaluations per free parameter.
const EVALS_PER_PARAM: usize = 2500;

/// Free parameters of the best optimum found, from a seeded search.
pub fn search(problem: &Problem, seed: u64) -> Vec<f64> {
    let n = problem.free.len();
    let bounds = problem.bounds();
    let thin = problem.subset(GLOBAL_SAMPLES);
    let to_x = |z: &[f64]| -> Vec<f64> { bounds.iter().zip(z).map(|(b, &z)| from_unit(b, z)).collect() };
    let objective = |z: &cmaes::DVector<f64>| {
        // Outside the cube: the cost at the nearest face plus a penalty that grows with the distance.
        let outside: f64 = z.iter().map(|v| (v - v.clamp(0.0, 1.0)).powi(2)).sum();
        let zc: Vec<f64> = z.iter().map(|v| v.clamp(0.0, 1.0)).collect();
        let c = thin.cost(&to_x(&zc));
        let c = if c.is_finite() { c } else { f64::MAX / 4.0 };
        c * (1.0 + 1e3 * outside) + outside
    };
    let strategy = RestartStrategy::IPOP(IPOP::new(2).expect("increase factor 2 is valid"));
    let results = RestartOptions::new(n, 0.2..=0.8, strategy)
        .max_function_evals(EVALS_PER_PARAM * n)
        .seed(seed)
        .build()
        .expect("dimension ≥ 1 and a non-empty range")
        .run_with_reuse(objective);
    let z: Vec<f64> = match results.best {
        Some(best) => best.point.iter().map(|v| v.clamp(1e-9, 1.0 - 1e-9)).collect(),
        None => vec![0.5; n],
    };
    // Polish on the thinned data first (cheap), then on everything.
    let x = local::minimize(&thin, &to_x(&z));
    local::minimize(problem, &x)
}
