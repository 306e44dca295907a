//! The rational model (Belcour et al. 2014 §5.B, Pacanowski et al. 2012) on
//! materials that are none of our models: a glass-bead layer and two retro
//! lobes of different widths, sampled with 2 % noise on the Belcour grid,
//! with the paper's absolute segments of ±0.5 sr⁻¹.

use gonio_analysis::fit::Dataset;
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::{self, RationalSpec, SegmentSource};
use gonio_brdf::{Directions, GlassBeads};
use gonio_tests::synthetic;

/// Fits, checks every sample against its segment on the function itself,
/// and returns the degree found.
fn fits_within(data: &Dataset, parametrization: Parametrization, max_degree: usize) -> usize {
    let half = 0.5;
    let spec = RationalSpec {
        parametrization,
        segments: SegmentSource::Absolute(half),
        max_degree,
        cosine: true,
        densify: None,
    };
    let f = rational::fit(data, &spec).unwrap_or_else(|e| panic!("{parametrization:?}: {e:#}"));
    eprintln!(
        "{parametrization:?}: degree {} ({} coefficients), RMSE {:.4}, L∞ {:.4}, {:.2} s, {:?}",
        f.function.degree,
        f.function.coefficients(),
        f.metrics.rmse,
        f.linf,
        f.seconds,
        f.attempts
    );
    assert_eq!(f.worst_violation, 0.0);
    for o in &data.observations {
        let v = f.function.eval(&o.directions());
        // A segment reaching below zero is [0, max(v + h, 2h)].
        let (lo, hi) = if o.value < half {
            (0.0, (o.value + half).max(2.0 * half))
        } else {
            (o.value - half, o.value + half)
        };
        assert!(v > lo && v < hi, "{v} outside [{lo}, {hi}]");
    }
    assert!(f.linf < 2.0 * half && f.metrics.l2.is_finite());
    // The fewest terms: one fewer was tried and could not be held.
    let below = f.attempts.iter().find(|a| a.coefficients + 2 == f.function.coefficients());
    assert!(below.is_some_and(|a| !a.feasible), "{:?}", f.attempts);
    f.function.degree
}

#[test]
fn glass_beads_in_both_planes() {
    let beads = GlassBeads::default();
    let data = synthetic::samples_of(|d: &Directions| beads.eval(d), &synthetic::belcour_geometries(), 3_000, 0.02, 7);
    for p in Parametrization::BOTH {
        // Belcour et al. needed 48–70 coefficients for their tapes.
        assert!(fits_within(&data, p, RationalSpec::MAX_DEGREE) <= 4);
    }
}

#[test]
fn two_lobes_of_different_widths() {
    let data = synthetic::samples_of(synthetic::two_lobes, &synthetic::belcour_geometries(), 3_000, 0.02, 7);
    fits_within(&data, Parametrization::Back, 6);
}
