//! The vertical segments a rational function must pass through (Pacanowski
//! et al. 2012): an interval per sample, from the measurement's
//! own uncertainty or of a width the user gives, in the samples' quantity
//! (`f_r` or `f_r·cosθo`).

use crate::fit::data::Observation;
use crate::rounding::significant;
use crate::uncertainty::K_COVERAGE;
use anyhow::{bail, Result};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};
use std::str::FromStr;

/// Where the segments come from (`--segments`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind", content = "width")]
pub enum SegmentSource {
    /// The sample's k = 2 interval, `value ± 2σ`: the calibrated CSV's
    /// `brdf_lo_sr`–`brdf_hi_sr`, ALTA's `#VS 2`.
    Sigma,
    /// `value ± kσ`, k wide enough that the true BRDF lies within every
    /// segment at once with probability `JOINT_COVERAGE` (`joint_k`). With
    /// thousands of samples, some 5 % of the ±2σ segments miss the truth,
    /// so a function through all of them must follow the noise: no smooth
    /// function does, however many coefficients it has.
    Joint,
    /// `value ± width` (sr⁻¹): Belcour et al. 2014 used 0.5 (1.0 for the
    /// orange coating).
    Absolute(f64),
    /// `value · (1 ± width)`.
    Relative(f64),
}

impl FromStr for SegmentSource {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        let width = |w: &str| -> Result<f64> {
            match w.trim().parse::<f64>() {
                Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
                _ => bail!("the width in `--segments {s}` must be a positive number"),
            }
        };
        match s.split_once(':') {
            None if s.trim() == "sigma" => Ok(SegmentSource::Sigma),
            None if s.trim() == "joint" => Ok(SegmentSource::Joint),
            Some(("abs", w)) => Ok(SegmentSource::Absolute(width(w)?)),
            Some(("rel", w)) => Ok(SegmentSource::Relative(width(w)?)),
            _ => bail!("`--segments {s}`: expected `sigma`, `joint`, `abs:WIDTH` or `rel:WIDTH`"),
        }
    }
}

impl SegmentSource {
    /// What the segments were, in words; `k`, the multiple of σ the
    /// segments came to (`Segments::k`), is written out for `joint`.
    pub fn text(self, k: Option<f64>) -> String {
        match self {
            SegmentSource::Sigma => format!("sigma (value ± {K_COVERAGE}σ)"),
            SegmentSource::Joint => {
                let k = k.map_or("k".to_string(), |k| significant(k, 3));
                format!("joint (value ± {k}σ, the truth within all at once at {JOINT_COVERAGE})")
            }
            SegmentSource::Absolute(w) => format!("abs:{w} (value ± {w} sr⁻¹)"),
            SegmentSource::Relative(w) => format!("rel:{w} (value × (1 ± {w}))"),
        }
    }
}

/// The probability that the true BRDF lies within every `joint` segment.
pub const JOINT_COVERAGE: f64 = 0.95;

/// The multiple of σ whose `n` intervals all hold the truth with
/// probability `JOINT_COVERAGE`, the errors independent and normal
/// (Šidák): each must hold it with probability `JOINT_COVERAGE^(1/n)`.
/// 1.96 at one sample, 4.56 at 10 000. The errors a whole
/// scan shares (the reference's reflectance, the scale) move every value
/// together, which a smooth function follows; counted as independent
/// they only widen the segments.
pub fn joint_k(n: usize) -> f64 {
    let each = JOINT_COVERAGE.powf(1.0 / n.max(1) as f64);
    Normal::standard().inverse_cdf(0.5 + each / 2.0)
}

/// One sample's interval, `0 ≤ lo < hi`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub lo: f64,
    pub hi: f64,
}

/// The segments of every sample, and how many lay wholly
/// below zero.
#[derive(Debug, Clone, PartialEq)]
pub struct Segments {
    pub segments: Vec<Segment>,
    /// Segments of a negative value, `[0, max(v + h, h)]`. Every segment is
    /// clamped at zero, as Belcour et al. did (`[max(v − h, 0), v + h]`); a
    /// value that noise took below zero would then leave a sliver `[0, v +
    /// h]` that narrows to nothing as `v → −h`, so its upper end is held
    /// at `h` at least: a dark sample says the BRDF is within about `h` of
    /// zero.
    pub shifted: usize,
    /// The multiple of σ of segments drawn from the samples' σ.
    pub k: Option<f64>,
}

/// Where a sample is, for messages: its index in the file's order and its
/// angles.
pub fn sample_text(i: usize, o: &Observation) -> String {
    format!(
        "sample {} (θi = {:.2}°, θo = {:.2}°, Δφ = {:.2}°, value {})",
        i + 1,
        o.theta_i.to_degrees(),
        o.theta_o.to_degrees(),
        o.dphi.to_degrees(),
        o.value
    )
}

impl Segments {
    /// The segments of `observations` (in their quantity), clamped to
    /// non-negative values. A value or σ that is not a number, a missing σ
    /// with `sigma`, or a segment of zero width is an error naming the
    /// sample.
    pub fn new(observations: &[Observation], source: SegmentSource) -> Result<Segments> {
        let mut segments = Vec::with_capacity(observations.len());
        let mut shifted = 0;
        let k = match source {
            SegmentSource::Sigma => Some(K_COVERAGE),
            SegmentSource::Joint => Some(joint_k(observations.len())),
            SegmentSource::Absolute(_) | SegmentSource::Relative(_) => None,
        };
        for (i, o) in observations.iter().enumerate() {
            if !o.value.is_finite() {
                bail!("{}: the value is not a number", sample_text(i, o));
            }
            let half = match (source, k) {
                (SegmentSource::Absolute(w), _) => w,
                (SegmentSource::Relative(w), _) => w * o.value.abs(),
                (_, k) => match o.sigma {
                    Some(s) if s.is_finite() => k.unwrap_or(K_COVERAGE) * s,
                    Some(_) => bail!("{}: its uncertainty is not a number", sample_text(i, o)),
                    None => bail!(
                        "{}: no uncertainty, which `--segments sigma` and `joint` need (a calibrated CSV or an ALTA file with #VS); give `--segments abs:WIDTH` or `rel:WIDTH`",
                        sample_text(i, o)
                    ),
                },
            };
            if half < 0.0 {
                bail!("{}: its uncertainty is negative", sample_text(i, o));
            }
            if half.is_nan() || half == 0.0 {
                bail!(
                    "{}: its segment has zero width (σ = 0, or a relative width of a zero value); a rational function cannot pass exactly through a point",
                    sample_text(i, o)
                );
            }
            if !(o.value + half).is_finite() {
                bail!("{}: its segment is not finite", sample_text(i, o));
            }
            let (lo, hi) = (o.value - half, o.value + half);
            if o.value < 0.0 {
                shifted += 1;
            }
            let s = Segment {
                lo: lo.max(0.0),
                hi: hi.max(half),
            };
            segments.push(s);
        }
        Ok(Segments { segments, shifted, k })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(value: f64, sigma: Option<f64>) -> Observation {
        Observation {
            theta_i: 0.5,
            theta_o: 0.5,
            dphi: 0.0,
            value,
            sigma,
            shared: Default::default(),
        }
    }

    #[test]
    fn parses_the_four_sources_and_refuses_the_rest() {
        assert_eq!("sigma".parse::<SegmentSource>().unwrap(), SegmentSource::Sigma);
        assert_eq!("joint".parse::<SegmentSource>().unwrap(), SegmentSource::Joint);
        assert_eq!("abs:0.5".parse::<SegmentSource>().unwrap(), SegmentSource::Absolute(0.5));
        assert_eq!("rel:0.1".parse::<SegmentSource>().unwrap(), SegmentSource::Relative(0.1));
        for bad in ["abs:0", "rel:-1", "abs:nan", "abs:", "sig", "pct:3"] {
            assert!(bad.parse::<SegmentSource>().is_err(), "{bad}");
        }
    }

    #[test]
    fn joint_segments_hold_the_truth_at_once() {
        assert!((joint_k(1) - 1.959964).abs() < 1e-5);
        // Drawn: the share of 2 000 draws of 2 000 normal errors that all lie
        // within ±kσ is the joint coverage, within its binomial scatter.
        use rand::{rngs::StdRng, SeedableRng};
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = StdRng::seed_from_u64(7);
        let n = 2_000;
        let k = joint_k(n);
        assert!((4.1..4.3).contains(&k), "{k}");
        let draws = 2_000;
        let held = (0..draws)
            .filter(|_| {
                (0..n).all(|_| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    z.abs() <= k
                })
            })
            .count();
        let share = held as f64 / draws as f64;
        assert!((share - JOINT_COVERAGE).abs() < 0.015, "{share}");
        let s = Segments::new(&[obs(1.0, Some(0.1)), obs(2.0, Some(0.1))], SegmentSource::Joint).unwrap();
        assert_eq!(s.k, Some(joint_k(2)));
        assert!((s.segments[1].hi - (2.0 + 0.1 * joint_k(2))).abs() < 1e-12);
    }

    #[test]
    fn clamps_at_zero_without_slivers() {
        let s = Segments::new(
            &[obs(1.0, Some(0.1)), obs(0.05, Some(0.1)), obs(-0.3, Some(0.1))],
            SegmentSource::Sigma,
        )
        .unwrap();
        assert_eq!(s.segments[0], Segment { lo: 0.8, hi: 1.2 });
        assert_eq!(s.segments[1], Segment { lo: 0.0, hi: 0.25 });
        assert_eq!(s.segments[2], Segment { lo: 0.0, hi: 0.2 });
        assert_eq!(s.shifted, 1);
        // Continuous in the value: no sliver as it nears −2σ.
        let near = Segments::new(&[obs(-0.2 + 1e-12, Some(0.1))], SegmentSource::Sigma).unwrap();
        assert!((near.segments[0].hi - 0.2).abs() < 1e-9);
    }

    #[test]
    fn names_the_sample_of_a_bad_segment() {
        let e = Segments::new(&[obs(1.0, Some(0.1)), obs(1.0, Some(0.0))], SegmentSource::Sigma).unwrap_err();
        assert!(e.to_string().contains("sample 2") && e.to_string().contains("zero width"), "{e}");
        let e = Segments::new(&[obs(f64::NAN, Some(0.1))], SegmentSource::Absolute(0.5)).unwrap_err();
        assert!(e.to_string().contains("not a number"), "{e}");
        let e = Segments::new(&[obs(1.0, Some(f64::NAN))], SegmentSource::Sigma).unwrap_err();
        assert!(e.to_string().contains("uncertainty is not a number"), "{e}");
        let e = Segments::new(&[obs(1.0, None)], SegmentSource::Sigma).unwrap_err();
        assert!(e.to_string().contains("abs:WIDTH"), "{e}");
        let e = Segments::new(&[obs(1.0, Some(-0.1))], SegmentSource::Sigma).unwrap_err();
        assert!(e.to_string().contains("negative"), "{e}");
        let e = Segments::new(&[obs(1.0, Some(f64::MAX))], SegmentSource::Sigma).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        let e = Segments::new(&[obs(0.0, None)], SegmentSource::Relative(0.1)).unwrap_err();
        assert!(e.to_string().contains("zero width"), "{e}");
    }
}
