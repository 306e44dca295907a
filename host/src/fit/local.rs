//! Bounded local least squares: Levenberg–Marquardt on the MINUIT-transformed
//! parameters, with the exact Jacobian chained through the transform.
//!
//! Written here rather than taken from the `levenberg-marquardt` crate (its
//! MINPACK port was the first version): our problems are tall and thin
//! (thousands of samples, at most 8 parameters), and the crate's pivoted QR
//! of the whole Jacobian took half of every fit (measured: 7 of 14 ms for
//! `lafortune` on 7 000 samples). Solving the n×n normal equations with
//! Marquardt's diagonal scaling costs `m·n²` flops and a Cholesky of at most
//! 8×8, which is plenty accurate for a handful of well-scaled parameters;
//! the damping update is Nielsen's (Madsen, Nielsen & Tingleff 2004, §3.2).

use super::problem::Problem;
use super::transform::{slope, to_external, to_internal};
use crate::brdf::Bound;
use nalgebra::{DMatrix, DVector};

/// Stop when a step lowers the cost by less than this fraction.
const FTOL: f64 = 1e-10;
/// …or moves the internal parameters by less than this (relative).
const XTOL: f64 = 1e-12;
/// …or the residuals are this close to orthogonal to every Jacobian column
/// (MINPACK's gtol: `|gᵢ|/sqrt(Aᵢᵢ·cost)`).
const GTOL: f64 = 1e-10;
pub const MAX_ITERATIONS: usize = 500;
/// Largest change of one transformed parameter in one step (rad).
const MAX_STEP: f64 = 1.0;
/// A parameter whose transformed value is this close to a bound's (rad;
/// `x` within about 1e-4 of the box's width) is tried on the bound.
const SNAP: f64 = 0.02;
/// Where a snapped parameter is put: this far (rad) inside the bound, a
/// few 1e-9 of the box's width from it, where the transform's slope is
/// small but not zero, so a later step can still take it off the bound (one
/// exactly on it could never leave: its Jacobian column is zero).
const ON_BOUND: f64 = 1e-4;
/// Progress per step (relative cost) below which a fit is crawling.
const CRAWL: f64 = 1e-6;

struct State {
    u: DVector<f64>,
    r: DVector<f64>,
    /// `∂r/∂u`, where it was evaluated.
    j: Option<DMatrix<f64>>,
    cost: f64,
}

/// Minimises from `start` (free parameters, inside the bounds); returns the
/// free parameters at the minimum.
///
/// A trial point right after an accepted step is evaluated with its Jacobian
/// (one pass gives both), since it is usually accepted too; after a
/// rejection only the residuals are taken, since more rejections tend to
/// follow while the damping grows.
pub fn minimize(problem: &Problem, start: &[f64]) -> Vec<f64> {
    minimize_within(problem, start, MAX_ITERATIONS)
}

/// [`minimize`] with at most `iterations` rounds: the global search's
/// probes of a basin, which need its floor only roughly.
pub fn minimize_within(problem: &Problem, start: &[f64], iterations: usize) -> Vec<f64> {
    let mut d = Descent::new(problem, start);
    d.run(iterations);
    d.x()
}

/// A Levenberg–Marquardt descent that can run a few rounds at a time and go
/// on where it stopped, with its damping and scaling (the global search's
/// race of candidates; a restart would forget both and crawl).
pub struct Descent<'a> {
    problem: &'a Problem,
    bounds: Vec<Bound>,
    start: Vec<f64>,
    s: State,
    lambda: f64,
    nu: f64,
    scale: DVector<f64>,
    finished: bool,
}

impl<'a> Descent<'a> {
    pub fn new(problem: &'a Problem, start: &[f64]) -> Self {
        let bounds = problem.bounds();
        let u = DVector::from_iterator(start.len(), bounds.iter().zip(start).map(|(b, &x)| to_internal(b, x)));
        let s = evaluate(problem, &bounds, u, true);
        Descent {
            finished: !s.cost.is_finite(),
            problem,
            bounds,
            start: start.to_vec(),
            s,
            lambda: 1e-3,
            nu: 10.0,
            scale: DVector::zeros(start.len()),
        }
    }

    /// The cost where the descent stands (infinite where the start was).
    pub fn cost(&self) -> f64 {
        self.s.cost
    }

    /// Whether it has ended on its own: converged, or can go no further.
    pub fn finished(&self) -> bool {
        self.finished
    }

    /// The free parameters where it stands (the start, if the model could
    /// not be evaluated there).
    pub fn x(&self) -> Vec<f64> {
        if !self.s.cost.is_finite() {
            return self.start.clone();
        }
        external(&self.bounds, &self.s.u)
    }

    /// Whether `other` is heading for the same optimum: every parameter
    /// within `rel` of the two values' mean magnitude (for a parameter near
    /// zero, within `rel` of a millionth of its box's width).
    pub fn near(&self, other: &Descent, rel: f64) -> bool {
        let (x, y) = (self.x(), other.x());
        x.iter()
            .zip(&y)
            .zip(&self.bounds)
            .all(|((a, b), bound)| (a - b).abs() <= rel * (0.5 * (a.abs() + b.abs())).max(1e-6 * (bound.hi - bound.lo)))
    }

    /// Runs at most `iterations` more rounds.
    pub fn run(&mut self, iterations: usize) {
        if !self.finished && !self.step(iterations) {
            self.finished = true;
        }
    }

    /// The rounds; false once the descent has ended on its own.
    fn step(&mut self, iterations: usize) -> bool {
        let (problem, bounds) = (self.problem, &self.bounds);
        let evaluate = |u: DVector<f64>, with_jacobian: bool| evaluate(problem, bounds, u, with_jacobian);
        let n = self.start.len();
        let Descent { s, lambda, nu, scale, .. } = self;
        for _ in 0..iterations {
            let j = match s.j.take() {
                Some(j) => j,
                None => evaluate(s.u.clone(), true).j.unwrap_or_else(|| DMatrix::zeros(s.r.len(), n)),
            };
            let a: DMatrix<f64> = j.tr_mul(&j);
            let g: DVector<f64> = j.tr_mul(&s.r);
            // A Jacobian that overflowed (a lobe's power of a base at 0) gives no
            // direction to follow: stop where the cost was last finite.
            if !(a.iter().all(|v| v.is_finite()) && g.iter().all(|v| v.is_finite())) {
                return false;
            }
            // MINPACK's scaling: the largest diagonal seen so far, so a direction
            // that went flat (a parameter at its bound) stays damped.
            *scale = scale.zip_map(&a.diagonal(), f64::max);
            let diag = scale.map(|d| d.max(1e-300));
            let orthogonality = g
                .iter()
                .zip(diag.iter())
                .map(|(g, d)| g.abs() / (d * s.cost).sqrt())
                .fold(0.0, f64::max);
            if orthogonality <= GTOL || s.cost == 0.0 {
                return false;
            }
            let mut expect_accept = true;
            // Raise the damping until a step lowers the cost.
            loop {
                let mut damped = a.clone();
                for i in 0..diag.len() {
                    damped[(i, i)] += *lambda * diag[i];
                }
                let Some(ch) = damped.cholesky() else {
                    *lambda *= *nu;
                    *nu *= 2.0;
                    if *lambda > 1e16 {
                        return false;
                    }
                    continue;
                };
                let mut step = ch.solve(&(-&g));
                // The transform is periodic: a step of more than a radian in `u`
                // jumps across the bounds into an arbitrary basin. Trust region of 1 rad.
                let longest = step.amax();
                if longest > MAX_STEP {
                    step *= MAX_STEP / longest;
                }
                let small_x = step.norm() <= XTOL * (s.u.norm() + XTOL);
                let trial = evaluate(&s.u + &step, expect_accept);
                // Reduction the linear model predicts: −(2gᵀδ + δᵀAδ).
                let predicted = -(2.0 * g.dot(&step) + step.dot(&(&a * &step)));
                if trial.cost < s.cost {
                    // A small decrease means convergence only for a step close to
                    // Gauss–Newton's; a heavily damped one is small by construction.
                    let small_f = s.cost - trial.cost <= FTOL * s.cost && *lambda <= 1.0;
                    let rho = (s.cost - trial.cost) / predicted.max(f64::MIN_POSITIVE);
                    *lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                    *nu = 10.0;
                    let crawling = s.cost - trial.cost <= CRAWL * s.cost;
                    *s = trial;
                    // The transform is flat at a bound: an optimum on it is
                    // approached ever more slowly (the cost is quartic in `u`
                    // there). Once progress has slowed to a crawl, try the
                    // parameters that are nearly on a bound on it; keep that if
                    // it is no worse.
                    let near: Vec<usize> = (0..s.u.len())
                        .filter(|_| crawling)
                        .filter(|&i| {
                            let d = (s.u[i].sin().abs().min(1.0)).acos();
                            d > 1.5 * ON_BOUND && d < SNAP
                        })
                        .collect();
                    if !near.is_empty() {
                        let mut u = s.u.clone();
                        for &i in &near {
                            u[i] = (std::f64::consts::FRAC_PI_2 - ON_BOUND).copysign(s.u[i].sin());
                        }
                        let snapped = evaluate(u, true);
                        if snapped.cost <= s.cost {
                            *s = snapped;
                        }
                    }
                    if small_f || small_x {
                        return false;
                    }
                    break;
                }
                expect_accept = false;
                *lambda *= *nu;
                *nu *= 2.0;
                if *lambda > 1e16 {
                    return false;
                }
            }
        }
        true
    }
}

/// The parameters at the transformed `u`.
fn external(bounds: &[Bound], u: &DVector<f64>) -> Vec<f64> {
    bounds.iter().zip(u.iter()).map(|(b, &u)| to_external(b, u)).collect()
}

/// The residuals (and, if asked, the Jacobian in the transformed
/// parameters) at `u`.
fn evaluate(problem: &Problem, bounds: &[Bound], u: DVector<f64>, with_jacobian: bool) -> State {
    let x = external(bounds, &u);
    let (r, j) = if with_jacobian {
        let (r, mut j) = problem.residuals_and_jacobian(&x);
        for (c, (b, &uc)) in bounds.iter().zip(u.iter()).enumerate() {
            let k = slope(b, uc);
            j.column_mut(c).iter_mut().for_each(|v| *v *= k);
        }
        (r, Some(j))
    } else {
        (problem.residuals(&x), None)
    };
    let r = DVector::from_vec(r);
    let cost = r.norm_squared();
    State {
        u,
        r,
        j,
        cost: if cost.is_finite() { cost } else { f64::INFINITY },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{Directions, Geometry, ModelId, Param};
    use crate::uncertainty::SHARED;

    /// Retro-phong data over a spread of geometries, with a deterministic
    /// ±3 % ripple standing in for noise.
    fn problem() -> Problem {
        let model = ModelId::RetroPhong;
        let truth = [0.3, 30.0, 0.2, 0.05, 0.01, 4.0];
        let geos: Vec<Geometry> = (0..600)
            .map(|k| {
                Geometry::new(&Directions::from_degrees(
                    10.0 + (k % 6) as f64 * 12.0,
                    (k * 7 % 80) as f64,
                    -180.0 + (k * 37 % 360) as f64,
                ))
            })
            .collect();
        let y = geos
            .iter()
            .enumerate()
            .map(|(k, g)| model.eval(g, &truth, Param::View) * (1.0 + 0.03 * (k as f64 * 0.7).sin()))
            .collect();
        let m = geos.len();
        Problem {
            model,
            param: Param::View,
            geos,
            y,
            scale: vec![1.0; m],
            weight: vec![1.0; m],
            shared: vec![[0.0; SHARED.len()]; m],
            bounds_all: model.bounds().to_vec(),
            template: truth.to_vec(),
            free: (0..truth.len()).collect(),
        }
    }

    /// The global search's race runs a descent a few rounds at a time: it
    /// keeps its damping, scaling and Jacobian between runs, so the pieces
    /// end exactly where one run of the same length does.
    #[test]
    fn a_descent_run_in_pieces_is_the_same_descent() {
        let p = problem();
        let start: Vec<f64> = p.bounds().iter().map(|b| crate::fit::transform::from_unit(b, 0.5)).collect();
        let mut whole = Descent::new(&p, &start);
        whole.run(12);
        let mut pieces = Descent::new(&p, &start);
        pieces.run(2);
        // Still going after the first piece: the pieces do continue it.
        assert!(!pieces.finished());
        for _ in 0..5 {
            pieces.run(2);
        }
        assert_eq!(whole.x(), pieces.x());
        assert_eq!(whole.cost().to_bits(), pieces.cost().to_bits());
        assert_eq!(whole.finished(), pieces.finished());
        assert!(whole.cost() < Descent::new(&p, &start).cost());
    }
}
