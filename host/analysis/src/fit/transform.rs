//! Bounds for an unconstrained optimiser: MINUIT's transform (also lmfit's),
//! `x = lo + (hi − lo)(sin u + 1)/2`. It reaches the bounds at finite `u`, so
//! an optimum on a bound (a lobe that is not there, `k2 = 0`) is found, not
//! approached forever as with a logistic map.
//!
//! And the unit cube of the global search: `z ∈ [0, 1]` spread over the
//! bounds as [`Spread`] says (linear, logarithmic, or cubic for amplitudes
//! spanning decades down to zero).

use gonio_brdf::{Bound, Spread};

pub fn to_internal(b: &Bound, x: f64) -> f64 {
    let s = (2.0 * (x - b.lo) / (b.hi - b.lo) - 1.0).clamp(-1.0, 1.0);
    s.asin()
}

pub fn to_external(b: &Bound, u: f64) -> f64 {
    b.lo + (b.hi - b.lo) * (u.sin() + 1.0) / 2.0
}

/// `dx/du`.
pub fn slope(b: &Bound, u: f64) -> f64 {
    (b.hi - b.lo) * u.cos() / 2.0
}

/// From the unit cube to a parameter value.
pub fn from_unit(b: &Bound, z: f64) -> f64 {
    let z = z.clamp(0.0, 1.0);
    match b.spread {
        Spread::Linear => b.lo + (b.hi - b.lo) * z,
        Spread::Log => (b.lo.ln() + (b.hi.ln() - b.lo.ln()) * z).exp(),
        Spread::Amplitude => b.lo + (b.hi - b.lo) * z * z * z,
    }
}

/// From a parameter value to the unit cube (inverse of [`from_unit`]).
pub fn to_unit(b: &Bound, x: f64) -> f64 {
    let x = x.clamp(b.lo, b.hi);
    match b.spread {
        Spread::Linear => (x - b.lo) / (b.hi - b.lo),
        Spread::Log => (x.ln() - b.lo.ln()) / (b.hi.ln() - b.lo.ln()),
        Spread::Amplitude => ((x - b.lo) / (b.hi - b.lo)).cbrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_reaches_the_bounds() {
        for spread in [Spread::Linear, Spread::Log, Spread::Amplitude] {
            let b = Bound {
                lo: 0.5,
                hi: 200.0,
                spread,
                scales: false,
                open: (false, true),
            };
            for x in [0.5, 0.51, 3.0, 199.0, 200.0] {
                assert!((to_external(&b, to_internal(&b, x)) - x).abs() < 1e-9 * x);
                assert!((from_unit(&b, to_unit(&b, x)) - x).abs() < 1e-9 * x);
            }
        }
        let b = Bound {
            lo: -1.0,
            hi: 3.0,
            spread: Spread::Linear,
            scales: false,
            open: (true, true),
        };
        assert_eq!(to_external(&b, -std::f64::consts::FRAC_PI_2), -1.0);
        assert_eq!(to_external(&b, std::f64::consts::FRAC_PI_2), 3.0);
        let u = 0.3;
        let fd = (to_external(&b, u + 1e-6) - to_external(&b, u - 1e-6)) / 2e-6;
        assert!((slope(&b, u) - fd).abs() < 1e-8);
    }
}
