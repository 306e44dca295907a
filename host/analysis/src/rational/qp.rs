//! One basis's programme (Pacanowski et al. 2012, as ALTA's
//! `rational_fitter_quadprog` poses it): coefficients `x = (p, q)` such
//! that every sample's segment holds `P/Q`,
//!
//! `P(u) − lo·Q(u) ≥ 0` and `hi·Q(u) − P(u) ≥ 0`,
//!
//! each row scaled to unit norm. With `lo ≥ 0 < hi` the two rows imply
//! `Q > 0` at every sample. On a grid over the whole box (`grid_size`),
//! `Q > 0` and `P ≥ 0` as well: no pole and no negative value at the
//! grid's points, where there are no samples as much as where there are.
//! Between grid points nothing is proven: `Rational::eval` says where
//! `Q ≤ 0`.
//!
//! ALTA minimises `‖x‖²` with every margin row `≥ 1`. Posed so, a set of
//! segments that is barely feasible has a solution of huge norm and an
//! infeasible one no solution at all, and the interior-point method spends
//! its iterations telling the two apart (300 iterations without an answer
//! at degree 8). The same solution, up to its scale, is the one of largest
//! margin: maximise `t` with every margin row `≥ t` and `‖x‖ ≤ 1` (the
//! least-norm solution is `x/t`). That programme is always feasible and
//! bounded; the segments can be held iff `t > 0` (the fit then checks the
//! candidate on every segment), and when they cannot, its dual weights
//! are a certificate of which samples conflict. Solved by
//! Clarabel (interior point, a second-order cone for the norm).

use super::basis::Basis;
use anyhow::{anyhow, bail, Result};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus};

/// A sample as the programme sees it: its point in [−1, 1]³ and its segment
/// of the rational part (`f_r` divided by the cosine factor).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    pub u: [f64; 3],
    pub lo: f64,
    pub hi: f64,
}

/// What one basis gives.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Numerator and denominator coefficients, and the margin `t` they
    /// were found with (rows and coefficients of unit norm): a candidate,
    /// which the fit checks on every segment.
    Solved {
        p: Vec<f64>,
        q: Vec<f64>,
        margin: f64,
        reduced: bool,
    },
    /// No function of this basis holds every segment; `worst` is the
    /// sample with the largest dual weight at the zero margin, the one most
    /// in conflict with the others.
    Infeasible { worst: usize, reduced: bool },
}

/// The grid over the box where the denominator is held positive and the
/// numerator non-negative: `2d + 1` points per coordinate (at least 9),
/// ends included, so that a polynomial of degree `d` cannot turn between
/// two of its points more than once.
fn grid_size(degree: usize) -> usize {
    (2 * degree + 1).max(9)
}

/// Solves the programme of `basis` for `rows`.
///
/// By constraint generation: a programme over every row at once costs
/// Clarabel a factorisation of `m·n²` per interior-point iteration (0.4 s
/// at 4 500 rows and degree 8), while at the optimum only the rows it
/// touches matter, a few times `n` of them (as in a support-vector
/// machine). So a spread subset is solved, every row checked, the most
/// violated added, until none is. A subset's margin bounds the whole
/// programme's from above, so a subset that cannot be held proves the
/// whole one cannot; when every row holds the subset's margin, the
/// subset's solution is the whole programme's.
pub fn solve(basis: &Basis, rows: &[Row]) -> Result<Outcome> {
    let c = Constraints::new(basis, rows);
    let m = c.rows.len();
    let n = c.n;
    let samples = 2 * rows.len();
    let mut taken = vec![false; m];
    let mut working: Vec<usize> = {
        // About n samples and n grid points, each at a stride.
        let stride = (rows.len() / n).max(1);
        let mut w: Vec<usize> = (0..rows.len()).step_by(stride).flat_map(|i| [2 * i, 2 * i + 1]).collect();
        let points = (m - samples) / 2;
        w.extend(
            (0..points)
                .step_by((points / n).max(1))
                .flat_map(|i| [samples + 2 * i, samples + 2 * i + 1]),
        );
        w
    };
    for &i in &working {
        taken[i] = true;
    }
    for _ in 0..ROUNDS {
        let Margin { x, t, z, reduced } = c.solve(&working, basis.degree)?;
        if t <= 0.0 {
            // The dual weights of the margin rows sum to 1 and balance
            // each other: the largest is the sample most in conflict.
            let mut weight = vec![0.0; rows.len()];
            for (k, &r) in working.iter().enumerate() {
                if r < samples {
                    weight[r / 2] += z[k];
                }
            }
            let worst = (0..rows.len()).max_by(|&i, &j| weight[i].total_cmp(&weight[j])).unwrap_or(0);
            return Ok(Outcome::Infeasible { worst, reduced });
        }
        let mut violated: Vec<(f64, usize)> = (0..m)
            .filter(|&i| !taken[i])
            .filter_map(|i| {
                let short = c.margin(i) * t * (1.0 - 1e-6) - c.dot(i, &x);
                (short > SLACK).then_some((short, i))
            })
            .collect();
        if violated.is_empty() {
            // The least-norm scale, as ALTA's solution: every margin ≥ 1.
            let k = basis.len();
            return Ok(Outcome::Solved {
                p: x[..k].iter().map(|v| v / t).collect(),
                q: x[k..].iter().map(|v| v / t).collect(),
                margin: t,
                reduced,
            });
        }
        violated.sort_by(|a, b| b.0.total_cmp(&a.0));
        let add = n.max(violated.len() / 8);
        for &(_, i) in violated.iter().take(add) {
            taken[i] = true;
            working.push(i);
        }
    }
    bail!(
        "the programme of {} terms (degree {}) still had violated segments after {ROUNDS} rounds of constraint generation",
        basis.len(),
        basis.degree
    )
}

/// One subset's answer: coefficients and margin (unit norms), the dual
/// weights of its rows, and whether Clarabel reached only its reduced
/// accuracy (`AlmostSolved`: gap 5e-5, feasibility 1e-4). A candidate is
/// checked on every segment whatever the accuracy; an infeasible verdict
/// at reduced accuracy is said as such (`Attempt::reduced`).
struct Margin {
    x: Vec<f64>,
    t: f64,
    z: Vec<f64>,
    reduced: bool,
}

/// Rounds of constraint generation before giving up.
const ROUNDS: usize = 60;

/// How far below its share of the margin a row left out may fall and count
/// as held: rows of margin 0 (the numerator's sign) have no slack of their
/// own, and noise of 1e-12 must not keep adding them.
const SLACK: f64 = 1e-9;

/// Every row `a·x ≥ margin·t` of the programme, `‖a‖ = 1`: `margin = 1`
/// for the segments and the denominator on the grid, `0` for the
/// numerator's sign on the grid.
///
/// Each row is a pair `(α, β)` times its point's terms `t̂` (unit norm):
/// `a = (α t̂, β t̂)/‖(α, β)‖`. Kept so, 50 000 samples of degree 8 take
/// 66 MB (a term vector per point) where the rows written out would take
/// four times that.
struct Constraints {
    /// Row-major `points × k`: each point's terms, of unit norm.
    terms: Vec<f64>,
    /// Per row: its point, `(α, β)` of unit norm, and its margin.
    rows: Vec<(usize, [f64; 2], f64)>,
    k: usize,
    n: usize,
}

impl Constraints {
    fn new(basis: &Basis, rows: &[Row]) -> Constraints {
        let k = basis.len();
        let g = grid_size(basis.degree);
        let at = |i: usize| -1.0 + 2.0 * i as f64 / (g - 1) as f64;
        let grid = (0..g.pow(3)).map(|i| [at(i / (g * g)), at(i / g % g), at(i % g)]);
        let points: Vec<[f64; 3]> = rows.iter().map(|r| r.u).chain(grid).collect();
        let mut terms = vec![0.0; points.len() * k];
        for (p, t) in points.iter().zip(terms.chunks_exact_mut(k)) {
            basis.values(*p, t);
            let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 {
                t.iter_mut().for_each(|v| *v /= norm);
            }
        }
        let unit = |a: f64, b: f64| {
            let norm = a.hypot(b);
            [a / norm, b / norm]
        };
        let mut out = Vec::with_capacity(2 * points.len());
        for (i, r) in rows.iter().enumerate() {
            out.push((i, unit(1.0, -r.lo), 1.0));
            out.push((i, unit(-1.0, r.hi), 1.0));
        }
        for i in rows.len()..points.len() {
            out.push((i, [0.0, 1.0], 1.0));
            out.push((i, [1.0, 0.0], 0.0));
        }
        Constraints {
            terms,
            rows: out,
            k,
            n: 2 * k,
        }
    }

    /// Row `i`'s coefficient `j`.
    fn at(&self, i: usize, j: usize) -> f64 {
        let (point, ab, _) = self.rows[i];
        let (half, j) = if j < self.k { (0, j) } else { (1, j - self.k) };
        ab[half] * self.terms[point * self.k + j]
    }

    fn margin(&self, i: usize) -> f64 {
        self.rows[i].2
    }

    fn dot(&self, i: usize, x: &[f64]) -> f64 {
        let (point, [a, b], _) = self.rows[i];
        let t = &self.terms[point * self.k..(point + 1) * self.k];
        let (p, q) = x.split_at(self.k);
        let tp: f64 = t.iter().zip(p).map(|(t, x)| t * x).sum();
        let tq: f64 = t.iter().zip(q).map(|(t, x)| t * x).sum();
        a * tp + b * tq
    }

    /// The largest margin over the rows `subset`: `(x, t, dual weights)`.
    /// Variables `(x, t)`; Clarabel's form `A z + s = b`: a row
    /// `a·x − margin·t = s ≥ 0`, then `(1, x)` in the second-order cone.
    fn solve(&self, subset: &[usize], degree: usize) -> Result<Margin> {
        let n = self.n;
        let m = subset.len();
        let (mut colptr, mut rowval, mut nzval) = (Vec::with_capacity(n + 2), Vec::new(), Vec::new());
        colptr.push(0);
        for j in 0..n {
            for (r, &i) in subset.iter().enumerate() {
                let v = self.at(i, j);
                if v != 0.0 {
                    rowval.push(r);
                    nzval.push(-v);
                }
            }
            // The cone's coordinate j + 1 is x_j.
            rowval.push(m + 1 + j);
            nzval.push(-1.0);
            colptr.push(rowval.len());
        }
        for (r, &i) in subset.iter().enumerate() {
            if self.margin(i) != 0.0 {
                rowval.push(r);
                nzval.push(self.margin(i));
            }
        }
        colptr.push(rowval.len());
        let a = CscMatrix::new(m + 1 + n, n + 1, colptr, rowval, nzval);
        let mut b = vec![0.0; m + 1 + n];
        b[m] = 1.0;
        let mut q = vec![0.0; n + 1];
        q[n] = -1.0;
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(200)
            .build()
            .map_err(|e| anyhow!("Clarabel's settings: {e}"))?;
        let cones = [NonnegativeConeT(m), SecondOrderConeT(n + 1)];
        let mut solver = match DefaultSolver::new(&CscMatrix::zeros((n + 1, n + 1)), &q, &a, &b, &cones, settings) {
            Ok(s) => s,
            Err(e) => bail!("the programme at degree {degree} was refused by Clarabel: {e:?}"),
        };
        solver.solve();
        let s = &solver.solution;
        match s.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(Margin {
                x: s.x[..n].to_vec(),
                t: s.x[n],
                z: s.z[..m].to_vec(),
                reduced: s.status == SolverStatus::AlmostSolved,
            }),
            other => bail!(
                "the programme at degree {degree} did not converge (Clarabel: {other:?} after {} iterations)",
                s.iterations
            ),
        }
    }
}
