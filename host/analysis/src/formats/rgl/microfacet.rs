//! The microfacet quantities of Dupuy & Jakob 2018 (§4) for an isotropic
//! material, estimated from its retroreflection as the paper does: in the
//! retro configuration the half vector is the direction itself, so a
//! microfacet BRDF gives `f(ω, ω) = F·D(ω) / (4 σ(ω) cos θ)` with
//! `σ(ω) = ∫ D(m) ⟨ω·m⟩ dm` the projected area. `D ∝ f(ω, ω) σ(ω) cos θ` is a
//! fixed point, found by power iteration from `σ = 1`, with `D` normalised so
//! that `∫ D(m) cos θm dm = 1`.
//!
//! The `.bsdf` file stores `D` and `σ`; the renderer multiplies the tabulated
//! values by `D(m) / (4 σ(ωi))` (the file's `jacobian` flag), which takes
//! the shape a microfacet lobe would have out of what is interpolated.

use std::f64::consts::{FRAC_PI_2, PI};

/// Polar angles of the table (uniform over `[0, π/2]`).
const TABLE: usize = 512;
/// Power iterations; the paper's converge in a handful.
const ITERATIONS: usize = 8;

/// `D(θm)` and `σ(θ)` on a uniform table of polar angles.
#[derive(Debug, Clone)]
pub struct Microfacet {
    d: Vec<f64>,
    sigma: Vec<f64>,
}

/// `∫₀^{2π} max(0, a + b cos φ) dφ` for `b ≥ 0`.
fn clipped_cosine_integral(a: f64, b: f64) -> f64 {
    if b <= a.abs() {
        return if a > 0.0 { 2.0 * PI * a } else { 0.0 };
    }
    let phi0 = (-a / b).acos();
    2.0 * (a * phi0 + b * phi0.sin())
}

fn angle(i: usize) -> f64 {
    i as f64 * FRAC_PI_2 / (TABLE - 1) as f64
}

/// Linear interpolation in a table of [`angle`]s.
fn interpolate(table: &[f64], theta: f64) -> f64 {
    let x = (theta / FRAC_PI_2).clamp(0.0, 1.0) * (TABLE - 1) as f64;
    let i = (x as usize).min(TABLE - 2);
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

impl Microfacet {
    /// From the retroreflection `retro(θ) = f(ω, ω)` (sr⁻¹, finite and ≥ 0).
    pub fn from_retro(mut retro: impl FnMut(f64) -> f64) -> Self {
        let retro: Vec<f64> = (0..TABLE).map(|i| retro(angle(i))).collect();
        let mut sigma = vec![1.0; TABLE];
        let mut d = vec![0.0; TABLE];
        for _ in 0..ITERATIONS {
            for i in 0..TABLE {
                d[i] = retro[i] * sigma[i] * angle(i).cos();
            }
            normalise(&mut d);
            sigma = projected_area(&d);
        }
        Microfacet { d, sigma }
    }

    /// `D(θm)`.
    pub fn ndf(&self, theta_m: f64) -> f64 {
        interpolate(&self.d, theta_m)
    }

    /// `σ(θ)`.
    pub fn sigma(&self, theta: f64) -> f64 {
        interpolate(&self.sigma, theta)
    }
}

/// Midpoint rule over `θm` of `2π ∫ D cos θm sin θm dθm`, then `D` scaled to one.
fn normalise(d: &mut [f64]) {
    let n = 4 * TABLE;
    let h = FRAC_PI_2 / n as f64;
    let total: f64 = (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) * h;
            interpolate(d, t) * t.cos() * t.sin()
        })
        .sum::<f64>()
        * 2.0
        * PI
        * h;
    if total > 0.0 {
        d.iter_mut().for_each(|x| *x /= total);
    }
}

/// `σ(θ) = ∫ D(m) max(0, ω·m) dm` for every table angle, the azimuth integrated in closed form.
fn projected_area(d: &[f64]) -> Vec<f64> {
    let n = 4 * TABLE;
    let h = FRAC_PI_2 / n as f64;
    let terms: Vec<(f64, f64, f64)> = (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) * h;
            (interpolate(d, t) * t.sin() * h, t.cos(), t.sin())
        })
        .collect();
    (0..TABLE)
        .map(|i| {
            let (c, s) = (angle(i).cos(), angle(i).sin());
            terms.iter().map(|&(w, cm, sm)| w * clipped_cosine_integral(c * cm, s * sm)).sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Beckmann NDF of roughness α, normalised.
    fn beckmann(alpha: f64, t: f64) -> f64 {
        let c = t.cos();
        (-(t.tan() / alpha).powi(2)).exp() / (PI * alpha * alpha * c.powi(4))
    }

    #[test]
    fn the_retroreflection_of_a_microfacet_material_gives_back_its_ndf() {
        let alpha = 0.4;
        let truth = Microfacet {
            d: (0..TABLE).map(|i| beckmann(alpha, angle(i).min(1.5))).collect(),
            sigma: vec![],
        };
        let sigma = projected_area(&truth.d);
        // σ(0) = ∫ D cos = 1 for a normalised NDF.
        assert!((sigma[0] - 1.0).abs() < 2e-3, "σ(0) = {}", sigma[0]);
        let retro = |t: f64| 0.9 * interpolate(&truth.d, t) / (4.0 * interpolate(&sigma, t) * t.cos().max(1e-6));
        let m = Microfacet::from_retro(retro);
        for deg in [0.0, 20.0, 40.0, 60.0, 70.0] {
            let t = f64::to_radians(deg);
            let (got, want) = (m.ndf(t), interpolate(&truth.d, t));
            assert!((got / want - 1.0).abs() < 0.01, "D({deg}°) = {got}, want {want}");
        }
    }

    #[test]
    fn the_clipped_cosine_integral_matches_quadrature() {
        for &(a, b) in &[(0.3, 0.1), (-0.3, 0.1), (0.2, 0.7), (-0.2, 0.7), (0.0, 1.0)] {
            let n = 100_000;
            let q: f64 = (0..n)
                .map(|k| (a + b * ((k as f64 + 0.5) * 2.0 * PI / n as f64).cos()).max(0.0))
                .sum::<f64>()
                * 2.0
                * PI
                / n as f64;
            assert!((clipped_cosine_integral(a, b) - q).abs() < 1e-6, "{a} {b}");
        }
    }
}
