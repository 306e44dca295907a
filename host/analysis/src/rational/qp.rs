//! One basis's programme (Pacanowski et al. 2012, as ALTA's
//! `rational_fitter_quadprog` poses it): the least-norm coefficients
//! `x = (p, q)` such that every sample's segment holds `P/Q`,
//!
//! `P(u) − lo·Q(u) ≥ 1` and `hi·Q(u) − P(u) ≥ 1`,
//!
//! each row scaled to unit norm. With `lo ≥ 0 < hi` the two rows imply
//! `Q > 0` at every sample. On a grid over the whole box (`grid_size`),
//! `Q ≥ 1` and `P ≥ 0` as well: no pole and no negative value at the
//! grid's points, where there are no samples as much as where there are.
//! Between grid points nothing is proven: `Rational::eval` says where
//! `Q ≤ 0`.
//!
//! The least-norm solution is, up to its scale, the one of largest margin
//! (`x/‖x‖` holds every row by `1/‖x‖`), which `Outcome::Solved` reports.
//! Solved by Goldfarb–Idnani's dual active-set method (`active_set`), as
//! ALTA does with QuadProg++: at the optimum only a few times `n` rows
//! are active, and the method takes them one at a time, the most violated
//! first, so a programme costs a scan of the rows per step rather than a
//! factorisation over all of them. The samples are scanned before the
//! grid: a grid row is taken only once every segment holds, as most never
//! bind.

use super::active_set::{self, HalfSpaces};
use super::basis::Basis;
use anyhow::{bail, Result};

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
    /// Numerator and denominator coefficients (every row ≥ 1) and the
    /// margin `1/‖x‖` of the unit-norm solution: a candidate, which the
    /// fit checks on every segment.
    Solved { p: Vec<f64>, q: Vec<f64>, margin: f64 },
    /// No function of this basis holds every segment by the margin asked for;
    /// `worst` is the sample the method could not take in with the others
    /// (or, when that was a grid point, one of the samples against it).
    Infeasible { worst: usize },
}

/// The grid over the box where the denominator is held positive and the
/// numerator non-negative: `2d + 1` points per coordinate (at least 9),
/// ends included, so that a polynomial of degree `d` cannot turn between
/// two of its points more than once.
fn grid_size(degree: usize) -> usize {
    (2 * degree + 1).max(9)
}

/// Solves the programme of `basis` for `rows`, taking no function held by
/// less than `min_margin` ([`SINGLE_MARGIN`] or [`DOUBLE_MARGIN`]).
pub fn solve(basis: &Basis, rows: &[Row], min_margin: f64) -> Result<Outcome> {
    let mut c = Constraints::new(basis, rows);
    let samples = c.samples;
    let sample_of = |row: usize| (row < samples).then_some(row / 2);
    let steps = STEPS_PER_UNKNOWN * c.n;
    match active_set::solve(&mut c, steps, 1.0 / min_margin) {
        active_set::Outcome::Optimum(o) => {
            let norm = o.x.iter().map(|v| v * v).sum::<f64>().sqrt();
            let (p, q) = o.x.split_at(c.k);
            Ok(Outcome::Solved {
                p: p.to_vec(),
                q: q.to_vec(),
                margin: 1.0 / norm,
            })
        }
        active_set::Outcome::Empty(e) => Ok(Outcome::Infeasible {
            worst: sample_of(e.row)
                .or_else(|| e.against.iter().find_map(|&r| sample_of(r)))
                .unwrap_or(0),
        }),
        active_set::Outcome::Beyond { row, .. } => Ok(Outcome::Infeasible {
            worst: sample_of(row).unwrap_or(0),
        }),
        active_set::Outcome::Stalled { steps } => bail!(
            "the programme of {} terms (degree {}) found no optimum in {steps} steps",
            basis.len(),
            basis.degree
        ),
    }
}

/// The least margin of a function that holds in single precision. Renderers and shaders
/// evaluate in single precision, which rounds each term by 6e-8 of the
/// coefficient scale: a function held by less holds its segments only in
/// double. Measured (`tests/tests/brdf_export.rs`, glass beads at ±0.5
/// sr⁻¹): 7 terms held by 1e-7 gave 4.5e-3 of the peak between the f32
/// shader and the function; the 10 terms held by more than 1e-6 give
/// under 1e-5. At this bar the bench's counts stay ALTA's (`fit-bench
/// rational`), whose margins are 5e-6 and above; at 1e-5 two lobes need
/// 184 coefficients to ALTA's 126.
pub const SINGLE_MARGIN: f64 = 1e-6;

/// The least margin of a function that holds in double precision: the
/// rounding allowance of a row ([`ROUNDING`], [`RELATIVE_ROUNDING`] times
/// `‖x‖ ≤ 1/margin`) stays under 1e-4 of the unit margin. ALTA's fitter
/// takes any margin. It binds on measured tapes: ALTA's yellow tape at
/// ±0.5 is held by 462 coefficients at 1.8·10⁻¹⁰ (`fit::VALUE_UNIT`); in
/// values ten times larger the margins fall to this bar and 500 are
/// needed.
pub const DOUBLE_MARGIN: f64 = 1e-10;

/// Steps of the active-set method per unknown before it is taken as
/// cycling: rows enter and leave many times before the active set settles
/// (36 steps per unknown on the mimic tape's 126 coefficients, 84 on the
/// yellow tape's 462), and a cycle goes on forever.
const STEPS_PER_UNKNOWN: usize = 1000;

/// A row counts as violated below `−(ROUNDING + RELATIVE_ROUNDING·‖x‖)`:
/// its value is a sum of unit-order terms times coefficients, rounded to
/// about `1e-16·‖x‖`. Within `1/SINGLE_MARGIN` that is at most 1e-8 of the
/// unit margin, so a row within it still holds its segment strictly.
const ROUNDING: f64 = 1e-9;
const RELATIVE_ROUNDING: f64 = 1e-14;

/// Every row `a·x ≥ margin` of the programme, `‖a‖ = 1`: `margin = 1`
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
    /// Rows before this are the samples' (two per sample).
    samples: usize,
    /// The rows the last full scan found violated (`violated`).
    candidates: Vec<usize>,
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
            samples: 2 * rows.len(),
            candidates: Vec::new(),
            k,
            n: 2 * k,
        }
    }

    /// A point's terms (unit norm).
    fn terms_of(&self, point: usize) -> &[f64] {
        &self.terms[point * self.k..(point + 1) * self.k]
    }

    /// A point's terms against the numerator and the denominator.
    fn products(&self, point: usize, x: &[f64]) -> (f64, f64) {
        let t = self.terms_of(point);
        let (p, q) = x.split_at(self.k);
        (active_set::dot(t, p), active_set::dot(t, q))
    }

    /// Every row among `rows` (pairs of a point) violated beyond
    /// `tolerance`, with its slack.
    fn violations(&self, rows: std::ops::Range<usize>, x: &[f64], tolerance: f64) -> Vec<(f64, usize)> {
        let mut out = Vec::new();
        for pair in rows.step_by(2) {
            let (tp, tq) = self.products(self.rows[pair].0, x);
            for i in [pair, pair + 1] {
                let (_, [a, b], margin) = self.rows[i];
                let slack = a * tp + b * tq - margin;
                if slack < -tolerance {
                    out.push((slack, i));
                }
            }
        }
        out
    }
}

impl HalfSpaces for Constraints {
    fn dimension(&self) -> usize {
        self.n
    }

    fn normal(&self, i: usize, out: &mut [f64]) {
        let (point, [a, b], _) = self.rows[i];
        let t = self.terms_of(point);
        let (p, q) = out.split_at_mut(self.k);
        p.iter_mut().zip(t).for_each(|(o, t)| *o = a * t);
        q.iter_mut().zip(t).for_each(|(o, t)| *o = b * t);
    }

    fn slack(&self, i: usize, x: &[f64]) -> f64 {
        let (point, [a, b], margin) = self.rows[i];
        let (tp, tq) = self.products(point, x);
        a * tp + b * tq - margin
    }

    /// Partial pricing: the most violated of the rows a full scan last
    /// found violated (the worst `n` of them), and a full scan, the
    /// samples' rows before the grid's, only when none of those still is.
    /// Any violated row is a valid next step of the method; a scan costs
    /// `rows × n` where a step of the method costs `n²`.
    fn violated(&mut self, x: &[f64]) -> Option<usize> {
        let tolerance = ROUNDING + RELATIVE_ROUNDING * x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let worst_candidate = self
            .candidates
            .iter()
            .map(|&i| (self.slack(i, x), i))
            .filter(|(s, _)| *s < -tolerance)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, i)) = worst_candidate {
            return Some(i);
        }
        let mut found = self.violations(0..self.samples, x, tolerance);
        if found.is_empty() {
            found = self.violations(self.samples..self.rows.len(), x, tolerance);
        }
        if found.len() > self.n {
            found.select_nth_unstable_by(self.n, |a, b| a.0.total_cmp(&b.0));
            found.truncate(self.n);
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.candidates = found.iter().map(|&(_, i)| i).collect();
        found.first().map(|&(_, i)| i)
    }
}
