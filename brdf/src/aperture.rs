//! Finite apertures: a detector, a lamp or a retroreflectometer's receiver
//! is a disc of some angular diameter seen from the sample, and what it
//! reads is the BRDF averaged over that disc, not its value at the nominal
//! direction. On a retro lobe a few tenths of a degree wide the two differ
//! by percents, so the simulated head's detector and the coefficients'
//! standard apertures average the same way, with the same quadrature.
//!
//! A disc is covered by equal-area rings (midpoint rule in `(r/ρ)²`) of
//! points spread evenly in azimuth, the rings' starting azimuths staggered:
//! exact for any function that is linear or quadratic across the disc (each
//! ring's `r²` is the mean `r²` of its annulus), which is what the width of
//! a lobe shows as; the host's test checks a lobe narrower than the disc
//! against a Monte Carlo average.

use crate::frame::{cross, normalize};
use crate::Directions;

/// How finely a disc is covered: rings, and points on each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiscRule {
    pub rings: usize,
    pub per_ring: usize,
}

impl DiscRule {
    /// 32 points: the coefficients' source and receiver (1 024 pairs).
    pub const FINE: DiscRule = DiscRule { rings: 4, per_ring: 8 };
    /// 12 points: the simulated head's detector, evaluated at every
    /// conversion of a sweep (still exact for quadratics).
    pub const DETECTOR: DiscRule = DiscRule { rings: 2, per_ring: 6 };
}

/// Unit vectors covering a disc of angular diameter `diameter_deg` about
/// the unit vector `axis`, each standing for an equal share of its solid
/// angle; the axis alone for a point aperture (`diameter_deg ≤ 0`).
pub fn disc(axis: [f64; 3], diameter_deg: f64, rule: DiscRule) -> Vec<[f64; 3]> {
    if diameter_deg <= 0.0 {
        return vec![axis];
    }
    let rho = (diameter_deg / 2.0).to_radians();
    // Two unit vectors perpendicular to the axis.
    let helper = if axis[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let e1 = normalize(cross(axis, helper));
    let e2 = cross(axis, e1);
    let mut out = Vec::with_capacity(rule.rings * rule.per_ring);
    for ring in 0..rule.rings {
        let r = rho * ((ring as f64 + 0.5) / rule.rings as f64).sqrt();
        for k in 0..rule.per_ring {
            let phi = std::f64::consts::TAU * (k as f64 + 0.5 * (ring % 2) as f64) / rule.per_ring as f64;
            let (s, c) = (r.sin(), r.cos());
            out.push([0, 1, 2].map(|i| c * axis[i] + s * (phi.cos() * e1[i] + phi.sin() * e2[i])));
        }
    }
    out
}

/// Angular diameter (degrees) of the disc that subtends `solid_angle_sr`:
/// `Ω = 2π(1 − cos ρ)`.
pub fn diameter_deg(solid_angle_sr: f64) -> f64 {
    let cos_rho = 1.0 - solid_angle_sr / std::f64::consts::TAU;
    2.0 * cos_rho.clamp(-1.0, 1.0).acos().to_degrees()
}

/// The BRDF (sr⁻¹) a detector of field `detector_sr` reads of `f` at
/// nominal directions `d`: the flux `f·cosθ` it collects over its field (a
/// disc of that solid angle about the view) over the nominal `cosθo`, which
/// is what a calibration divides by.
pub fn field_average(detector_sr: f64, d: &Directions, f: impl Fn(&Directions) -> f64) -> f64 {
    let views = disc(d.v, diameter_deg(detector_sr), DiscRule::DETECTOR);
    let flux: f64 = views
        .iter()
        .filter(|v| v[2] > 0.0)
        .map(|&v| f(&Directions { l: d.l, v }) * v[2])
        .sum();
    flux / views.len() as f64 / d.cos_o()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::dot;

    #[test]
    fn the_disc_points_lie_inside_the_disc_and_balance_about_its_axis() {
        let axis = [0.0, 0.6, 0.8];
        for rule in [DiscRule::FINE, DiscRule::DETECTOR] {
            let pts = disc(axis, 0.4, rule);
            assert_eq!(pts.len(), rule.rings * rule.per_ring);
            let mut mean = [0.0; 3];
            for p in &pts {
                assert!(dot(*p, axis).acos().to_degrees() <= 0.2 + 1e-12);
                for i in 0..3 {
                    mean[i] += p[i] / pts.len() as f64;
                }
            }
            let along = dot(mean, axis);
            let off = [0, 1, 2].map(|i| mean[i] - along * axis[i]);
            assert!(dot(off, off).sqrt() < 1e-12, "{mean:?}");
        }
    }

    /// The mean squared angle from the axis is a disc's, ρ²/2, for either
    /// rule: what makes the average exact for quadratics.
    #[test]
    fn the_rings_hold_the_discs_second_moment() {
        let axis = [0.3, 0.0, (1.0f64 - 0.09).sqrt()];
        let rho = 0.25f64.to_radians();
        for rule in [DiscRule::FINE, DiscRule::DETECTOR] {
            let pts = disc(axis, 0.5, rule);
            let m2 = pts.iter().map(|p| dot(*p, axis).acos().powi(2)).sum::<f64>() / pts.len() as f64;
            assert!((m2 / (rho * rho / 2.0) - 1.0).abs() < 1e-6, "{rule:?}: {m2}");
        }
    }

    #[test]
    fn a_detector_of_belcours_solid_angle_is_about_four_tenths_of_a_degree() {
        let d = diameter_deg(3.6e-5);
        // π(ρ)² = Ω for a small disc.
        let small = 2.0 * (3.6e-5 / std::f64::consts::PI).sqrt().to_degrees();
        assert!((d - small).abs() < 1e-6 && (d - 0.3882).abs() < 1e-3, "{d}");
        assert_eq!(diameter_deg(0.0), 0.0);
    }
}
