//! A physical retroreflector that is none of the models: a layer of glass
//! beads (refractive index 1.9, as in road-marking and sign beads) half
//! sunk in a white binder, with a glossy top. Real materials are never
//! exactly a model, and a simulated head that measured only members of the
//! model family would flatter every fit (`gonio demo` found retro-phong with
//! NCC 1.00000 on retro-phong data). Three terms, each with structure no
//! model of `models.md` has:
//!
//! - **Bead retroreflection.** A sphere of index n focuses paraxial light at
//!   `nR/(2(n − 1))` from its centre: for n = 1.9 that is 5.6 % behind the
//!   rear surface, so the return is not a cone about the source but a ring
//!   (its maximum at an observation angle γ0 > 0) with a halo from spherical
//!   aberration. `P(γ) = exp(−(γ − γ0)²/(2w²)) + h·exp(−γ/γh)`, γ the angle
//!   between light and view. Its strength follows the light through the
//!   bead's front surface twice (Fresnel transmission `T(θi)²`, n = 1.9) and
//!   the binder's shadow on half-sunk beads at grazing incidence
//!   (`cosθi^s`).
//! - **A glossy top** (the binder's and the beads' own surface): a GGX
//!   microfacet lobe with Smith shadowing and Fresnel (n = 1.5), which
//!   rises towards grazing (a sheen), unlike the Beckmann/Blinn lobes.
//! - **The binder**: Lambertian, reflectance ρ times the uncovered fraction.
//!
//! Values are of the order of a road-marking bead layer: `R_A(0.2°, −4°)`
//! ≈ 5 cd·lx⁻¹·m⁻² at 633 nm.

use super::frame::{dot, Directions};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GlassBeads {
    /// Peak of the bead retroreflection (sr⁻¹) at normal incidence.
    pub retro_sr: f64,
    /// Angle of the ring's maximum and its width (degrees).
    pub ring_deg: f64,
    pub ring_width_deg: f64,
    /// The aberration halo: its height relative to the ring and its decay angle (degrees).
    pub halo: f64,
    pub halo_deg: f64,
    /// Refractive index of the beads.
    pub bead_index: f64,
    /// Exponent of the binder's shadow on the beads, `cosθi^s`.
    pub shadow: f64,
    /// GGX roughness of the top surface and its refractive index.
    pub gloss_roughness: f64,
    pub gloss_index: f64,
    /// Reflectance of the binder between the beads.
    pub binder_rho: f64,
}

impl Default for GlassBeads {
    fn default() -> Self {
        GlassBeads {
            retro_sr: 8.0,
            ring_deg: 0.6,
            ring_width_deg: 0.45,
            halo: 0.25,
            halo_deg: 2.5,
            bead_index: 1.9,
            shadow: 0.7,
            gloss_roughness: 0.12,
            gloss_index: 1.5,
            binder_rho: 0.25,
        }
    }
}

/// Fresnel reflectance of unpolarised light entering a medium of index `n`
/// from air at incidence `cos_i`.
fn fresnel(cos_i: f64, n: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let s2 = (1.0 - c * c) / (n * n);
    if s2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - s2).sqrt();
    let rs = (c - n * ct) / (c + n * ct);
    let rp = (n * c - ct) / (n * c + ct);
    (rs * rs + rp * rp) / 2.0
}

/// Smith's masking of the GGX distribution for a direction at `cos`.
fn smith_ggx(cos: f64, a: f64) -> f64 {
    let c2 = cos * cos;
    let t2 = (1.0 - c2) / c2.max(1e-300);
    2.0 / (1.0 + (1.0 + a * a * t2).sqrt())
}

impl GlassBeads {
    /// `f_r` (sr⁻¹).
    pub fn eval(&self, d: &Directions) -> f64 {
        let (ci, co) = (d.cos_i(), d.cos_o());
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        // Bead retroreflection.
        let gamma = dot(d.l, d.v).clamp(-1.0, 1.0).acos().to_degrees();
        let ring = (-(gamma - self.ring_deg).powi(2) / (2.0 * self.ring_width_deg.powi(2))).exp();
        let halo = self.halo * (-gamma / self.halo_deg).exp();
        let t = 1.0 - fresnel(ci, self.bead_index);
        let retro = self.retro_sr * t * t * ci.powf(self.shadow) * (ring + halo);
        // Glossy top: GGX with Smith shadowing and Fresnel.
        let h = d.half();
        let a2 = self.gloss_roughness * self.gloss_roughness;
        let nh2 = h[2] * h[2];
        let dist = a2 / (PI * (nh2 * (a2 - 1.0) + 1.0).powi(2));
        let g = smith_ggx(ci, self.gloss_roughness) * smith_ggx(co, self.gloss_roughness);
        let gloss = fresnel(dot(d.v, h), self.gloss_index) * dist * g / (4.0 * ci * co);
        // The binder between the beads.
        retro + gloss + self.binder_rho / PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_retro_return_is_a_ring_not_a_peak() {
        let g = GlassBeads::default();
        let at = |gamma: f64| g.eval(&Directions::from_degrees(30.0, 30.0 - gamma, 0.0));
        assert!(at(0.6) > at(0.0) * 1.1, "maximum off the source: {} vs {}", at(0.6), at(0.0));
        assert!(at(0.0) > at(3.0) * 3.0);
        // Falls with entrance angle (Fresnel and the binder's shadow).
        let ra = |ti: f64| g.eval(&Directions::from_degrees(ti, ti - 0.2, 0.0));
        assert!(ra(5.0) > ra(40.0) && ra(40.0) > ra(80.0));
    }

    #[test]
    fn fresnel_is_right_at_the_ends() {
        assert!((fresnel(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert!((fresnel(0.0, 1.5) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn finite_and_non_negative_everywhere() {
        let g = GlassBeads::default();
        for ti in (0..90).step_by(7) {
            for to in (0..90).step_by(7) {
                for dp in (-180..=180).step_by(15) {
                    let v = g.eval(&Directions::from_degrees(ti as f64, to as f64, dp as f64));
                    assert!(v.is_finite() && v >= 0.0, "{ti} {to} {dp}: {v}");
                }
            }
        }
    }
}
