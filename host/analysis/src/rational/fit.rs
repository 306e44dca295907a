//! The rational fit: the fewest terms (in graded order, numerator and
//! denominator alike) whose function passes through every segment, in
//! either coordinate system, up to the highest degree the spec and the
//! samples allow (`search`); each count is a programme per system (`qp`).

use super::basis::{Basis, Coordinates, Domain};
use super::function::Rational;
use super::qp::{self, Outcome, Row};
use super::search::fewest;
use super::segments::{sample_text, SegmentSource, Segments};
use crate::fit::data::Observation;
use crate::fit::densify::densify;
use crate::fit::{Dataset, Metrics};
use crate::moments::plane::Parametrization;
use anyhow::{bail, Result};
use serde::Serialize;
use std::time::Instant;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RationalSpec {
    pub parametrization: Parametrization,
    pub segments: SegmentSource,
    /// The highest total degree tried (numerator and denominator alike).
    pub max_degree: usize,
    /// `cosθi·cosθo·P/Q` (the paper's) or `P/Q` alone.
    pub cosine: bool,
    /// Fit a grid of this step (degrees) interpolated between the samples
    /// (`fit::densify`, the paper's §6.A.b) instead of the samples.
    pub densify: Option<f64>,
}

impl RationalSpec {
    /// Degree 8 is 330 coefficients, beyond the 48–70 Belcour et al. 2014
    /// needed for their tapes at ±0.5 sr⁻¹.
    pub const MAX_DEGREE: usize = 8;

    /// The highest degree a spec may ask for: 1 360 coefficients, beyond
    /// the 1 200 ALTA's fitter needs on a measured tape at ±0.5 sr⁻¹.
    pub const HIGHEST_DEGREE: usize = 14;
}

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

/// A fit to densified data: the grid, and how the function holds the
/// measured samples' own segments.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Densified {
    pub step_deg: f64,
    /// Grid points fitted.
    pub points: usize,
    pub measured: Held,
    /// What the grid could not cover (`fit::densify`).
    pub warnings: Vec<String>,
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

#[derive(Debug, Clone, PartialEq)]
pub struct RationalFit {
    pub function: Rational,
    pub segments: SegmentSource,
    /// Segments wholly below zero, moved up (`Segments::shifted`).
    pub shifted: usize,
    pub samples: usize,
    pub seconds: f64,
    /// Against the data, in the data's units.
    pub metrics: Metrics,
    /// The largest |measured − fitted|, in the data's units.
    pub linf: f64,
    /// The largest distance of a fitted value outside its segment, over the
    /// segment's width (0: every segment holds the function).
    pub worst_violation: f64,
    /// Why the most terms tried are what they are, when fewer than the
    /// spec's: more coefficients than samples interpolate anything.
    pub capped: Option<String>,
    /// Whether its margin holds every segment in single precision too
    /// (`qp::SINGLE_MARGIN`), as shaders and renderers evaluate it; else
    /// in double only: no function of up to twice its terms (or the
    /// highest count) held by that margin.
    pub single_precision: bool,
    pub attempts: Vec<Attempt>,
    /// Where the samples fitted were a grid between the measured ones.
    pub densified: Option<Densified>,
}

/// A function that holds every segment: its worst miss (within rounding)
/// and its programme's margin.
type Found = (Rational, f64, f64);

/// The unit of the programme's values, over the largest segment end. The
/// least-norm solution weighs the numerator's coefficients against the
/// denominator's by it, and with them how many steps the active-set
/// method takes: measured on the mimic tape's 126 coefficients, 21 746
/// steps in units of the largest value, 4 527 at a hundredth (0.32 s →
/// 0.07 s), 3 044 at a thousandth; on ALTA's yellow tape at 462
/// coefficients, the whole search 231 s → 67 s, the same count found.
/// The margins (`qp`) are rounding bounds of unit rows, so they hold at
/// any unit.
const VALUE_UNIT: f64 = 0.01;

/// Misses beyond this (relative to a segment's width) reject a count's
/// function: the margins put a solution strictly inside.
const VIOLATION_TOLERANCE: f64 = 1e-9;

/// Fits `data` in its own quantity (`f_r` or `f_r·cosθo`, as ALTA fits a
/// file's numbers): the segments are of that quantity.
pub fn fit(data: &Dataset, spec: &RationalSpec) -> Result<RationalFit> {
    fit_observed(data, spec, |_| {})
}

/// One coordinate system's programmes: its box and its rows.
struct Plane {
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

/// Each sample's cosine factor (1 without it), refusing a grazing one.
fn cosine_factors(obs: &[Observation], cosine: bool) -> Result<Vec<f64>> {
    obs.iter()
        .enumerate()
        .map(|(i, o)| {
            let d = o.directions();
            let c = if cosine { d.cos_i() * d.cos_o() } else { 1.0 };
            if c.is_nan() || c <= 1e-9 {
                bail!(
                    "{}: grazing, where the cosine factor cosθi·cosθo is zero (fit without it: --no-cosine)",
                    sample_text(i, o)
                );
            }
            Ok(c)
        })
        .collect()
}

/// As `fit`, calling `trying` with each count of coefficients before its
/// programme is solved (a progress bar's hook).
///
/// Two coordinate systems are tried at each count, the spec's warped retro
/// plane and ALTA's unwarped view plane (`Coordinates`): neither needs the
/// fewest terms on every material, and the one that held last is tried
/// first. Holding in either is monotone in the count as each is, so the
/// search over counts stays sound, and a plane is not tried again at a
/// count below one it failed at. A failing programme costs a fraction of
/// a holding one (on the mimic tape 0.01–0.03 s, against 0.055 s).
pub fn fit_observed(data: &Dataset, spec: &RationalSpec, mut trying: impl FnMut(usize)) -> Result<RationalFit> {
    let start = Instant::now();
    if spec.max_degree > RationalSpec::HIGHEST_DEGREE {
        bail!(
            "--max-degree {}: at most {} ({} coefficients); beyond it one programme takes hours",
            spec.max_degree,
            RationalSpec::HIGHEST_DEGREE,
            2 * Basis::size(RationalSpec::HIGHEST_DEGREE)
        );
    }
    let measured = data;
    let grid = spec.densify.map(|step| densify(measured, step)).transpose()?;
    let data = grid.as_ref().unwrap_or(measured);
    let obs = &data.observations;
    let segs = Segments::new(obs, spec.segments)?;
    let factors = cosine_factors(obs, spec.cosine)?;
    let m = obs.len();
    // The most terms: the spec's degree, or as many as the samples allow.
    let top = Basis::size(spec.max_degree).min(m / 2);
    if top == 0 {
        bail!("{m} sample(s): too few for a rational function (a constant over a constant has 2 coefficients)");
    }
    let capped = (top < Basis::size(spec.max_degree)).then(|| {
        format!(
            "degree {} has {} coefficients, more than the {m} samples: up to {} were tried",
            spec.max_degree,
            2 * Basis::size(spec.max_degree),
            2 * top
        )
    });
    // Values in units of a hundredth of the largest segment end: the same
    // for every data set, so that the programmes are alike between them.
    let scale = VALUE_UNIT * segs.segments.iter().zip(&factors).map(|(s, c)| s.hi / c).fold(0.0, f64::max);
    let planes: Vec<Plane> = [Coordinates::retro(spec.parametrization), Coordinates::ViewProjected]
        .into_iter()
        .map(|c| Plane::new(c, obs, &segs, &factors, scale))
        .collect();
    let mut attempts = Vec::new();
    let mut lead = 0;
    // Per plane, the most terms known not to hold in double: no fewer do
    // either, and are not tried again.
    let mut failed = [0; 2];
    // The function of `terms` terms if it holds every segment in either
    // plane (checked on the function itself, not taken from the solver),
    // else the sample most in conflict in the first plane tried.
    // Single precision is sought in the plane that held in double only.
    let mut attempt = |terms: usize, min_margin: f64| -> Result<std::result::Result<Found, usize>> {
        trying(2 * terms);
        let basis = Basis::with_terms(terms);
        let mut conflict = None;
        let single = min_margin >= qp::SINGLE_MARGIN;
        for k in [lead, 1 - lead].into_iter().take(if single { 1 } else { 2 }) {
            if terms <= failed[k] {
                continue;
            }
            let plane = &planes[k];
            let t = Instant::now();
            let (held, margin) = match qp::solve(&basis, &plane.rows, min_margin)? {
                Outcome::Solved { p, q, margin } => {
                    let f = Rational {
                        coordinates: plane.coordinates,
                        degree: basis.degree,
                        cosine: spec.cosine,
                        quantity: data.units,
                        domain: plane.domain,
                        order: basis.order,
                        numerator: p.iter().map(|c| c * scale).collect(),
                        denominator: q,
                    };
                    let h = Held::of(&f, data, &segs);
                    (if h.all() { Ok((f, h.worst, margin)) } else { Err(h.at) }, Some(margin))
                }
                Outcome::Infeasible { worst } => (Err(worst), None),
            };
            attempts.push(Attempt {
                coordinates: plane.coordinates,
                degree: basis.degree,
                coefficients: 2 * basis.len(),
                feasible: held.is_ok(),
                margin,
                single_precision: single,
                seconds: t.elapsed().as_secs_f64(),
            });
            match held {
                Ok(found) => {
                    lead = k;
                    return Ok(Ok(found));
                }
                Err(worst) => {
                    if !single {
                        failed[k] = terms;
                    }
                    conflict.get_or_insert(worst);
                }
            }
        }
        Ok(Err(conflict.unwrap_or(0)))
    };
    // The fewest terms that hold in double precision; then, unless their
    // margin already holds in single precision (as shaders and renderers
    // evaluate), the fewest that do, up to twice as many terms: beyond, the
    // single-precision programmes cost more than the whole search (a measured
    // tape's 680 terms: minutes), for a function of more than twice the
    // coefficients. Else the double one, said so.
    let double = match fewest(1, 1, top, |n| attempt(n, qp::DOUBLE_MARGIN))? {
        Ok(found) => found,
        Err(worst) => bail!(
            "no rational function of degree {} ({} coefficients) passes through every segment; the {} most in conflict with the others is {}, segment [{}, {}]: widen the segments{}",
            Basis::degree_of(top),
            2 * top,
            if grid.is_some() { "point of the densified grid" } else { "sample" },
            sample_text(worst, &obs[worst]),
            segs.segments[worst].lo,
            segs.segments[worst].hi,
            if capped.is_some() { " or measure more samples" } else { " or raise --max-degree" }
        ),
    };
    let terms = double.0.numerator.len();
    let most = (2 * terms).min(top);
    let (best, single_precision) = if double.2 >= qp::SINGLE_MARGIN {
        (double, true)
    } else if most > terms {
        match fewest(terms + 1, most, most, |n| attempt(n, qp::SINGLE_MARGIN))? {
            Ok(single) => (single, true),
            Err(_) => (double, false),
        }
    } else {
        (double, false)
    };
    let (function, worst_violation, _) = best;
    let densified = match (spec.densify, &grid) {
        (Some(step_deg), Some(g)) => Some(Densified {
            step_deg,
            points: g.observations.len(),
            measured: Held::of(&function, measured, &Segments::new(&measured.observations, spec.segments)?),
            warnings: g.warnings.clone(),
        }),
        _ => None,
    };
    // The figures against the measured samples, in their own units, as
    // every other fit reports them.
    let (metrics, linf) = function.against(measured);
    Ok(RationalFit {
        metrics,
        function,
        segments: spec.segments,
        shifted: segs.shifted,
        samples: m,
        seconds: start.elapsed().as_secs_f64(),
        linf,
        worst_violation,
        capped,
        single_precision,
        attempts,
        densified,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::Units;

    /// Samples of `f` over three incidences and a fan of views.
    fn data(f: impl Fn(f64, f64, f64) -> f64) -> Dataset {
        let mut observations = Vec::new();
        for ti in [10.0f64, 30.0, 50.0] {
            for to in (0..=14).map(|k| 5.0 * k as f64) {
                for dphi in [0.0f64, 45.0, 90.0, 135.0, 180.0] {
                    let (ti, to, dphi) = (ti.to_radians(), to.to_radians(), dphi.to_radians());
                    observations.push(Observation {
                        theta_i: ti,
                        theta_o: to,
                        dphi,
                        value: f(ti, to, dphi),
                        sigma: None,
                        shared: Default::default(),
                    });
                }
            }
        }
        Dataset::new(Units::Fr, observations)
    }

    fn spec(segments: SegmentSource) -> RationalSpec {
        RationalSpec {
            parametrization: Parametrization::Back,
            segments,
            max_degree: RationalSpec::MAX_DEGREE,
            cosine: true,
            densify: None,
        }
    }

    #[test]
    fn a_cosine_product_is_degree_zero() {
        // f = 0.3 cosθi cosθo is the cosine factor times a constant.
        let d = data(|ti, to, _| 0.3 * ti.cos() * to.cos());
        let f = fit(&d, &spec(SegmentSource::Relative(0.01))).unwrap();
        assert_eq!(f.function.degree, 0);
        assert_eq!(f.worst_violation, 0.0);
        assert!(f.linf < 0.01 * 0.3, "{}", f.linf);
    }

    #[test]
    fn a_lobe_needs_a_higher_degree_and_every_segment_holds() {
        // A Lambertian floor and a retro lobe: no constant passes within 2 %.
        let lobe = |ti: f64, to: f64, dphi: f64| {
            let d = gonio_brdf::Directions::from_angles(ti, to, dphi);
            let c = gonio_brdf::frame::dot(d.l, d.v).max(0.0);
            0.1 + 2.0 * c.powi(8)
        };
        let d = data(lobe);
        let f = fit(&d, &spec(SegmentSource::Relative(0.02))).unwrap();
        assert!(f.function.degree >= 1, "{:?}", f.attempts);
        assert!(f.worst_violation <= VIOLATION_TOLERANCE);
        for (o, &v) in d
            .observations
            .iter()
            .zip(&d.observations.iter().map(|o| f.function.eval(&o.directions())).collect::<Vec<_>>())
        {
            assert!((v - o.value).abs() <= 0.02 * o.value * (1.0 + 1e-9), "{v} against {}", o.value);
        }
        // The count found is the lowest: one term fewer was tried and failed.
        let below = f
            .attempts
            .iter()
            .find(|a| a.coefficients + 2 == f.function.coefficients() && a.coordinates == f.function.coordinates)
            .expect("one term fewer was tried");
        assert!(f
            .attempts
            .iter()
            .all(|a| a.coefficients + 2 != f.function.coefficients() || !a.feasible));
        assert!(!below.feasible);
    }

    #[test]
    fn contradicting_segments_name_a_sample_and_too_few_samples_are_refused() {
        let mut d = data(|_, _, _| 1.0);
        // The same geometry twice, with disjoint segments.
        let mut twin = d.observations[7];
        twin.value = 2.0;
        d.observations.push(twin);
        let e = fit(&d, &spec(SegmentSource::Absolute(0.1))).unwrap_err().to_string();
        assert!(e.contains("no rational function of degree") && e.contains("sample"), "{e}");
        let one = Dataset {
            observations: d.observations[..1].to_vec(),
            ..d.clone()
        };
        let e = fit(&one, &spec(SegmentSource::Absolute(0.1))).unwrap_err().to_string();
        assert!(e.contains("too few"), "{e}");
        let few = Dataset {
            observations: d.observations[..30].to_vec(),
            ..d
        };
        let f = fit(&few, &spec(SegmentSource::Absolute(0.1))).unwrap();
        assert!(f.capped.is_some() && f.attempts.iter().all(|a| a.coefficients <= 30));
    }
}
