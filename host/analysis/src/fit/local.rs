//! Bounded local least squares: Levenberg–Marquardt on the MINUIT-transformed
//! parameters, with the exact Jacobian chained through the transform; and
//! its last steps in the parameters themselves, the box kept by projection
//! ([`Space::Box`]).
//!
//! Written here rather than taken from the `levenberg-marquardt` crate: our
//! problems are tall and thin (thousands of samples, at most 9 parameters),
//! and a pivoted QR of the whole Jacobian, as that crate's MINPACK port
//! does, costs as much as the rest of a fit (`fit-bench` times both).
//! Solving the n×n normal equations with
//! Marquardt's diagonal scaling costs `m·n²` flops and a Cholesky of at most
//! 9×9, which is plenty accurate for a handful of well-scaled parameters;
//! the damping update is Nielsen's (Madsen, Nielsen & Tingleff 2004, §3.2).

use super::problem::{Normal, Problem};
use super::transform::{slope, to_external, to_internal};
use gonio_brdf::Bound;
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

/// Where the descent takes its steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Space {
    /// In `u`, with `x = lo + (hi − lo)(sin u + 1)/2`: any step stays in the
    /// box, so a descent from anywhere in it can go anywhere. But the
    /// transform is flat at a bound: an optimum on one is approached ever
    /// more slowly and ends a few 1e-9 of the box inside it (`ON_BOUND`),
    /// and a valley along a bound is bent into one that LM crawls along.
    Transformed,
    /// In `x` itself: a step is clipped to the box, and a parameter on a
    /// bound that the gradient pushes outwards is held there for the step
    /// (the active set of projected methods such as scipy's `trf`). It lands
    /// exactly on a bound and converges along one; from a good start only,
    /// since clipping bends long steps: the global search's race, which
    /// starts from probes that are already in their basins.
    Box,
}

struct State {
    u: DVector<f64>,
    /// `JᵀJ` and `Jᵀr` in `u`, where they were evaluated.
    normal: Option<(DMatrix<f64>, DVector<f64>)>,
    cost: f64,
}

/// Minimises from `start` (free parameters, inside the bounds); returns the
/// free parameters at the minimum.
///
/// A trial point right after an accepted step is evaluated with its normal
/// equations (one pass gives both), since it is usually accepted too; after
/// a rejection only the cost is taken, since more rejections tend to follow
/// while the damping grows.
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
    space: Space,
    start: Vec<f64>,
    s: State,
    lambda: f64,
    nu: f64,
    scale: DVector<f64>,
    finished: bool,
}

impl<'a> Descent<'a> {
    /// In [`Space::Transformed`].
    pub fn new(problem: &'a Problem, start: &[f64]) -> Self {
        Descent::new_in(problem, start, Space::Transformed)
    }

    pub fn new_in(problem: &'a Problem, start: &[f64], space: Space) -> Self {
        let bounds = problem.bounds();
        let u = DVector::from_iterator(
            start.len(),
            bounds.iter().zip(start).map(|(b, &x)| match space {
                Space::Transformed => to_internal(b, x),
                Space::Box => x.clamp(b.lo, b.hi),
            }),
        );
        let s = evaluate(problem, &bounds, space, u, true);
        Descent {
            finished: !s.cost.is_finite(),
            problem,
            bounds,
            space,
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
        external(&self.bounds, self.space, &self.s.u)
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
        let (problem, bounds, space) = (self.problem, &self.bounds, self.space);
        let evaluate = |u: DVector<f64>, with_jacobian: bool| evaluate(problem, bounds, space, u, with_jacobian);
        let n = self.start.len();
        let Descent { s, lambda, nu, scale, .. } = self;
        for _ in 0..iterations {
            let (mut a, mut g) = match s.normal.take() {
                Some(normal) => normal,
                None => evaluate(s.u.clone(), true)
                    .normal
                    .unwrap_or_else(|| (DMatrix::zeros(n, n), DVector::zeros(n))),
            };
            // A Jacobian that overflowed (a lobe's power of a base at 0) gives no
            // direction to follow: stop where the cost was last finite.
            if !(a.iter().all(|v| v.is_finite()) && g.iter().all(|v| v.is_finite())) {
                return false;
            }
            // MINPACK's scaling: the largest diagonal seen so far, so a direction
            // that went flat (a parameter at its bound) stays damped.
            *scale = scale.zip_map(&a.diagonal(), f64::max);
            let diag = scale.map(|d| d.max(1e-300));
            if space == Space::Box {
                hold_on_bounds(bounds, &s.u, &mut a, &mut g, &diag);
            }
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
                    if !raise(lambda, nu) {
                        return false;
                    }
                    continue;
                };
                let next = proposal(space, bounds, &s.u, ch.solve(&(-&g)));
                // The step actually taken.
                let step = &next - &s.u;
                // Clipped to nothing (a free parameter on a bound that the coupling
                // pushes outwards): more damping turns the step towards the gradient.
                if step.iter().all(|v| *v == 0.0) {
                    if !raise(lambda, nu) {
                        return false;
                    }
                    continue;
                }
                let small_x = match space {
                    Space::Transformed => step.norm() <= XTOL * (s.u.norm() + XTOL),
                    // In the parameters' own units, which span decades (n to 1e4, k2 to 1e-12).
                    Space::Box => step.iter().zip(bounds).all(|(d, b)| d.abs() <= XTOL * (b.hi - b.lo)),
                };
                let trial = evaluate(next, expect_accept);
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
                    if crawling && space == Space::Transformed {
                        snap_to_bounds(s, &evaluate);
                    }
                    if small_f || small_x {
                        return false;
                    }
                    break;
                }
                expect_accept = false;
                if !raise(lambda, nu) {
                    return false;
                }
            }
        }
        true
    }
}

/// In the box, a parameter on a bound that the descent would push out of it
/// is held there: no gradient, no coupling to the others.
fn hold_on_bounds(bounds: &[Bound], u: &DVector<f64>, a: &mut DMatrix<f64>, g: &mut DVector<f64>, diag: &DVector<f64>) {
    for (i, b) in bounds.iter().enumerate() {
        if (u[i] <= b.lo && g[i] > 0.0) || (u[i] >= b.hi && g[i] < 0.0) {
            g[i] = 0.0;
            a.row_mut(i).fill(0.0);
            a.column_mut(i).fill(0.0);
            a[(i, i)] = diag[i];
        }
    }
}

/// Where the solved `step` from `u` lands.
fn proposal(space: Space, bounds: &[Bound], u: &DVector<f64>, mut step: DVector<f64>) -> DVector<f64> {
    match space {
        // The transform is periodic: a step of more than a radian in `u`
        // jumps across the bounds into an arbitrary basin. Trust region of 1 rad.
        Space::Transformed => {
            let longest = step.amax();
            if longest > MAX_STEP {
                step *= MAX_STEP / longest;
            }
            u + &step
        }
        // Clipped to the box, so a parameter lands exactly on its bound
        // (`u + (clamped − u)` can miss it by an ulp, either way).
        Space::Box => DVector::from_iterator(u.len(), bounds.iter().enumerate().map(|(i, b)| (u[i] + step[i]).clamp(b.lo, b.hi))),
    }
}

/// The transform is flat at a bound: an optimum on it is approached ever
/// more slowly (the cost is quartic in `u` there). Once progress has slowed
/// to a crawl, the parameters that are nearly on a bound are tried on it;
/// that is kept if it is no worse.
fn snap_to_bounds(s: &mut State, evaluate: &impl Fn(DVector<f64>, bool) -> State) {
    let near: Vec<usize> = (0..s.u.len())
        .filter(|&i| {
            let d = (s.u[i].sin().abs().min(1.0)).acos();
            d > 1.5 * ON_BOUND && d < SNAP
        })
        .collect();
    if near.is_empty() {
        return;
    }
    let mut u = s.u.clone();
    for &i in &near {
        u[i] = (std::f64::consts::FRAC_PI_2 - ON_BOUND).copysign(s.u[i].sin());
    }
    let snapped = evaluate(u, true);
    if snapped.cost <= s.cost {
        *s = snapped;
    }
}

/// Raises the damping after a failed step (Nielsen's update); false once it
/// is past any use.
fn raise(lambda: &mut f64, nu: &mut f64) -> bool {
    *lambda *= *nu;
    *nu *= 2.0;
    *lambda <= 1e16
}

/// The parameters at `u`.
fn external(bounds: &[Bound], space: Space, u: &DVector<f64>) -> Vec<f64> {
    match space {
        Space::Transformed => bounds.iter().zip(u.iter()).map(|(b, &u)| to_external(b, u)).collect(),
        Space::Box => u.iter().copied().collect(),
    }
}

/// The cost (and, if asked, the normal equations in `u`) at `u`.
fn evaluate(problem: &Problem, bounds: &[Bound], space: Space, u: DVector<f64>, with_jacobian: bool) -> State {
    let x = external(bounds, space, &u);
    let (cost, normal) = if with_jacobian {
        let Normal { cost, mut a, mut g } = problem.normal_equations(&x);
        // Chained through the transform: ∂x/∂u per parameter.
        if space == Space::Transformed {
            let k = DVector::from_iterator(u.len(), bounds.iter().zip(u.iter()).map(|(b, &uc)| slope(b, uc)));
            a.component_mul_assign(&(&k * k.transpose()));
            g.component_mul_assign(&k);
        }
        (cost, Some((a, g)))
    } else {
        (problem.cost(&x), None)
    };
    State { u, normal, cost }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem() -> Problem {
        crate::fit::problem::retro_phong_fixture(600)
    }

    /// The global search's race runs a descent a few rounds at a time: it
    /// keeps its damping, scaling and normal equations between runs, so the pieces
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

    /// An optimum outside the box (the exponent's truth, 30, above a box
    /// cut at 20.3). From the transformed descent's end with the exponent on
    /// the bound and the others 20 % off, the descent in the box holds the
    /// exponent there while the others, coupled to it, go on to the optimum
    /// of the problem with the exponent fixed at 20.3 (to 1e-9 of its cost)
    /// in a few rounds (5; without the hold, 500 rounds ended 0.7 % above
    /// it), and nothing leaves the box.
    #[test]
    fn in_the_box_an_optimum_on_a_bound_is_reached() {
        let mut p = problem();
        p.bounds_all[1].hi = 20.3;
        let start: Vec<f64> = p.bounds().iter().map(|b| crate::fit::transform::from_unit(b, 0.5)).collect();
        let mut transformed = Descent::new(&p, &start);
        transformed.run(MAX_ITERATIONS);
        assert!(transformed.x()[1] < 20.3);
        let from: Vec<f64> = (transformed.x().iter().enumerate())
            .map(|(i, &v)| if i == 1 { 20.3 } else { 1.2 * v })
            .collect();
        let mut boxed = Descent::new_in(&p, &from, Space::Box);
        boxed.run(20);
        assert!(boxed.finished());
        assert_eq!(boxed.x()[1], 20.3);
        assert!(boxed.x().iter().zip(p.bounds()).all(|(v, b)| (b.lo..=b.hi).contains(v)));
        let mut fixed = p.clone();
        fixed.template[1] = 20.3;
        fixed.free = vec![0, 2, 3, 4, 5];
        let rest: Vec<f64> = [0, 2, 3, 4, 5].iter().map(|&i| start[i]).collect();
        let on_bound = fixed.cost(&minimize(&fixed, &rest));
        assert!((boxed.cost() - on_bound).abs() <= 1e-9 * on_bound, "{} vs {on_bound}", boxed.cost());
    }
}
