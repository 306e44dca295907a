//! Source and receiver apertures: a retroreflectometer's lamp and receiver
//! are discs of finite angular diameter seen from the sample, and what it
//! reads is the average over both. On a retro lobe a few tenths of a degree
//! wide the average differs from the value at the nominal directions, so
//! the coefficients average the model the same way, with the quadrature of
//! `gonio_brdf::aperture` (32 points a disc); the test checks it on a lobe
//! narrower than the discs against a brute-force Monte Carlo average.

use super::angles::{in_sample_frame, Cie};
use gonio_brdf::aperture::{disc, DiscRule};
use gonio_brdf::Directions;
use serde::Serialize;

/// Angular diameters (degrees) of the source and the receiver as seen from the sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Apertures {
    pub source_deg: f64,
    pub receiver_deg: f64,
}

impl Apertures {
    /// Point source and point receiver: the value at the nominal directions.
    pub const POINT: Apertures = Apertures {
        source_deg: 0.0,
        receiver_deg: 0.0,
    };

    /// The wider of the two (degrees): the disc the standard averages over,
    /// within which samples interpolate a value (`Support::classify`).
    pub fn widest(&self) -> f64 {
        self.source_deg.max(self.receiver_deg)
    }
}

/// The average of `f(directions)` over every source point and every
/// receiver point, for the geometry `g`. Points behind the sample count as
/// zero (no light reaches, none leaves).
pub fn average(g: &Cie, apertures: Apertures, f: impl Fn(&Directions) -> f64) -> f64 {
    let (n, s, o) = g.lab();
    let sources = disc(s, apertures.source_deg, DiscRule::FINE);
    let receivers = disc(o, apertures.receiver_deg, DiscRule::FINE);
    let mut sum = 0.0;
    for l in &sources {
        for v in &receivers {
            let d = in_sample_frame(n, *l, *v);
            if d.l[2] > 0.0 && d.v[2] > 0.0 {
                sum += f(&d);
            }
        }
    }
    sum / (sources.len() * receivers.len()) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn a_point_aperture_is_the_value_at_the_nominal_directions() {
        let g = Cie::coplanar(0.2, 30.0, 0.0);
        let f = |d: &Directions| d.l[2] * d.v[2];
        let nominal = f(&g.directions());
        assert_eq!(average(&g, Apertures::POINT, f), nominal);
    }

    /// A narrow Gaussian lobe about the retro direction against a Monte
    /// Carlo average over uniformly drawn disc points.
    #[test]
    fn the_quadrature_matches_a_monte_carlo_average_on_a_narrow_lobe() {
        let g = Cie::coplanar(0.1, 10.0, 0.0);
        let ap = Apertures {
            source_deg: 0.17,
            receiver_deg: 0.17,
        };
        let width = 0.1f64.to_radians();
        let lobe = |d: &Directions| {
            let c = (d.l[0] * d.v[0] + d.l[1] * d.v[1] + d.l[2] * d.v[2]).clamp(-1.0, 1.0);
            (-(c.acos() / width).powi(2)).exp()
        };
        let quad = average(&g, ap, lobe);
        let (n, s, o) = g.lab();
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut draw = |axis: [f64; 3]| {
            // Rejection sampling of a uniform point of the disc.
            let rho = (ap.source_deg / 2.0).to_radians();
            loop {
                let (x, y): (f64, f64) = (rng.random_range(-rho..rho), rng.random_range(-rho..rho));
                if x * x + y * y <= rho * rho {
                    let e1 = [1.0, 0.0, 0.0];
                    let e2 = [0.0, axis[2], -axis[1]];
                    let v = [0, 1, 2].map(|i| axis[i] + x * e1[i] + y * e2[i]);
                    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    return v.map(|c| c / len);
                }
            }
        };
        let draws = 200_000;
        let mc = (0..draws).map(|_| lobe(&in_sample_frame(n, draw(s), draw(o)))).sum::<f64>() / draws as f64;
        let point = lobe(&g.directions());
        assert!((quad / mc - 1.0).abs() < 0.01, "quadrature {quad}, Monte Carlo {mc}");
        assert!((quad / point - 1.0).abs() > 0.1, "the apertures matter here: {quad} vs {point}");
    }
}
