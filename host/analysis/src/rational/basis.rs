//! The polynomial basis of a rational function: products of Legendre
//! polynomials in three coordinates of a geometry, of total degree at most
//! `d`, each coordinate mapped onto [−1, 1] over the data's range.
//!
//! Legendre polynomials rather than monomials (ALTA's
//! `rational_function_legendre`, which Belcour et al. 2014 fitted with): on
//! [−1, 1] they are orthogonal, so the constraint matrix of a degree-8
//! basis stays well conditioned where monomials' columns become nearly
//! parallel. Terms are ordered by total degree, so a basis of `n` terms
//! is a prefix of that of `n + 1`: a solution with fewer terms is one with
//! every larger count (zeros appended), which is what makes bisecting on
//! the number of terms sound for the segments (`search`).

use crate::moments::plane::Parametrization;
use gonio_brdf::Directions;
use serde::{Deserialize, Serialize};

/// The coordinates a rational function is a function of: the incidence θi
/// (degrees) and two of the view.
///
/// `Back` and `LightView` take the view's place `(x, y)` in a retro plane
/// (`moments::plane`), with the retro direction at the origin and its
/// radius, the angle θ from the retro direction in degrees, taken to its
/// square root: `(x, y)·θ^(−1/2)`. The warp is for the retro lobe. A lobe
/// a few degrees wide fills 1 % of a 180° span and no polynomial of degree
/// 8 on it follows the lobe; √θ gives its core a tenth of the span. A lobe
/// that is a smooth function of θ² stays one of `(x′² + y′²)²` after the
/// warp. Measured on a simulated glass-bead scan (1 506 samples, retro
/// rings to 4.75°, ±0.5 sr⁻¹): no degree up to 8 held every segment in
/// `(x, y)`; degree 6 does in `(x′, y′)`.
///
/// `ViewProjected` is ALTA's `ISOTROPIC_TL_TV_PROJ_DPHI`, in degrees:
/// `(θo cosΔφ, θo |sinΔφ|)`, unwarped. A lobe as wide as the mimic tape's
/// (`tests/data/tape-frcos.dat`, σ 4° and 6°) needs fewer terms there:
/// 126 coefficients at ±0.5, as ALTA, where the warped light-view plane
/// needs 258; on ALTA's yellow tape the warped plane needs 462 where
/// ALTA needs 1 242. The fit tries both (`fit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Coordinates {
    Back,
    LightView,
    ViewProjected,
}

impl Coordinates {
    /// The warped retro plane of `p`.
    pub fn retro(p: Parametrization) -> Coordinates {
        match p {
            Parametrization::Back => Coordinates::Back,
            Parametrization::LightView => Coordinates::LightView,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Coordinates::Back => "back",
            Coordinates::LightView => "light-view",
            Coordinates::ViewProjected => "view-projected",
        }
    }

    /// The coordinates of `d`, before the box maps them onto [−1, 1]³.
    pub fn of(self, d: &Directions) -> [f64; 3] {
        let (theta_i, theta_o, dphi) = d.angles();
        let [x, y] = match self {
            Coordinates::Back => Parametrization::Back.coordinates(d),
            Coordinates::LightView => Parametrization::LightView.coordinates(d),
            Coordinates::ViewProjected => {
                let t = theta_o.to_degrees();
                return [theta_i.to_degrees(), t * dphi.cos(), t * dphi.sin().abs()];
            }
        };
        let r = x.hypot(y);
        let k = if r > 0.0 { r.sqrt() / r } else { 0.0 };
        [theta_i.to_degrees(), k * x, k * y]
    }
}

/// The box the coordinates are mapped from: the data's range per coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Domain {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl Domain {
    /// The smallest box holding every point; a coordinate that does not
    /// vary (one incidence) gets ±1 about its value, as ALTA does, so that
    /// the map stays defined.
    pub fn around(points: &[[f64; 3]]) -> Domain {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        for k in 0..3 {
            // Rounding, not range: Δφ = 180° puts y at 1e-15, not 0.
            if hi[k] - lo[k] <= 1e-9 * lo[k].abs().max(hi[k].abs()).max(1.0) {
                lo[k] -= 1.0;
                hi[k] += 1.0;
            }
        }
        Domain { lo, hi }
    }

    /// `c` mapped onto [−1, 1]³, clamped to the box: outside its data a
    /// polynomial grows without bound, so a rational function holds the
    /// value at the nearest edge of what it was fitted to.
    pub fn unit(&self, c: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| (2.0 * (c[k] - self.lo[k]) / (self.hi[k] - self.lo[k]) - 1.0).clamp(-1.0, 1.0))
    }
}

/// The order of the terms within one total degree, which a fit file's
/// coefficients are listed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TermOrder {
    /// ALTA's (`rational_function_1d::index2degree`): the third
    /// coordinate's degree rising slowest, then the second's, so that
    /// within a degree the terms in θi and x′ alone come before any in y′.
    /// A count between whole degrees then spends its terms on the
    /// coordinates the lobes vary most in: measured by `fit-bench
    /// rational`, 50 coefficients where the order below needs 62 (glass
    /// beads), 126 where it needs 156 (two lobes), as ALTA.
    Alta,
    /// The first coordinate's degree falling, then the second's: what
    /// files written before the ALTA order was adopted hold.
    FirstFalling,
}

/// The first terms in graded order: exponent triples by total degree, in
/// `order` within one. `degree` is the highest total degree among them.
#[derive(Debug, Clone, PartialEq)]
pub struct Basis {
    pub degree: usize,
    /// The order its terms are in (what a fitted function records).
    pub order: TermOrder,
    terms: Vec<[usize; 3]>,
}

impl Basis {
    /// Every term of total degree at most `degree`.
    pub fn new(degree: usize) -> Basis {
        Basis::with_terms(Self::size(degree))
    }

    /// The first `count` terms (at least one) in ALTA's order: a basis
    /// between two whole degrees, as ALTA's counts are, so that the fit can
    /// stop at the fewest coefficients rather than at the next whole
    /// degree.
    pub fn with_terms(count: usize) -> Basis {
        Basis::in_order(count, TermOrder::Alta)
    }

    /// The first `count` terms in `order`.
    pub fn in_order(count: usize, order: TermOrder) -> Basis {
        let degree = Self::degree_of(count);
        let mut terms = Vec::with_capacity(Self::size(degree));
        for total in 0..=degree {
            match order {
                TermOrder::Alta => {
                    for c in 0..=total {
                        terms.extend((0..=total - c).map(|b| [total - b - c, b, c]));
                    }
                }
                TermOrder::FirstFalling => {
                    for a in (0..=total).rev() {
                        terms.extend((0..=total - a).rev().map(|b| [a, b, total - a - b]));
                    }
                }
            }
        }
        terms.truncate(count.max(1));
        Basis { degree, order, terms }
    }

    /// The total degree of the last of the first `count` terms.
    pub fn degree_of(count: usize) -> usize {
        (0..).find(|&d| Self::size(d) >= count).unwrap_or(0)
    }

    /// The number of terms of degree at most `degree` in three variables:
    /// C(degree + 3, 3).
    pub const fn size(degree: usize) -> usize {
        (degree + 1) * (degree + 2) * (degree + 3) / 6
    }

    pub fn len(&self) -> usize {
        self.terms.len()
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Each term's Legendre degree in each coordinate, in the coefficients' order.
    pub fn terms(&self) -> &[[usize; 3]] {
        &self.terms
    }

    /// Every term at `u` (a point of [−1, 1]³), into `out` (`len()` values).
    pub fn values(&self, u: [f64; 3], out: &mut [f64]) {
        let mut table = vec![[0.0; 3]; self.degree + 1];
        for (k, &x) in u.iter().enumerate() {
            let mut prev = 1.0;
            let mut cur = x;
            table[0][k] = 1.0;
            if self.degree >= 1 {
                table[1][k] = x;
            }
            // (n + 1) P_{n+1} = (2n + 1) x P_n − n P_{n−1}
            for n in 1..self.degree {
                let next = ((2 * n + 1) as f64 * x * cur - n as f64 * prev) / (n + 1) as f64;
                prev = cur;
                cur = next;
                table[n + 1][k] = next;
            }
        }
        for (o, [a, b, c]) in out.iter_mut().zip(&self.terms) {
            *o = table[*a][0] * table[*b][1] * table[*c][2];
        }
    }

    /// `Σ coefficients[j] · term_j(u)`.
    pub fn eval(&self, coefficients: &[f64], u: [f64; 3]) -> f64 {
        let mut v = vec![0.0; self.len()];
        self.values(u, &mut v);
        v.iter().zip(coefficients).map(|(t, c)| t * c).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_nesting() {
        for d in 0..9 {
            let b = Basis::new(d);
            assert_eq!(b.len(), Basis::size(d));
            if d > 0 {
                let lower = Basis::new(d - 1);
                assert_eq!(&b.terms[..lower.len()], &lower.terms[..], "degree {d} must extend degree {}", d - 1);
            }
        }
        assert_eq!(Basis::size(3), 20);
        // Between whole degrees: the prefix, and the degree of its last term.
        let b = Basis::with_terms(25);
        assert_eq!((b.len(), b.degree), (25, 4));
        assert_eq!(&b.terms[..], &Basis::new(4).terms[..25]);
        assert_eq!(Basis::with_terms(20).degree, 3);
        assert_eq!(Basis::with_terms(1).degree, 0);
    }

    #[test]
    fn the_orders_within_a_degree() {
        // ALTA's `populate` for three coordinates, total degree 2: the
        // third's degree slowest, then the second's.
        let alta = Basis::in_order(10, TermOrder::Alta);
        assert_eq!(
            &alta.terms[4..],
            &[[2, 0, 0], [1, 1, 0], [0, 2, 0], [1, 0, 1], [0, 1, 1], [0, 0, 2]]
        );
        let old = Basis::in_order(10, TermOrder::FirstFalling);
        assert_eq!(&old.terms[4..], &[[2, 0, 0], [1, 1, 0], [1, 0, 1], [0, 2, 0], [0, 1, 1], [0, 0, 2]]);
        assert_eq!(&alta.terms[1..4], &[[1, 0, 0], [0, 1, 0], [0, 0, 1]]);
    }

    #[test]
    fn legendre_polynomials_by_their_closed_forms() {
        // P2 = (3x² − 1)/2, P3 = (5x³ − 3x)/2, P4 = (35x⁴ − 30x² + 3)/8.
        let b = Basis::new(4);
        let mut v = vec![0.0; b.len()];
        for x in [-1.0, -0.3, 0.0, 0.55, 1.0] {
            b.values([x, 0.2, -0.7], &mut v);
            let at = |e: [usize; 3]| v[b.terms.iter().position(|t| *t == e).unwrap()];
            assert!((at([2, 0, 0]) - (3.0 * x * x - 1.0) / 2.0).abs() < 1e-14);
            assert!((at([3, 0, 0]) - (5.0 * x * x * x - 3.0 * x) / 2.0).abs() < 1e-14);
            assert!((at([4, 0, 0]) - (35.0 * x.powi(4) - 30.0 * x * x + 3.0) / 8.0).abs() < 1e-14);
            assert!((at([1, 1, 1]) - x * 0.2 * -0.7).abs() < 1e-15);
            assert_eq!(at([0, 0, 0]), 1.0);
        }
    }

    #[test]
    fn the_domain_maps_its_corners_and_clamps_beyond() {
        let d = Domain::around(&[[10.0, -5.0, 0.0], [50.0, 5.0, 0.0]]);
        assert_eq!(d.lo[2], -1.0);
        assert_eq!(d.unit([10.0, -5.0, 0.0]), [-1.0, -1.0, 0.0]);
        assert_eq!(d.unit([50.0, 5.0, 0.0]), [1.0, 1.0, 0.0]);
        assert_eq!(d.unit([70.0, 0.0, 3.0]), [1.0, 0.0, 1.0]);
        // A principal-plane scan's y is rounding about 0: no dimension.
        let plane = Domain::around(&[[10.0, -5.0, 1e-15], [50.0, 5.0, -2e-15]]);
        assert!(plane.hi[2] - plane.lo[2] > 1.9, "{plane:?}");
    }
}
