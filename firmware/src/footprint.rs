//! The laser's footprint on the sample. A beam of 1/e² diameter `d`
//! (Gaussian, standard deviation `d/4` in each direction) meets the sample
//! at incidence θi, so its footprint is `d/cosθi` long in the plane of
//! incidence: 46 beam widths at EN 1436's 88.76°. On a square sample of
//! side `S` centred on the axes the share of the light that lands is
//! `erf(√2·S·cosθi/d)·erf(√2·S/d)`; the rest misses the sample and a reading
//! falls short by as much. A scan refuses an incidence that loses more than
//! [`LOST_MAX`] (`gonio scan --sample-size-mm`), and the simulated head
//! loses it (`gonio-sim`).

/// The share of the light a scan may lose off the sample's edges: a fifth
/// of the plate's certificate uncertainty (0.5 %), so that no budget
/// component is needed for it.
pub const LOST_MAX: f64 = 1e-3;

/// The share of a beam of diameter `beam_mm` (1/e²) that lands on a square
/// sample of side `sample_mm` at incidence `theta_i_deg` (0 at and beyond
/// the horizon).
pub fn on_sample(theta_i_deg: f64, beam_mm: f64, sample_mm: f64) -> f64 {
    if beam_mm <= 0.0 {
        return 1.0;
    }
    if theta_i_deg.abs() >= 90.0 {
        return 0.0;
    }
    let cos_i = libm::cos(theta_i_deg.to_radians());
    let k = core::f64::consts::SQRT_2 * sample_mm / beam_mm;
    libm::erf(k * cos_i) * libm::erf(k)
}

/// The largest incidence (degrees) at which a sample of side `sample_mm`
/// holds all but [`LOST_MAX`] of the beam: what a refusal suggests.
pub fn largest_incidence_deg(beam_mm: f64, sample_mm: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 90.0);
    if 1.0 - on_sample(lo, beam_mm, sample_mm) > LOST_MAX {
        return 0.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if 1.0 - on_sample(mid, beam_mm, sample_mm) > LOST_MAX {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_footprint_grows_as_one_over_cos_theta_i() {
        // Normal incidence on a sample 100 beams wide: all of it.
        assert!((on_sample(0.0, 1.0, 100.0) - 1.0).abs() < 1e-12);
        // A sample as long as the footprint's 1/e² length holds erf(√2)
        // of it along the plane of incidence: 95.4 %.
        let theta: f64 = 88.76;
        let long = 1.0 / theta.to_radians().cos();
        assert!((on_sample(theta, 1.0, long) - libm::erf(2f64.sqrt())).abs() < 1e-6);
        // EN 1436's incidence on 100 mm with a 1 mm beam: held; on 50 mm: not.
        assert!(1.0 - on_sample(88.76, 1.0, 100.0) < LOST_MAX);
        assert!(1.0 - on_sample(88.76, 1.0, 50.0) > LOST_MAX);
        assert_eq!(on_sample(90.0, 1.0, 100.0), 0.0);
        let t = largest_incidence_deg(1.0, 50.0);
        assert!(
            (1.0 - on_sample(t, 1.0, 50.0) - LOST_MAX).abs() < 1e-9 && (85.0..88.76).contains(&t),
            "{t}"
        );
    }
}
