//! The least-norm point of a set of half-spaces, `min ½‖x‖²` subject to
//! `aᵢ·x ≥ bᵢ`, by Goldfarb & Idnani's dual active-set method (1983, "A
//! numerically stable dual method for solving strictly convex quadratic
//! programs"), the method of QuadProg++ that ALTA's rational fitter calls.
//!
//! Written here rather than taken from a crate: the one pure-Rust port
//! (`quadprog`) is GPL-2.0, which this MIT/Apache product cannot link, and
//! it takes the constraint matrix dense and whole, where a rational fit's
//! rows are pairs over a point's terms (`qp::Constraints`) and are best
//! scanned in an order the caller chooses (the samples before the
//! positivity grid). With the identity as Hessian the method keeps an
//! orthogonal `J` and an upper-triangular `R` with `N = J₁R` for the active
//! normals `N`; each step adds the most violated half-space or drops one
//! whose multiplier would turn negative, with Givens rotations, so a
//! programme of `n` unknowns costs `O(n²)` per step plus the caller's scan.
//!
//! Starting from `x = 0`, the unconstrained optimum, every iterate is the
//! optimum of the half-spaces taken so far; when none is violated it is
//! the optimum of all. A violated half-space that no step can satisfy
//! proves the whole set empty.

/// The half-spaces, as the method sees them.
pub trait HalfSpaces {
    /// The unknowns' count.
    fn dimension(&self) -> usize;
    /// Row `i`'s normal, into `out`.
    fn normal(&self, i: usize, out: &mut [f64]);
    /// `aᵢ·x − bᵢ`.
    fn slack(&self, i: usize, x: &[f64]) -> f64;
    /// The half-space to take next at `x`: one violated beyond rounding
    /// (the most violated, or by any rule the caller prefers), or `None`
    /// when `x` is in every one.
    fn violated(&mut self, x: &[f64]) -> Option<usize>;
}

/// The optimum: the point and the half-spaces it lies on.
#[derive(Debug, Clone, PartialEq)]
pub struct Optimum {
    pub x: Vec<f64>,
    pub active: Vec<usize>,
    /// Steps taken (additions and drops).
    pub steps: usize,
}

/// No point is in every half-space: `row` could not be satisfied together
/// with `against`, the active half-spaces whose normals oppose its own
/// (the certificate: `a_row` is a non-positive combination of theirs).
#[derive(Debug, Clone, PartialEq)]
pub struct Empty {
    pub row: usize,
    pub against: Vec<usize>,
    pub steps: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Optimum(Optimum),
    Empty(Empty),
    /// The iterate's norm passed the bound while taking `row`: the
    /// least-norm point, if any, is farther (the norm only grows from step
    /// to step, the dual objective rising).
    Beyond {
        row: usize,
        steps: usize,
    },
    /// The step limit was reached (cycling under rounding).
    Stalled {
        steps: usize,
    },
}

/// `a·b`, by nalgebra's kernel: eight sums at once, where an iterator's
/// `sum` adds one term after another and waits on each (a dot product of
/// the `n` columns of `J` is most of a step).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    nalgebra::DVectorView::from_slice(&a[..n], n).dot(&nalgebra::DVectorView::from_slice(&b[..n], n))
}

/// `√(a² + b²)` of a rotation's pair: unit-order values (rows of unit
/// norm), where `hypot`'s guard against overflow cost 5 % of a solve.
fn norm2(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// Below this, a step direction is taken as zero (normals are of unit
/// order: `qp`'s rows have unit norm).
const TINY: f64 = 1e-13;

/// Solves `min ½‖x‖²` over `set`, in at most `max_steps` steps, unless the
/// optimum's norm is beyond `max_norm`.
pub fn solve(set: &mut impl HalfSpaces, max_steps: usize, max_norm: f64) -> Outcome {
    let n = set.dimension();
    let mut s = State::new(n);
    let mut np = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut r = vec![0.0; n];
    let mut steps = 0;
    while let Some(p) = set.violated(&s.x) {
        set.normal(p, &mut np);
        // The multiplier of `p`, grown as the step proceeds.
        let mut up = 0.0;
        loop {
            steps += 1;
            if steps > max_steps {
                return Outcome::Stalled { steps };
            }
            let q = s.active.len();
            s.direction(&np, &mut d, &mut z, &mut r);
            // The largest dual step keeping every multiplier ≥ 0.
            let mut partial = (f64::INFINITY, usize::MAX);
            for (j, (&rj, &uj)) in r[..q].iter().zip(&s.u).enumerate() {
                if rj > 0.0 && uj / rj < partial.0 {
                    partial = (uj / rj, j);
                }
            }
            // The primal step that satisfies `p`.
            let zn = dot(&z, &np);
            let full = if zn > TINY * TINY {
                -set.slack(p, &s.x) / zn
            } else {
                f64::INFINITY
            };
            if full.is_infinite() && partial.0.is_infinite() {
                let against = (0..q).filter(|&j| r[j] < 0.0).map(|j| s.active[j]).collect();
                return Outcome::Empty(Empty { row: p, against, steps });
            }
            let t = full.min(partial.0);
            if full.is_finite() {
                s.x.iter_mut().zip(&z).for_each(|(x, z)| *x += t * z);
                if s.x.iter().map(|v| v * v).sum::<f64>() > max_norm * max_norm {
                    return Outcome::Beyond { row: p, steps };
                }
            }
            s.u.iter_mut().zip(&r).for_each(|(u, r)| *u -= t * r);
            up += t;
            if full <= partial.0 {
                s.add(p, up, &mut d);
                break;
            }
            s.drop(partial.1);
        }
    }
    Outcome::Optimum(Optimum {
        x: s.x,
        active: s.active,
        steps,
    })
}

/// The method's factors: `J` orthogonal (column-major, `n × n`), `R` upper
/// triangular (column-major, its first `q` columns used), the active rows
/// and their multipliers, and the iterate.
struct State {
    n: usize,
    j: Vec<f64>,
    r: Vec<f64>,
    active: Vec<usize>,
    u: Vec<f64>,
    x: Vec<f64>,
}

impl State {
    fn new(n: usize) -> State {
        let mut j = vec![0.0; n * n];
        for i in 0..n {
            j[i * n + i] = 1.0;
        }
        State {
            n,
            j,
            r: vec![0.0; n * n],
            active: Vec::new(),
            u: Vec::new(),
            x: vec![0.0; n],
        }
    }

    fn col(&self, c: usize) -> &[f64] {
        &self.j[c * self.n..(c + 1) * self.n]
    }

    /// `d = Jᵀ·np`; the primal direction `z = J₂·d₂` (np projected off the
    /// active normals) and the dual one `r = R⁻¹·d₁`.
    fn direction(&self, np: &[f64], d: &mut [f64], z: &mut [f64], r: &mut [f64]) {
        let (n, q) = (self.n, self.active.len());
        for (c, dc) in d.iter_mut().enumerate() {
            *dc = dot(self.col(c), np);
        }
        z.iter_mut().for_each(|v| *v = 0.0);
        for (c, &dc) in d.iter().enumerate().skip(q) {
            z.iter_mut().zip(self.col(c)).for_each(|(z, j)| *z += dc * j);
        }
        // Back-substitution by columns: `R`'s column `k` is contiguous,
        // where its rows are `n` apart (the row form was a tenth of a
        // step, measured).
        r[..q].copy_from_slice(&d[..q]);
        for k in (0..q).rev() {
            let rk = r[k] / self.r[k * n + k];
            r[k] = rk;
            r[..k].iter_mut().zip(&self.r[k * n..k * n + k]).for_each(|(ri, c)| *ri -= c * rk);
        }
    }

    /// Takes row `p` (with `d = Jᵀ·a_p`) into the active set: rotations
    /// fold `d`'s tail into its entry `q`, which closes `R`'s new column.
    fn add(&mut self, p: usize, up: f64, d: &mut [f64]) {
        let (n, q) = (self.n, self.active.len());
        for c in (q + 1..n).rev() {
            if d[c] == 0.0 {
                continue;
            }
            let h = norm2(d[c - 1], d[c]);
            let (cs, sn) = (d[c - 1] / h, d[c] / h);
            d[c - 1] = h;
            d[c] = 0.0;
            self.rotate_columns(c - 1, cs, sn);
        }
        self.r[q * n..q * n + q + 1].copy_from_slice(&d[..=q]);
        self.active.push(p);
        self.u.push(up);
    }

    /// Drops the active row at position `k`: `R` loses that column and the
    /// rotations that make it triangular again turn `J` alike.
    fn drop(&mut self, k: usize) {
        let (n, q) = (self.n, self.active.len());
        self.active.remove(k);
        self.u.remove(k);
        self.r.copy_within((k + 1) * n..q * n, k * n);
        self.r[(q - 1) * n..q * n].iter_mut().for_each(|v| *v = 0.0);
        for c in k..q - 1 {
            let (a, b) = (self.r[c * n + c], self.r[c * n + c + 1]);
            if b == 0.0 {
                continue;
            }
            let h = norm2(a, b);
            let (cs, sn) = (a / h, b / h);
            for col in c..q - 1 {
                let (x, y) = (self.r[col * n + c], self.r[col * n + c + 1]);
                self.r[col * n + c] = cs * x + sn * y;
                self.r[col * n + c + 1] = -sn * x + cs * y;
            }
            self.r[c * n + c + 1] = 0.0;
            self.rotate_columns(c, cs, sn);
        }
    }

    /// `J`'s columns `c` and `c + 1` ← `(cs·J_c + sn·J_{c+1}, −sn·J_c + cs·J_{c+1})`.
    fn rotate_columns(&mut self, c: usize, cs: f64, sn: f64) {
        let n = self.n;
        let (left, right) = self.j.split_at_mut((c + 1) * n);
        for (a, b) in left[c * n..].iter_mut().zip(&mut right[..n]) {
            let (x, y) = (*a, *b);
            *a = cs * x + sn * y;
            *b = -sn * x + cs * y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense rows, the most violated taken first.
    struct Dense {
        n: usize,
        rows: Vec<(Vec<f64>, f64)>,
    }

    impl HalfSpaces for Dense {
        fn dimension(&self) -> usize {
            self.n
        }
        fn normal(&self, i: usize, out: &mut [f64]) {
            out.copy_from_slice(&self.rows[i].0);
        }
        fn slack(&self, i: usize, x: &[f64]) -> f64 {
            self.rows[i].0.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() - self.rows[i].1
        }
        fn violated(&mut self, x: &[f64]) -> Option<usize> {
            (0..self.rows.len())
                .map(|i| (self.slack(i, x), i))
                .filter(|(s, _)| *s < -1e-12)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, i)| i)
        }
    }

    fn optimum(set: &mut Dense) -> Optimum {
        match solve(set, 10_000, 1e9) {
            Outcome::Optimum(o) => o,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_single_half_space_projects_the_origin() {
        // x + 2y ≥ 1: the nearest point is (1, 2)/5.
        let mut set = Dense {
            n: 2,
            rows: vec![(vec![1.0, 2.0], 1.0)],
        };
        let o = optimum(&mut set);
        assert!((o.x[0] - 0.2).abs() < 1e-15 && (o.x[1] - 0.4).abs() < 1e-15, "{:?}", o.x);
        assert_eq!(o.active, vec![0]);
    }

    #[test]
    fn an_empty_set_is_proven_so() {
        // x ≥ 1 and −x ≥ 0 cannot both hold.
        let mut set = Dense {
            n: 3,
            rows: vec![(vec![1.0, 0.0, 0.0], 1.0), (vec![-1.0, 0.0, 0.0], 0.0), (vec![0.0, 1.0, 0.0], -5.0)],
        };
        match solve(&mut set, 100, 1e9) {
            Outcome::Empty(e) => {
                assert_eq!(e.row, 1);
                assert_eq!(e.against, vec![0]);
            }
            other => panic!("{other:?}"),
        }
        // x ≥ 1 beyond a norm of ½.
        let mut set = Dense {
            n: 1,
            rows: vec![(vec![1.0], 1.0)],
        };
        assert_eq!(solve(&mut set, 100, 0.5), Outcome::Beyond { row: 0, steps: 1 });
    }

    #[test]
    fn random_programmes_meet_the_optimality_conditions() {
        // KKT: x feasible, x = Σ uᵢ aᵢ over the active rows with uᵢ ≥ 0, and
        // active rows tight; checked against the rows and solved by least
        // squares for u, on programmes of 12 unknowns and 60 rows. Steps
        // beyond the active rows are drops (each drop is a step and undoes
        // an addition): some programmes must have taken them.
        let mut dropped = 0;
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..50 {
            let n = 12;
            // Every row holds at a random point, by a random room: a
            // programme that is never empty.
            let inside: Vec<f64> = (0..n).map(|_| 2.0 * uniform()).collect();
            let rows: Vec<(Vec<f64>, f64)> = (0..60)
                .map(|_| {
                    let a: Vec<f64> = (0..n).map(|_| uniform()).collect();
                    let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
                    let a: Vec<f64> = a.iter().map(|v| v / norm).collect();
                    let at: f64 = a.iter().zip(&inside).map(|(a, x)| a * x).sum();
                    (a, at - uniform().abs())
                })
                .collect();
            let mut set = Dense { n, rows };
            let o = optimum(&mut set);
            dropped += (o.steps - o.active.len()) / 2;
            for i in 0..set.rows.len() {
                assert!(set.slack(i, &o.x) > -1e-10);
            }
            for &i in &o.active {
                assert!(set.slack(i, &o.x).abs() < 1e-10);
            }
            // x in the cone of the active normals: solve the normal equations.
            let k = o.active.len();
            let g: Vec<Vec<f64>> = o
                .active
                .iter()
                .map(|&a| {
                    o.active
                        .iter()
                        .map(|&b| set.rows[a].0.iter().zip(&set.rows[b].0).map(|(x, y)| x * y).sum())
                        .collect()
                })
                .collect();
            let rhs: Vec<f64> = o
                .active
                .iter()
                .map(|&a| set.rows[a].0.iter().zip(&o.x).map(|(x, y)| x * y).sum())
                .collect();
            let u = nalgebra::DMatrix::from_fn(k, k, |i, j| g[i][j])
                .lu()
                .solve(&nalgebra::DVector::from_vec(rhs))
                .expect("active normals independent");
            assert!(u.iter().all(|&v| v >= -1e-9), "{u}");
            let mut back = vec![0.0; n];
            for (w, &a) in u.iter().zip(&o.active) {
                back.iter_mut().zip(&set.rows[a].0).for_each(|(b, r)| *b += w * r);
            }
            assert!(back.iter().zip(&o.x).all(|(b, x)| (b - x).abs() < 1e-9));
        }
        assert!(dropped > 0, "no programme dropped a row: the drop path is untested");
    }
}
