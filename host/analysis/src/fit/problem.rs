//! One least-squares problem: a model, the samples it is fitted to, the
//! weights, and which parameters are free. Residuals are
//! `w_k·(s_k·f(g_k; p) − y_k)`, with `s_k` the factor from `f_r` to the
//! fitting units (1 or `cosθo`), and exact Jacobians by forward-mode
//! differentiation (`num-dual`).

use crate::uncertainty::SHARED;
use gonio_brdf::{Bound, GeometryTerms, ModelId, Param};
use nalgebra::{Const, DMatrix, DVector, U1};
use num_dual::DualSVec64;
use rayon::prelude::*;
use std::ops::Range;

/// Samples per task of the parallel evaluation: a task of 256 samples is
/// some 5–300 µs of model, above rayon's few microseconds to hand it to a
/// thread. Sums stay in task order, and the tasks do not depend on the
/// number of threads, so a fit gives the same numbers on any number of them.
const CHUNK: usize = 256;
/// Fewer samples than this are evaluated on the calling thread: the global
/// search's subsets (600 samples and up) are evaluated many candidates at a
/// time instead, one per thread, where the hand-over costs nothing. The
/// probes' subset of data past 20 480 samples, and CMA-ES's past 40 960, are
/// larger, and nest their tasks inside the candidates' (rayon's work stealing
/// runs both).
const PARALLEL_MIN: usize = 2048;
/// Most free parameters of any model (`abc-retro-per-lobe`).
const MAX_FREE: usize = 9;

/// `task` over the samples `0..m`, in tasks of [`CHUNK`] samples on all
/// threads when there are enough samples to pay for them, else at once
/// here; the results in sample order.
fn tasks<T: Send>(m: usize, task: impl Fn(Range<usize>) -> T + Sync) -> Vec<T> {
    if m < PARALLEL_MIN {
        vec![task(0..m)]
    } else {
        (0..m.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| task(c * CHUNK..((c + 1) * CHUNK).min(m)))
            .collect()
    }
}

/// What a pass over the samples keeps of each weighted residual and its row
/// of the Jacobian, one `Part` per task.
trait Gather: Sync {
    type Part: Send;
    fn start(&self, samples: usize) -> Self::Part;
    fn add(&self, part: &mut Self::Part, r: f64, row: &[f64]);
}

/// The residuals and the whole Jacobian, row by row (`n` per row).
struct Dense(usize);

impl Gather for Dense {
    type Part = (Vec<f64>, Vec<f64>);
    fn start(&self, samples: usize) -> Self::Part {
        (Vec::with_capacity(samples), Vec::with_capacity(samples * self.0))
    }
    fn add(&self, (r, rows): &mut Self::Part, rk: f64, row: &[f64]) {
        r.push(rk);
        rows.extend_from_slice(row);
    }
}

/// What a Levenberg–Marquardt step needs of a point, `JᵀJ`, `Jᵀr` and `Σr²`,
/// summed as the rows are made: the `m×n` Jacobian is never stored
/// (storing it and multiplying it out costs as much as computing it).
#[derive(Debug, Clone)]
pub struct Normal {
    pub cost: f64,
    /// `JᵀJ`.
    pub a: DMatrix<f64>,
    /// `Jᵀr`.
    pub g: DVector<f64>,
}

/// [`Normal`] of `n` parameters, summed.
struct Sums(usize);

impl Gather for Sums {
    type Part = Normal;
    fn start(&self, _: usize) -> Normal {
        Normal {
            cost: 0.0,
            a: DMatrix::zeros(self.0, self.0),
            g: DVector::zeros(self.0),
        }
    }
    fn add(&self, part: &mut Normal, r: f64, row: &[f64]) {
        part.cost += r * r;
        for (i, &ji) in row.iter().enumerate() {
            part.g[i] += ji * r;
            for (k, &jk) in row.iter().enumerate().take(i + 1) {
                part.a[(i, k)] += ji * jk;
            }
        }
    }
}

#[derive(Debug, Clone)]
pub struct Problem {
    pub model: ModelId,
    pub param: Param,
    pub geos: Vec<GeometryTerms>,
    /// Targets in the fitting units.
    pub y: Vec<f64>,
    /// `f_r` → fitting units, per sample.
    pub scale: Vec<f64>,
    pub weight: Vec<f64>,
    /// Weighted shifts of the targets when each shared input is off by one
    /// standard uncertainty (`Observation::shared`), per sample.
    pub shared: Vec<[f64; SHARED.len()]>,
    /// The search box of every parameter (`ModelId::bounds_for` the data,
    /// with the user's overrides).
    pub bounds_all: Vec<Bound>,
    /// Every parameter; the free ones are overwritten on evaluation.
    pub template: Vec<f64>,
    /// Indices of the free parameters.
    pub free: Vec<usize>,
}

impl Problem {
    pub fn bounds(&self) -> Vec<Bound> {
        self.free.iter().map(|&i| self.bounds_all[i]).collect()
    }

    /// Every parameter, with the free ones set to `x`.
    pub fn full(&self, x: &[f64]) -> Vec<f64> {
        let mut p = self.template.clone();
        for (&i, &v) in self.free.iter().zip(x) {
            p[i] = v;
        }
        p
    }

    /// Model values in the fitting units.
    pub fn predict(&self, x: &[f64]) -> Vec<f64> {
        let p = self.full(x);
        self.geos
            .iter()
            .zip(&self.scale)
            .map(|(g, s)| s * self.model.eval(g, &p, self.param))
            .collect()
    }

    /// Sample `k`'s weighted residual where the model gives `f_r = f`.
    fn residual(&self, k: usize, f: f64) -> f64 {
        self.weight[k] * (self.scale[k] * f - self.y[k])
    }

    /// `Σ r²`, the samples shared among the threads; infinite where the
    /// model overflows. Summed as
    /// [`Problem::normal_equations`] sums it, so a descent compares like
    /// with like whichever of the two gave a point's cost.
    pub fn cost(&self, x: &[f64]) -> f64 {
        let p = self.full(x);
        let parts = tasks(self.geos.len(), |range| {
            let mut c = 0.0;
            for k in range {
                let r = self.residual(k, self.model.eval(&self.geos[k], &p, self.param));
                c += r * r;
            }
            c
        });
        let sum = parts.into_iter().fold(0.0, |sum, c| sum + c);
        if sum.is_finite() {
            sum
        } else {
            f64::INFINITY
        }
    }

    /// Residuals and `∂r/∂x` for the free parameters.
    pub fn residuals_and_jacobian(&self, x: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        let n = self.free.len();
        let (r, rows): (Vec<Vec<f64>>, Vec<Vec<f64>>) = self.rows(x, &Dense(n)).into_iter().unzip();
        let m = self.geos.len();
        (r.concat(), DMatrix::from_row_iterator(m, n, rows.concat()))
    }

    /// `JᵀJ`, `Jᵀr` and `Σr²` at `x` (infinite where the model overflows),
    /// summed in task order whatever the number of threads.
    pub fn normal_equations(&self, x: &[f64]) -> Normal {
        let n = self.free.len();
        let mut sum = Sums(n).start(0);
        for part in self.rows(x, &Sums(n)) {
            sum.cost += part.cost;
            sum.a += part.a;
            sum.g += part.g;
        }
        for i in 0..n {
            for k in i + 1..n {
                sum.a[(i, k)] = sum.a[(k, i)];
            }
        }
        if !sum.cost.is_finite() {
            sum.cost = f64::INFINITY;
        }
        sum
    }

    /// Every sample's weighted residual and Jacobian row, as `gather` keeps
    /// them. The dual numbers carry exactly as many derivatives as there are
    /// free parameters (up to the 9 of `abc-retro-per-lobe`), so a one-parameter
    /// fit does not pay for nine; models with a hand-written gradient use it.
    fn rows<G: Gather>(&self, x: &[f64], gather: &G) -> Vec<G::Part> {
        if let Some(gradient) = self.model.hand_gradient() {
            let full = self.full(x);
            return self.weighted_rows(full.len(), gather, |g, row, grad| {
                let f = gradient(g, &full, self.param, grad);
                row.iter_mut().zip(&self.free).for_each(|(d, &i)| *d = grad[i]);
                f
            });
        }
        match self.free.len() {
            1 => self.dual_rows::<1, G>(x, gather),
            2 => self.dual_rows::<2, G>(x, gather),
            3 => self.dual_rows::<3, G>(x, gather),
            4 => self.dual_rows::<4, G>(x, gather),
            5 => self.dual_rows::<5, G>(x, gather),
            6 => self.dual_rows::<6, G>(x, gather),
            7 => self.dual_rows::<7, G>(x, gather),
            8 => self.dual_rows::<8, G>(x, gather),
            _ => self.dual_rows::<MAX_FREE, G>(x, gather),
        }
    }

    fn dual_rows<const N: usize, G: Gather>(&self, x: &[f64], gather: &G) -> Vec<G::Part> {
        let full = self.full(x);
        let mut p: Vec<DualSVec64<N>> = full.iter().map(|&v| DualSVec64::from_re(v)).collect();
        for (j, &i) in self.free.iter().enumerate() {
            p[i] = DualSVec64::from_re(full[i]).derivative(j);
        }
        self.weighted_rows(0, gather, |g, row, _| {
            let f = self.model.eval(g, &p, self.param);
            row.copy_from_slice(f.eps.unwrap_generic(Const::<N>, U1).as_slice());
            f.re
        })
    }

    /// Each sample's weighted residual and row, from `sample`, which
    /// returns `f_r` at a geometry and writes its derivatives into the row,
    /// with a scratch of `scratch` values of its own; handed to `gather`.
    fn weighted_rows<G: Gather>(
        &self,
        scratch: usize,
        gather: &G,
        sample: impl Fn(&GeometryTerms, &mut [f64], &mut [f64]) -> f64 + Sync,
    ) -> Vec<G::Part> {
        let n = self.free.len();
        tasks(self.geos.len(), |range| {
            let mut part = gather.start(range.len());
            let mut buf = vec![0.0; scratch];
            let mut row = [0.0; MAX_FREE];
            let row = &mut row[..n];
            for k in range {
                let f = sample(&self.geos[k], row, &mut buf);
                let ws = self.weight[k] * self.scale[k];
                row.iter_mut().for_each(|d| *d *= ws);
                gather.add(&mut part, self.residual(k, f), row);
            }
            part
        })
    }

    /// A problem on about `n` of the samples: the global search's cheap
    /// proxy. Narrow lobes show only in a few samples near their peaks, which
    /// a plain stride would miss; so the `n/4` samples of largest weighted
    /// target are always in, and a stride over the rest fills up.
    pub fn subset(&self, n: usize) -> Problem {
        let m = self.geos.len();
        if m <= n {
            return self.clone();
        }
        let mut by_size: Vec<usize> = (0..m).collect();
        by_size.sort_by(|&a, &b| (self.weight[b] * self.y[b]).abs().total_cmp(&(self.weight[a] * self.y[a]).abs()));
        let mut keep = vec![false; m];
        by_size.iter().take(n / 4).for_each(|&k| keep[k] = true);
        let stride = m.div_ceil(n - n / 4);
        (0..m).step_by(stride).for_each(|k| keep[k] = true);
        let pick = |v: &Vec<f64>| (0..m).filter(|&k| keep[k]).map(|k| v[k]).collect();
        Problem {
            geos: (0..m).filter(|&k| keep[k]).map(|k| self.geos[k]).collect(),
            y: pick(&self.y),
            scale: pick(&self.scale),
            weight: pick(&self.weight),
            shared: (0..m).filter(|&k| keep[k]).map(|k| self.shared[k]).collect(),
            ..self.clone()
        }
    }
}

/// A retro-phong problem for the unit tests: `m` samples over a spread of
/// geometries, with a deterministic ±3 % ripple standing in for noise.
#[cfg(test)]
pub(super) fn retro_phong_fixture(m: usize) -> Problem {
    use gonio_brdf::Directions;
    let model = ModelId::RetroPhong;
    let truth = [0.3, 30.0, 0.2, 0.05, 0.01, 4.0];
    let geos: Vec<GeometryTerms> = (0..m)
        .map(|k| {
            GeometryTerms::new(&Directions::from_degrees(
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The normal equations summed task by task are `JᵀJ`, `Jᵀr` and `Σr²`
    /// of the stored Jacobian, symmetric, on enough samples to be split
    /// among the threads; and the cost alone is the very same number.
    #[test]
    fn normal_equations_are_those_of_the_jacobian() {
        let p = retro_phong_fixture(3 * PARALLEL_MIN);
        let x = [0.25, 22.0, 0.3, 0.02, 0.02, 3.0];
        let (r, j) = p.residuals_and_jacobian(&x);
        let r = DVector::from_vec(r);
        let Normal { cost, a, g } = p.normal_equations(&x);
        let (want_a, want_g) = (j.tr_mul(&j), j.tr_mul(&r));
        for i in 0..6 {
            assert!((g[i] - want_g[i]).abs() <= 1e-9 * want_g.amax());
            for k in 0..6 {
                assert!((a[(i, k)] - want_a[(i, k)]).abs() <= 1e-9 * want_a.amax(), "({i}, {k})");
                assert_eq!(a[(i, k)], a[(k, i)]);
            }
        }
        assert!((cost - r.norm_squared()).abs() <= 1e-12 * cost);
        assert_eq!(cost.to_bits(), p.cost(&x).to_bits());
    }
}
