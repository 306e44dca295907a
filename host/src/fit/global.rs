//! Global search with no starting point, built so that a search that looks
//! at a subset of the data cannot lose on all of it:
//!
//! 1. CMA-ES with increasing-population restarts (IPOP; the `cmaes` crate)
//!    over the unit cube of the bounds, on a thinned copy of the data (the
//!    basin is located on a few hundred to a few thousand samples);
//! 2. local fits on the thinned data from CMA-ES's best point and from a
//!    spread of quasi-random points of the cube (Halton), so that the
//!    basins the thinned cost ranks second are still visited;
//! 3. every candidate judged by the cost on **all** the data, the best few
//!    polished there, the lowest kept.
//!
//! Why: a model that is not the material (every real case) has several
//! basins whose order can differ between a subset and the whole, and
//! CMA-ES on the subset alone found the wrong one on 80 000 samples of a
//! measured tape (retro-phong's `k4` of the opposite sign); the local
//! fits on the subset cost a few full ones.

use super::local;
use super::problem::Problem;
use super::transform::from_unit;
use cmaes::restart::{RestartOptions, RestartStrategy, IPOP};
use rayon::prelude::*;

/// Samples the global search looks at: a twentieth of the data, at least
/// 600 (narrow lobes need their peaks) and at most 4 000.
fn thinned_size(n: usize) -> usize {
    (n / 20).clamp(600, 4000)
}

/// Budget of cost evaluations per free parameter.
const EVALS_PER_PARAM: usize = 1000;
/// Quasi-random starts of the local fits on the thinned data, inside
/// `[0.02, 0.98]` of the cube (on a bound the bounded LM's transform is
/// flat, and a start there cannot move).
const STARTS: usize = 16;
/// Rounds of each probing fit on the thinned data: enough to reach the
/// floor of its basin roughly, which is all the ranking needs.
const PROBE_ITERATIONS: usize = 40;
/// Candidates polished on all the data.
const POLISHED: usize = 3;

/// The `k`-th point of the Halton sequence in `dim` dimensions (bases the
/// first primes), offset by half a step so no coordinate is 0.
fn halton(k: usize, dim: usize) -> Vec<f64> {
    const PRIMES: [usize; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];
    (0..dim)
        .map(|d| {
            let b = PRIMES[d % PRIMES.len()];
            let (mut i, mut f, mut x) = (k + 1, 1.0, 0.0);
            while i > 0 {
                f /= b as f64;
                x += f * (i % b) as f64;
                i /= b;
            }
            x
        })
        .collect()
}

/// Free parameters of the best optimum found, from a seeded search.
pub fn search(problem: &Problem, seed: u64) -> Vec<f64> {
    let n = problem.free.len();
    let bounds = problem.bounds();
    let thin = problem.subset(thinned_size(problem.y.len()));
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
        // Each generation's candidates on all the threads, one each.
        .run_parallel_with_reuse(objective);
    let best_z: Vec<f64> = match results.best {
        Some(best) => best.point.iter().map(|v| v.clamp(1e-9, 1.0 - 1e-9)).collect(),
        None => vec![0.5; n],
    };
    // Local fits on the thinned data, judged on all of it; the fits are
    // independent, so they run on all the threads (collected in order: the
    // result does not depend on the number of threads).
    let starts: Vec<Vec<f64>> = std::iter::once(best_z)
        .chain((0..STARTS).map(|k| halton(k + seed as usize * STARTS, n).into_iter().map(|z| 0.02 + 0.96 * z).collect()))
        .collect();
    let mut candidates: Vec<(f64, Vec<f64>)> = starts
        .into_par_iter()
        .map(|z| {
            let x = local::minimize_within(&thin, &to_x(&z), PROBE_ITERATIONS);
            let c = problem.cost(&x);
            (if c.is_finite() { c } else { f64::INFINITY }, x)
        })
        .collect();
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    candidates.truncate(POLISHED);
    let polished: Vec<(f64, Vec<f64>)> = candidates
        .into_par_iter()
        .map(|(_, x)| {
            let x = local::minimize(problem, &x);
            (problem.cost(&x), x)
        })
        .collect();
    polished
        .into_iter()
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, x)| x)
        .unwrap_or_else(|| to_x(&vec![0.5; n]))
}

#[cfg(test)]
mod tests {
    use super::halton;

    #[test]
    fn halton_points_fill_the_cube_without_repeating() {
        let pts: Vec<Vec<f64>> = (0..64).map(|k| halton(k, 3)).collect();
        for p in &pts {
            assert!(p.iter().all(|x| *x > 0.0 && *x < 1.0));
        }
        for d in 0..3 {
            let below = pts.iter().filter(|p| p[d] < 0.5).count();
            assert!((28..=36).contains(&below), "dimension {d}: {below} of 64 below ½");
        }
        assert_ne!(pts[0], pts[1]);
    }
}
