//! The rational fit: the fewest terms (in graded order, numerator and
//! denominator alike) whose function passes through every segment,
//! bracketed by doubling the count and found by bisection, up to the
//! highest degree the spec and the samples allow; each count is one
//! programme (`qp`).

use super::basis::{coordinates, Basis, Domain};
use super::function::Rational;
use super::qp::{self, Outcome, Row};
use super::segments::{sample_text, SegmentSource, Segments};
use crate::fit::{Dataset, Metrics, Units};
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
}

impl RationalSpec {
    /// Degree 8 is 330 coefficients, beyond the 48–70 Belcour et al. 2014
    /// needed for their tapes at ±0.5 sr⁻¹.
    pub const MAX_DEGREE: usize = 8;

    /// The highest degree a spec may ask for: 910 coefficients, about a
    /// minute per programme on this machine's cores (each interior-point
    /// iteration factors `rows·n²`), where degree 20 would take hours.
    pub const HIGHEST_DEGREE: usize = 12;
}

/// One count of terms tried.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Attempt {
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
    /// in double only: the fewest terms that held nothing by that margin
    /// up to the highest count tried.
    pub single_precision: bool,
    pub attempts: Vec<Attempt>,
}

/// Misses beyond this (relative to a segment's width) reject a count's
/// function: the margins put a solution strictly inside.
const VIOLATION_TOLERANCE: f64 = 1e-9;

/// Fits `data` (any units; segments are taken in `f_r`).
pub fn fit(data: &Dataset, spec: &RationalSpec) -> Result<RationalFit> {
    fit_observed(data, spec, |_| {})
}

/// As `fit`, calling `trying` with each count of coefficients before its
/// programme is solved (a progress bar's hook).
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
    let fr = data.in_units(Units::Fr)?;
    let obs = &fr.observations;
    let segs = Segments::new(obs, spec.segments)?;
    let points: Vec<[f64; 3]> = obs.iter().map(|o| coordinates(spec.parametrization, &o.directions())).collect();
    let domain = Domain::around(&points);
    let mut rows = Vec::with_capacity(obs.len());
    for (i, (o, s)) in obs.iter().zip(&segs.segments).enumerate() {
        let d = o.directions();
        let c = if spec.cosine { d.cos_i() * d.cos_o() } else { 1.0 };
        if c.is_nan() || c <= 1e-9 {
            bail!(
                "{}: grazing, where the cosine factor cosθi·cosθo is zero (fit without it: --no-cosine)",
                sample_text(i, o)
            );
        }
        rows.push(Row {
            u: domain.unit(points[i]),
            lo: s.lo / c,
            hi: s.hi / c,
        });
    }
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
    // Values in units of the largest segment end, so that the margin is
    // comparable between data sets (it scales as a half-width over the
    // largest value otherwise); the numerator takes the scale back.
    let scale = rows.iter().map(|r| r.hi).fold(0.0, f64::max);
    for r in &mut rows {
        r.lo /= scale;
        r.hi /= scale;
    }
    // The largest miss of a segment, over its width (∞ for a value that is
    // not a number), and where.
    let worst_of = |f: &Rational| -> (f64, usize) {
        let mut worst = (0.0, 0);
        for (i, (v, s)) in f.values(&fr).iter().zip(&segs.segments).enumerate() {
            let out = if v.is_nan() {
                f64::INFINITY
            } else {
                (s.lo - v).max(v - s.hi).max(0.0) / (s.hi - s.lo)
            };
            if out > worst.0 {
                worst = (out, i);
            }
        }
        worst
    };
    let mut attempts = Vec::new();
    // The function of `terms` terms if it holds every segment (checked on
    // the function itself, not taken from the solver), else the sample
    // most in conflict.
    let mut attempt = |terms: usize, min_margin: f64| -> Result<std::result::Result<(Rational, f64), usize>> {
        trying(2 * terms);
        let t = Instant::now();
        let basis = Basis::with_terms(terms);
        let (held, margin) = match qp::solve(&basis, &rows, min_margin)? {
            Outcome::Solved { p, q, margin } => {
                let f = Rational {
                    parametrization: spec.parametrization,
                    degree: basis.degree,
                    cosine: spec.cosine,
                    domain,
                    order: basis.order,
                    numerator: p.iter().map(|c| c * scale).collect(),
                    denominator: q,
                };
                let (miss, at) = worst_of(&f);
                (if miss <= VIOLATION_TOLERANCE { Ok((f, miss)) } else { Err(at) }, Some(margin))
            }
            Outcome::Infeasible { worst } => (Err(worst), None),
        };
        attempts.push(Attempt {
            degree: basis.degree,
            coefficients: 2 * basis.len(),
            feasible: held.is_ok(),
            margin,
            single_precision: min_margin >= qp::SINGLE_MARGIN,
            seconds: t.elapsed().as_secs_f64(),
        });
        Ok(held)
    };
    // Galloping (1, 2, 4, … terms up to `top`) brackets the fewest terms
    // that hold within a factor of two, so the costliest programme solved
    // has at most twice the answer's terms; a bisection inside the bracket
    // then finds it, to one term, as ALTA's walk does. Counts below `lo`
    // do not hold (none is below one term). `Err` names the sample most in
    // conflict at `top`.
    let mut search = |min_margin: f64| -> Result<std::result::Result<(Rational, f64), usize>> {
        let mut lo = 1;
        let mut n = 1;
        let mut best = loop {
            match attempt(n, min_margin)? {
                Ok(held) => break held,
                Err(worst) if n == top => return Ok(Err(worst)),
                Err(_) => {
                    lo = n + 1;
                    n = (2 * n).min(top);
                }
            }
        };
        let mut hi = n;
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            match attempt(mid, min_margin)? {
                Ok(held) => {
                    best = held;
                    hi = mid;
                }
                Err(_) => lo = mid + 1,
            }
        }
        Ok(Ok(best))
    };
    // A function that holds in single precision, as shaders and renderers
    // evaluate it; else one that holds in double only, said so.
    let (best, single_precision) = match search(qp::SINGLE_MARGIN)? {
        Ok(best) => (best, true),
        Err(_) => match search(qp::DOUBLE_MARGIN)? {
            Ok(best) => (best, false),
            Err(worst) => bail!(
                "no rational function of degree {} ({} coefficients) passes through every segment; the sample most in conflict with the others is {}, segment [{}, {}]: widen the segments{}",
                Basis::degree_of(top),
                2 * top,
                sample_text(worst, &obs[worst]),
                segs.segments[worst].lo,
                segs.segments[worst].hi,
                if capped.is_some() { " or measure more samples" } else { " or raise --max-degree" }
            ),
        },
    };
    let (function, worst_violation) = best;
    // The figures in the data's own units, as every other fit reports them.
    let (metrics, linf) = function.against(data);
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::data::Observation;

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
            .find(|a| a.coefficients + 2 == f.function.coefficients())
            .expect("one term fewer was tried");
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
