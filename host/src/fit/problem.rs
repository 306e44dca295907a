//! One least-squares problem: a model, the samples it is fitted to, the
//! weights, and which parameters are free. Residuals are
//! `w_k·(s_k·f(g_k; p) − y_k)`, with `s_k` the factor from `f_r` to the
//! fitting units (1 or `cosθo`), and exact Jacobians by forward-mode
//! differentiation (`num-dual`).

use crate::brdf::{Bound, Geometry, HandGradient, ModelId, Param};
use crate::uncertainty::SHARED;
use nalgebra::{Const, DMatrix, U1};
use num_dual::DualSVec64;
use rayon::prelude::*;

/// Samples per task of the parallel evaluation: a task of 256 samples is
/// some 5–300 µs of model, above rayon's few microseconds to hand it to a
/// thread. Sums stay sequential over the samples, so a fit gives the same
/// numbers on any number of threads.
const CHUNK: usize = 256;
/// Fewer samples than this are evaluated on the calling thread: the global
/// search's subsets (600 samples and up) are evaluated many candidates at a
/// time instead, one per thread, where the hand-over costs nothing. A subset
/// of data past 40 960 samples is larger, and nests its tasks inside the
/// candidates' (rayon's work stealing runs both).
const PARALLEL_MIN: usize = 2048;

/// Fills `out`, `width` values per sample, with `f(first sample, its part)`:
/// in tasks of [`CHUNK`] samples on all threads when there are enough
/// samples to pay for them, else at once here.
fn fill(out: &mut [f64], width: usize, f: impl Fn(usize, &mut [f64]) + Sync) {
    if out.len() < PARALLEL_MIN * width {
        f(0, out);
    } else {
        out.par_chunks_mut(CHUNK * width)
            .enumerate()
            .for_each(|(c, part)| f(c * CHUNK, part));
    }
}

#[derive(Debug, Clone)]
pub struct Problem {
    pub model: ModelId,
    pub param: Param,
    pub geos: Vec<Geometry>,
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

    /// Weighted residuals, the samples shared among the threads.
    pub fn residuals(&self, x: &[f64]) -> Vec<f64> {
        let p = self.full(x);
        let mut r = vec![0.0; self.geos.len()];
        fill(&mut r, 1, |first, out| {
            for (k, r) in (first..).zip(out) {
                *r = self.residual(k, self.model.eval(&self.geos[k], &p, self.param));
            }
        });
        r
    }

    /// Sample `k`'s weighted residual where the model gives `f_r = f`.
    fn residual(&self, k: usize, f: f64) -> f64 {
        self.weight[k] * (self.scale[k] * f - self.y[k])
    }

    /// `Σ r²`; infinite where the model overflows.
    pub fn cost(&self, x: &[f64]) -> f64 {
        let sum: f64 = self.residuals(x).iter().map(|r| r * r).sum();
        if sum.is_finite() {
            sum
        } else {
            f64::INFINITY
        }
    }

    /// Residuals and `∂r/∂x` for the free parameters. The dual numbers carry
    /// exactly as many derivatives as there are free parameters (up to the 8
    /// of `abc-retro`), so a one-parameter fit does not pay for eight.
    pub fn residuals_and_jacobian(&self, x: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        if let Some(gradient) = self.model.hand_gradient() {
            return self.hand_jacobian(x, gradient);
        }
        match self.free.len() {
            1 => self.jacobian_n::<1>(x),
            2 => self.jacobian_n::<2>(x),
            3 => self.jacobian_n::<3>(x),
            4 => self.jacobian_n::<4>(x),
            5 => self.jacobian_n::<5>(x),
            6 => self.jacobian_n::<6>(x),
            7 => self.jacobian_n::<7>(x),
            _ => self.jacobian_n::<8>(x),
        }
    }

    fn hand_jacobian(&self, x: &[f64], gradient: HandGradient) -> (Vec<f64>, DMatrix<f64>) {
        let full = self.full(x);
        self.weighted_rows(self.free.len(), full.len(), |g, row, grad| {
            let f = gradient(g, &full, grad);
            row.iter_mut().zip(&self.free).for_each(|(d, &i)| *d = grad[i]);
            f
        })
    }

    fn jacobian_n<const N: usize>(&self, x: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        let full = self.full(x);
        let mut p: Vec<DualSVec64<N>> = full.iter().map(|&v| DualSVec64::from_re(v)).collect();
        for (j, &i) in self.free.iter().enumerate() {
            p[i] = DualSVec64::from_re(full[i]).derivative(j);
        }
        self.weighted_rows(N, 0, |g, row, _| {
            let f = self.model.eval(g, &p, self.param);
            row.copy_from_slice(f.eps.unwrap_generic(Const::<N>, U1).as_slice());
            f.re
        })
    }

    /// Residuals and Jacobian from `sample`, which returns `f_r` at a
    /// geometry and writes its `n` derivatives into the row, with a scratch
    /// of `scratch` values of its own; the samples shared among the threads.
    fn weighted_rows(
        &self,
        n: usize,
        scratch: usize,
        sample: impl Fn(&Geometry, &mut [f64], &mut [f64]) -> f64 + Sync,
    ) -> (Vec<f64>, DMatrix<f64>) {
        let m = self.geos.len();
        // Per sample: its residual, then its row of the Jacobian.
        let width = n + 1;
        let mut out = vec![0.0; m * width];
        fill(&mut out, width, |first, part| {
            let mut buf = vec![0.0; scratch];
            for (k, sample_out) in (first..).zip(part.chunks_exact_mut(width)) {
                let (r, row) = sample_out.split_at_mut(1);
                let f = sample(&self.geos[k], row, &mut buf);
                let ws = self.weight[k] * self.scale[k];
                row.iter_mut().for_each(|d| *d *= ws);
                r[0] = self.residual(k, f);
            }
        });
        let r = out.iter().step_by(width).copied().collect();
        (r, DMatrix::from_fn(m, n, |k, j| out[k * width + 1 + j]))
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
