//! Global search with no starting point, built so that a search that looks
//! at a subset of the data cannot lose on all of it:
//!
//! 1. CMA-ES with increasing-population restarts (IPOP; the `cmaes` crate)
//!    over the unit cube of the bounds, on a thinned copy of the data (the
//!    basin is located on a few hundred to a few thousand samples);
//! 2. local fits on a larger subset from CMA-ES's best point and from a
//!    spread of quasi-random points of the cube (Halton), so that the
//!    basins the thinned cost ranks second are still visited;
//! 3. every candidate polished on **all** the data, as a race ([`race`]),
//!    in the parameters themselves with the box kept by projection
//!    ([`local::Space::Box`]: an optimum on a bound is reached, not
//!    approached through the flat end of a transform):
//!    a few rounds at a time, side by side on the threads, the ones that can
//!    no longer win dropped between rounds; the lowest kept.
//!
//! Why: a model that is not the material (every real case) has several
//! basins whose order can differ between a subset and the whole, and
//! CMA-ES on the subset alone found the wrong one on 80 000 samples of a
//! measured tape (retro-phong's `k4` of the opposite sign); the local
//! fits on the subset cost a few full ones.

use super::local::{self, Descent};
use super::problem::Problem;
use super::transform::from_unit;
use cmaes::restart::{RestartOptions, RestartStrategy, IPOP};
use rayon::prelude::*;

/// Samples the global search looks at: a twentieth of the data, at least
/// 600 (narrow lobes need their peaks) and at most 4 000.
fn thinned_size(n: usize) -> usize {
    (n / 20).clamp(600, 4000)
}

/// Samples the probing local fits look at: twice CMA-ES's, at least 1 200.
/// They take a few hundred evaluations where CMA-ES takes thousands, and
/// their ends are what the race starts from: on 600 samples of the glass-bead
/// layer none of lafortune's probes ended in the basin that is lowest on all
/// 7 000 (1.4 % lower in cost), on 1 000 and more they did.
fn probed_size(n: usize) -> usize {
    (n / 10).clamp(1200, 8000)
}

/// Budget of CMA-ES's cost evaluations per free parameter. It only has to
/// land one of the race's starts in a good basin, the Halton probes the
/// others: 500 gave the same optima as 1 000 on every `fit-bench` case
/// (global hits 20/20, misfit ratios) in half the time.
const EVALS_PER_PARAM: usize = 500;
/// Quasi-random starts of the probing local fits, inside
/// `[0.02, 0.98]` of the cube (on a bound the bounded LM's transform is
/// flat, and a start there cannot move).
const STARTS: usize = 16;
/// Rounds of each probing fit on its subset: enough to reach the
/// floor of its basin roughly, which is all the ranking needs.
const PROBE_ITERATIONS: usize = 40;
/// Rounds of Levenberg–Marquardt each candidate of the race gets between
/// two looks at the field (5 dropped the two-lobe winner early; 25 spent
/// twice the time on losers).
const ROUND: usize = 10;
/// Two running candidates this close in cost (relative) are on the same
/// optimum: the higher one is out.
const SAME_OPTIMUM: f64 = 1e-8;
/// Rounds ahead over which a candidate's pace must be able to take it to
/// the best cost to stay in the race. It assumes descents slow down; one
/// that would speed up later (leaving a plateau as its damping falls) can be
/// dropped: a trade of certainty for time, set on `fit-bench`'s misfit cases
/// (and checked again there when the pace became a factor per round).
const HORIZON: usize = 3;
/// A candidate this close (relative) above one that has ended (converged,
/// or could go no further) is crawling to the same floor along a flat
/// valley (retro-phong's towards a bound): it is out. Judged by cost alone:
/// a different basin within 1e-5 of an ended one is given up too.
const SAME_FLOOR: f64 = 1e-5;
/// …and so are two this close in cost and in every parameter (relative):
/// two descents into one basin, one of them behind.
const SAME_BASIN: f64 = 1e-3;

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

/// Free parameters of the best optimum found, from a seeded search; `known`
/// points (free parameters in the box) enter the race as they are: a
/// widened fit's optimum on the old edge, which the new probes must beat.
pub fn search(problem: &Problem, seed: u64, known: Vec<Vec<f64>>) -> Vec<f64> {
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
    // Short local fits on the larger subset, then the race on all of it; the
    // fits are independent, so they run on all the threads (collected in
    // order: the result does not depend on the number of threads).
    let starts: Vec<Vec<f64>> = std::iter::once(best_z)
        .chain((0..STARTS).map(|k| halton(k + seed as usize * STARTS, n).into_iter().map(|z| 0.02 + 0.96 * z).collect()))
        .collect();
    let probe_set = problem.subset(probed_size(problem.y.len()));
    let probed: Vec<Vec<f64>> = starts
        .into_par_iter()
        .map(|z| local::minimize_within(&probe_set, &to_x(&z), PROBE_ITERATIONS))
        .chain(known)
        .collect();
    race(problem, probed).unwrap_or_else(|| to_x(&vec![0.5; n]))
}

/// Polishes every candidate on all the data as a race, and returns the
/// lowest: each runs [`ROUND`] rounds of Levenberg–Marquardt at a time (its
/// damping and scaling kept between them), side by side on the threads.
/// Between rounds a candidate is dropped when it cannot win: at its last
/// round's pace (the factor by which its cost fell) it would not reach the
/// best cost in [`HORIZON`] more rounds, or it is on its way to where a
/// better one already is (within [`SAME_OPTIMUM`] of a running one,
/// [`SAME_FLOOR`] of a converged one, or [`SAME_BASIN`] of one in cost and
/// every parameter). Probes that ended in one basin enter once. A pace is a
/// factor, not a difference: a probe whose lobe overflows on the samples it
/// did not see enters at 1e30 and falls by decades a round, which a linear
/// pace would take for a winner's.
///
/// Why every candidate: a basin the subset ranks fifth or sixteenth can be
/// the lowest on all the data (`fit-bench`'s misfit cases: abc-retro data
/// fitted by beckmann-retro, whose best has `r0` on its bound, and two lobes
/// fitted by abc-retro, won by a start whose cost was 300 times the best's).
/// Why a race: polishing all of them to the end takes several times as
/// long (`fit-bench`), mostly on basins clearly worse and on copies of the best one crawling
/// along a flat valley towards a bound.
fn race(problem: &Problem, starts: Vec<Vec<f64>>) -> Option<Vec<f64>> {
    let mut entrants: Vec<Descent> = starts.iter().map(|x| Descent::new_in(problem, x, local::Space::Box)).collect();
    entrants.sort_by(|a, b| a.cost().total_cmp(&b.cost()));
    let mut done: Vec<Descent> = Vec::new();
    // Probes that ended in one basin enter once.
    let mut live = Vec::new();
    for d in entrants {
        if !is_copy(&d, &live, &done) {
            live.push(d);
        }
    }
    let rounds = local::MAX_ITERATIONS.div_ceil(ROUND);
    for round in 1..=rounds {
        if live.is_empty() {
            break;
        }
        let before: Vec<f64> = live.iter().map(Descent::cost).collect();
        live.par_iter_mut().for_each(|d| d.run(ROUND));
        let best = live.iter().chain(&done).map(Descent::cost).fold(f64::INFINITY, f64::min);
        let mut running: Vec<(f64, Descent)> = Vec::new();
        for (d, b) in live.into_iter().zip(before) {
            if d.finished() {
                done.push(d);
            } else {
                running.push((b, d));
            }
        }
        running.sort_by(|a, b| a.1.cost().total_cmp(&b.1.cost()));
        live = Vec::new();
        for (before, d) in running {
            // Descents slow down: a candidate that would not reach the best
            // in HORIZON more rounds at this round's pace (the same factor
            // per round) is out.
            let pace = d.cost() / before;
            let behind = d.cost() * pace.powi(HORIZON.min(rounds - round) as i32) > best;
            if !behind && !is_copy(&d, &live, &done) {
                live.push(d);
            }
        }
    }
    done.iter()
        .chain(&live)
        .filter(|d| d.cost().is_finite())
        .min_by(|a, b| a.cost().total_cmp(&b.cost()))
        .map(Descent::x)
}

/// Whether `d` is on its way to where a better candidate already is (still
/// running: `live`; or converged: `done`).
fn is_copy(d: &Descent, live: &[Descent], done: &[Descent]) -> bool {
    let c = d.cost();
    let above = |k: &Descent, rel: f64| k.cost() <= c && c - k.cost() <= rel * c;
    live.iter().any(|k| above(k, SAME_OPTIMUM))
        || done.iter().any(|k| above(k, SAME_FLOOR))
        || live.iter().chain(done).any(|k| above(k, SAME_BASIN) && k.near(d, SAME_BASIN))
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
