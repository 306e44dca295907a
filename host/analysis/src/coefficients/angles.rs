//! The CIE goniometer system of retroreflection (CIE 54.2, ASTM E808) in
//! the sample frame of `models.md` §1. Source direction `s = (0,0,1)`,
//! observer `o = (0, sinα, cosα)` (the observation half-plane is `x = 0`,
//! `y > 0`); the first axis is `x`, perpendicular to it. The reference axis
//! (the sample normal) starts on the illumination axis and is turned by β1
//! about the first axis (towards the observer for β1 > 0), then by β2 about
//! the second axis: `n = (sinβ2, sinβ1·cosβ2, cosβ1·cosβ2)`. Hence
//! `cosθi = cosβ1·cosβ2`, `cosθo = cosβ2·cos(β1 − α)`; in the coplanar
//! geometry of ASTM E810 (β2 = 0) `θi = |β|`, `θo = |β − α|`: at β = −4°
//! the observer is on the far side of the beam from the normal
//! (θo = 4° + α), at β = 30° between the beam and the normal (θo = 30° − α),
//! and the 30 m road-marking geometry (β = 88.76°, α = 1.05°) has the eye
//! nearer the normal than the headlamp (θo = 87.71°). The rotation angle ε
//! turns the sample about its normal: the head measures isotropic BRDFs, so
//! it changes nothing here and is carried for the report only.
//! Derivation and hand-computed cases: `docs/retroreflection.md`.

use gonio_brdf::Directions;
use serde::Serialize;

/// One geometry of the CIE system, in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Cie {
    pub alpha_deg: f64,
    pub beta1_deg: f64,
    pub beta2_deg: f64,
    pub epsilon_deg: f64,
}

impl Cie {
    /// Coplanar geometry (β2 = 0): entrance angle β, observation angle α.
    pub fn coplanar(alpha_deg: f64, beta_deg: f64, epsilon_deg: f64) -> Self {
        Cie {
            alpha_deg,
            beta1_deg: beta_deg,
            beta2_deg: 0.0,
            epsilon_deg,
        }
    }

    /// The entrance angle β: `cosβ = cosβ1·cosβ2`, signed as β1.
    pub fn beta_deg(&self) -> f64 {
        let (b1, b2) = (self.beta1_deg.to_radians(), self.beta2_deg.to_radians());
        let b = (b1.cos() * b2.cos()).clamp(-1.0, 1.0).acos().to_degrees();
        if self.beta1_deg < 0.0 {
            -b
        } else {
            b
        }
    }

    /// Unit vectors of the sample normal, the source and the observer (lab frame).
    pub fn lab(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (a, b1, b2) = (
            self.alpha_deg.to_radians(),
            self.beta1_deg.to_radians(),
            self.beta2_deg.to_radians(),
        );
        let n = [b2.sin(), b1.sin() * b2.cos(), b1.cos() * b2.cos()];
        (n, [0.0, 0.0, 1.0], [0.0, a.sin(), a.cos()])
    }

    /// Light and view in the sample frame (light at azimuth 0).
    pub fn directions(&self) -> Directions {
        let (n, s, o) = self.lab();
        in_sample_frame(n, s, o)
    }

    /// `(θi, θo, Δφ)` in degrees, Δφ in [0°, 180°] (isotropic: its sign is free).
    pub fn sample_angles_deg(&self) -> [f64; 3] {
        sample_angles_deg(&self.directions())
    }
}

/// Light `l` and view `v` (lab frame) in the frame of normal `n`, `x`
/// along the light's projection (or, at normal incidence, the first axis').
pub fn in_sample_frame(n: [f64; 3], l: [f64; 3], v: [f64; 3]) -> Directions {
    Directions::in_frame(n, l, v, [1.0, 0.0, 0.0])
}

/// `(θi, θo, |Δφ|)` in degrees of a pair of directions.
pub fn sample_angles_deg(d: &Directions) -> [f64; 3] {
    let (ti, to, dphi) = d.angles();
    [ti.to_degrees(), to.to_degrees(), dphi.abs().to_degrees()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_brdf::frame::dot;

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < tol)
    }

    /// Hand-computed cases (docs/retroreflection.md).
    #[test]
    fn coplanar_geometries_by_hand() {
        // β = −4°, α = 0.2°: observer beyond the beam, θo = 4.2°, retro side.
        let g = Cie::coplanar(0.2, -4.0, 0.0).sample_angles_deg();
        assert!(close(g, [4.0, 4.2, 0.0], 1e-9), "{g:?}");
        // β = 30°, α = 0.5°: observer between beam and normal, θo = 29.5°.
        let g = Cie::coplanar(0.5, 30.0, 90.0).sample_angles_deg();
        assert!(close(g, [30.0, 29.5, 0.0], 1e-9), "{g:?}");
        // β = 0.1°, α = 0.2°: the observer crosses the normal: θo = 0.1°, mirror side.
        let g = Cie::coplanar(0.2, 0.1, 0.0).sample_angles_deg();
        assert!(close(g, [0.1, 0.1, 180.0], 1e-9), "{g:?}");
        // The 30 m road-marking geometry.
        let g = Cie::coplanar(1.05, 88.76, 0.0).sample_angles_deg();
        assert!(close(g, [88.76, 87.71, 0.0], 1e-9), "{g:?}");
    }

    #[test]
    fn non_coplanar_geometry_by_hand() {
        // β1 = 30°, β2 = 20°, α = 1°: cosθi = cos30·cos20 = 0.813798,
        // cosθo = cos20·cos29 = 0.821874; l·v = cos α, so
        // cosΔφ = (cosα − cosθi cosθo)/(sinθi sinθo).
        let g = Cie {
            alpha_deg: 1.0,
            beta1_deg: 30.0,
            beta2_deg: 20.0,
            epsilon_deg: 0.0,
        };
        let [ti, to, dp] = g.sample_angles_deg();
        let (ci, co) = (0.813_797_681_349_373_7_f64, 0.821_873_684_792_822_6_f64);
        assert!((ti - ci.acos().to_degrees()).abs() < 1e-9, "{ti}");
        assert!((to - co.acos().to_degrees()).abs() < 1e-9, "{to}");
        let (si, so) = ((1.0 - ci * ci).sqrt(), (1.0 - co * co).sqrt());
        let cdp = (1f64.to_radians().cos() - ci * co) / (si * so);
        assert!((dp - cdp.acos().to_degrees()).abs() < 1e-6, "{dp} vs {}", cdp.acos().to_degrees());
        assert!((g.beta_deg() - ci.acos().to_degrees()).abs() < 1e-9);
    }

    #[test]
    fn the_angle_between_light_and_view_is_alpha() {
        for (a, b1, b2) in [(0.1, -4.0, 0.0), (2.0, 45.0, 10.0), (0.33, 5.0, -30.0)] {
            let d = Cie {
                alpha_deg: a,
                beta1_deg: b1,
                beta2_deg: b2,
                epsilon_deg: 0.0,
            }
            .directions();
            let cos = dot(d.l, d.v);
            assert!((cos.acos().to_degrees() - a).abs() < 1e-6);
        }
    }
}
