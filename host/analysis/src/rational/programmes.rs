//! The programmes the search over counts walks (`search`), in both
//! coordinate systems: the spec's warped retro plane and ALTA's unwarped
//! view plane (`basis::Coordinates`), neither of which needs the fewest
//! terms on every material. At each count the one that held last is
//! tried first. Holding in either is monotone in the count as each is, so
//! the search stays sound, and a plane is not tried again at a count
//! below one it failed at. A failing programme costs a fraction of a
//! holding one (on the mimic tape 0.01–0.03 s, against 0.055 s).

use super::basis::{Basis, Coordinates, Domain};
use super::function::Rational;
use super::qp::{self, Outcome, Row};
use super::search::fewest;
use super::segments::{sample_text, Segments};
use crate::fit::data::Observation;
use crate::fit::Dataset;
use crate::moments::plane::Parametrization;
use anyhow::{bail, Result};
use serde::Serialize;
use std::time::Instant;

/// How a function holds a data set's segments.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Held {
    /// Segments the function passes through (within `VIOLATION_TOLERANCE`).
    pub held: usize,
    pub of: usize,
    /// Samples where the function is not a number (`Q ≤ 0`, a pole).
    pub undefined: usize,
    /// The largest distance outside a segment where it is a number, over
    /// the segment's width.
    pub worst: f64,
    /// A sample where it is not a number, else that of the worst miss.
    #[serde(skip)]
    pub at: usize,
}

impl Held {
    pub fn of(f: &Rational, data: &Dataset, segs: &Segments) -> Held {
        let mut h = Held {
            held: 0,
            of: segs.segments.len(),
            undefined: 0,
            worst: 0.0,
            at: 0,
        };
        for (i, (v, s)) in f.values(data).iter().zip(&segs.segments).enumerate() {
            if v.is_nan() {
                h.undefined += 1;
                h.at = i;
                continue;
            }
            let out = (s.lo - v).max(v - s.hi).max(0.0) / (s.hi - s.lo);
            if out <= VIOLATION_TOLERANCE {
                h.held += 1;
            }
            if out > h.worst {
                h.worst = out;
                if h.undefined == 0 {
                    h.at = i;
                }
            }
        }
        h
    }

    /// Whether every segment holds.
    pub fn all(&self) -> bool {
        self.held == self.of
    }
}

/// One count of terms tried, in one coordinate system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Attempt {
    pub coordinates: Coordinates,
    /// The total degree of its last term.
    pub degree: usize,
    /// Numerator and denominator together (twice the terms).
    pub coefficients: usize,
    pub feasible: bool,
    /// The programme's margin (values over the largest segment end, rows
    /// and coefficients of unit norm); `None` where no function held.
    pub margin: Option<f64>,
    /// Whether the margin asked for was single precision's (else double's).
    pub single_precision: bool,
    pub seconds: f64,
}

/// A function that holds every segment: its worst miss (within rounding)
/// and its programme's margin.
pub(super) type Found = (Rational, f64, f64);

/// Misses beyond this (relative to a segment's width) reject a count's
/// function: the margins put a solution strictly inside.
pub(super) const VIOLATION_TOLERANCE: f64 = 1e-9;

/// One coordinate system's programmes: its box and its rows.
pub(super) struct Plane {
    coordinates: Coordinates,
    domain: Domain,
    rows: Vec<Row>,
}

impl Plane {
    /// The rows of `segs` in `coordinates`, each segment over its cosine
    /// factor (`factors`) and over `scale`.
    fn new(coordinates: Coordinates, obs: &[Observation], segs: &Segments, factors: &[f64], scale: f64) -> Plane {
        let points: Vec<[f64; 3]> = obs.iter().map(|o| coordinates.of(&o.directions())).collect();
        let domain = Domain::around(&points);
        let rows = points
            .iter()
            .zip(&segs.segments)
            .zip(factors)
            .map(|((p, s), c)| Row {
                u: domain.unit(*p),
                lo: s.lo / c / scale,
                hi: s.hi / c / scale,
            })
            .collect();
        Plane { coordinates, domain, rows }
    }
}

/// Whether `o` is grazing: its cosine factor cosθi·cosθo is zero (at most
/// 1e-9) or undefined, so that a fit with the factor cannot divide by it.
pub fn grazing(o: &Observation) -> bool {
    let d = o.directions();
    let c = d.cos_i() * d.cos_o();
    c.is_nan() || c <= 1e-9
}

/// Each sample's cosine factor (1 without it), refusing a grazing one.
pub(super) fn cosine_factors(obs: &[Observation], cosine: bool) -> Result<Vec<f64>> {
    obs.iter()
        .enumerate()
        .map(|(i, o)| match cosine {
            false => Ok(1.0),
            true if grazing(o) => bail!(
                "{}: grazing, where the cosine factor cosθi·cosθo is zero (fit without it: --no-cosine)",
                sample_text(i, o)
            ),
            true => {
                let d = o.directions();
                Ok(d.cos_i() * d.cos_o())
            }
        })
        .collect()
}

/// Every programme of a fit: its planes, what was tried, and what is
/// known of each plane.
pub(super) struct Programmes<'a> {
    data: &'a Dataset,
    segs: &'a Segments,
    /// The cosine factor's presence.
    cosine: bool,
    /// The values' unit (`fit::VALUE_UNIT` of the largest segment end).
    scale: f64,
    planes: [Plane; 2],
    /// The plane that held last, tried first.
    lead: usize,
    /// Per plane, the most terms known not to hold in double: no fewer
    /// do either.
    failed: [usize; 2],
    pub attempts: Vec<Attempt>,
}

impl<'a> Programmes<'a> {
    /// The programmes of `segs` over `data` in the retro plane `retro` and
    /// ALTA's view plane, with the cosine factor or not (`cosine`: each
    /// sample's in `factors`).
    pub fn new(
        data: &'a Dataset,
        segs: &'a Segments,
        (retro, cosine): (Parametrization, bool),
        factors: &[f64],
        scale: f64,
    ) -> Programmes<'a> {
        let obs = &data.observations;
        let planes = [Coordinates::retro(retro), Coordinates::ViewProjected].map(|c| Plane::new(c, obs, segs, factors, scale));
        Programmes {
            data,
            segs,
            cosine,
            scale,
            planes,
            lead: 0,
            failed: [0; 2],
            attempts: Vec::new(),
        }
    }

    /// The fewest terms up to `top` that hold in double precision; then,
    /// unless their margin already holds in single precision (as shaders
    /// and renderers evaluate), the fewest that do, up to twice as many
    /// terms: beyond, the single-precision programmes cost more than the
    /// whole search (a measured tape's 680 terms: minutes), for a function
    /// of more than twice the coefficients. Else the double one, said so
    /// (`false`). `Err`: the sample most in conflict at `top`.
    pub fn search(&mut self, top: usize, trying: &mut impl FnMut(usize)) -> Result<std::result::Result<(Found, bool), usize>> {
        let double = match fewest(1, 1, top, |n| {
            trying(2 * n);
            self.attempt(n, qp::DOUBLE_MARGIN)
        })? {
            Ok(found) => found,
            Err(worst) => return Ok(Err(worst)),
        };
        let terms = double.0.numerator.len();
        let most = (2 * terms).min(top);
        if double.2 >= qp::SINGLE_MARGIN {
            return Ok(Ok((double, true)));
        }
        if most == terms {
            return Ok(Ok((double, false)));
        }
        let single = fewest(terms + 1, most, most, |n| {
            trying(2 * n);
            self.attempt(n, qp::SINGLE_MARGIN)
        })?;
        Ok(Ok(match single {
            Ok(found) => (found, true),
            Err(_) => (double, false),
        }))
    }

    /// The function of `terms` terms if it holds every segment in either
    /// plane (checked on the function itself, not taken from the solver),
    /// else the sample most in conflict in the first plane tried. Single
    /// precision is sought in the plane that held in double only.
    fn attempt(&mut self, terms: usize, min_margin: f64) -> Result<std::result::Result<Found, usize>> {
        let basis = Basis::with_terms(terms);
        let single = min_margin >= qp::SINGLE_MARGIN;
        let mut conflict = None;
        for k in [self.lead, 1 - self.lead].into_iter().take(if single { 1 } else { 2 }) {
            if terms <= self.failed[k] {
                continue;
            }
            match self.solve(k, &basis, min_margin)? {
                Ok(found) => {
                    self.lead = k;
                    return Ok(Ok(found));
                }
                Err(worst) => {
                    if !single {
                        self.failed[k] = terms;
                    }
                    conflict.get_or_insert(worst);
                }
            }
        }
        Ok(Err(conflict.unwrap_or(0)))
    }

    /// Plane `k`'s programme of `basis`, its function checked on every
    /// segment, and the attempt recorded (in single precision when
    /// `min_margin` is single precision's).
    fn solve(&mut self, k: usize, basis: &Basis, min_margin: f64) -> Result<std::result::Result<Found, usize>> {
        let plane = &self.planes[k];
        let t = Instant::now();
        let (held, margin) = match qp::solve(basis, &plane.rows, min_margin)? {
            Outcome::Solved { p, q, margin } => {
                let f = Rational {
                    coordinates: plane.coordinates,
                    degree: basis.degree,
                    cosine: self.cosine,
                    quantity: self.data.units,
                    domain: plane.domain,
                    order: basis.order,
                    numerator: p.iter().map(|c| c * self.scale).collect(),
                    denominator: q,
                };
                let h = Held::of(&f, self.data, self.segs);
                (if h.all() { Ok((f, h.worst, margin)) } else { Err(h.at) }, Some(margin))
            }
            Outcome::Infeasible { worst } => (Err(worst), None),
        };
        self.attempts.push(Attempt {
            coordinates: plane.coordinates,
            degree: basis.degree,
            coefficients: 2 * basis.len(),
            feasible: held.is_ok(),
            margin,
            single_precision: min_margin >= qp::SINGLE_MARGIN,
            seconds: t.elapsed().as_secs_f64(),
        });
        Ok(held)
    }
}
