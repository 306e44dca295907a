//! The rational fit: the fewest terms (in graded order, numerator and
//! denominator alike) whose function passes through every segment, in
//! either coordinate system, up to the highest degree the spec and the
//! samples allow (`search`); each count is a programme per system (`qp`).

use super::basis::Basis;
use super::function::Rational;
use super::programmes::{cosine_factors, Attempt, Held, Programmes};
use super::segments::{sample_text, SegmentSource, Segments};
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

#[derive(Debug, Clone, PartialEq)]
pub struct RationalFit {
    pub function: Rational,
    pub segments: SegmentSource,
    /// The multiple of σ the segments came to, when drawn from σ.
    pub segment_k: Option<f64>,
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

impl RationalFit {
    /// The segments as fitted, with the multiple of σ a `joint` source
    /// came to.
    pub fn segments_text(&self) -> String {
        self.segments.text(self.segment_k)
    }
}

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

/// Fits `data` in its own quantity (`f_r` or `f_r·cosθo`, as ALTA fits a
/// file's numbers): the segments are of that quantity.
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
    let mut programmes = Programmes::new(data, &segs, (spec.parametrization, spec.cosine), &factors, scale);
    let (best, single_precision) = match programmes.search(top, &mut trying)? {
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
    let attempts = programmes.attempts;
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
        segment_k: segs.k,
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
    use crate::fit::data::Observation;
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

    fn back_spec(segments: SegmentSource) -> RationalSpec {
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
        let f = fit(&d, &back_spec(SegmentSource::Relative(0.01))).unwrap();
        assert_eq!(f.function.degree, 0);
        assert_eq!(f.worst_violation, 0.0);
        assert!(f.linf < 0.01 * 0.3, "{}", f.linf);
    }

    #[test]
    fn joint_segments_say_the_multiple_of_sigma_they_came_to() {
        let mut d = data(|ti, to, _| 0.3 * ti.cos() * to.cos());
        let n = d.observations.len();
        d.observations.iter_mut().for_each(|o| o.sigma = Some(0.01 * o.value));
        let f = fit(&d, &back_spec(SegmentSource::Joint)).unwrap();
        assert_eq!(f.segment_k, Some(super::super::segments::joint_k(n)));
        assert!(f.segments_text().starts_with("joint (value ± 3.69σ"), "{}", f.segments_text());
        let f = fit(&d, &back_spec(SegmentSource::Sigma)).unwrap();
        assert_eq!(f.segment_k, Some(2.0));
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
        let f = fit(&d, &back_spec(SegmentSource::Relative(0.02))).unwrap();
        assert!(f.function.degree >= 1, "{:?}", f.attempts);
        assert!(f.worst_violation <= super::super::programmes::VIOLATION_TOLERANCE);
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
        let e = fit(&d, &back_spec(SegmentSource::Absolute(0.1))).unwrap_err().to_string();
        assert!(e.contains("no rational function of degree") && e.contains("sample"), "{e}");
        let one = Dataset {
            observations: d.observations[..1].to_vec(),
            ..d.clone()
        };
        let e = fit(&one, &back_spec(SegmentSource::Absolute(0.1))).unwrap_err().to_string();
        assert!(e.contains("too few"), "{e}");
        let few = Dataset {
            observations: d.observations[..30].to_vec(),
            ..d
        };
        let f = fit(&few, &back_spec(SegmentSource::Absolute(0.1))).unwrap();
        assert!(f.capped.is_some() && f.attempts.iter().all(|a| a.coefficients <= 30));
    }
}
