//! Directional-hemispherical reflectance `ρ(θi) = ∫ f_r cosθo dω` over the
//! upper hemisphere (`models.md` §4, Zhang eq. 9), and the energy check.
//!
//! Retro lobes are as narrow as 0.01 rad (exponents of 10⁴), so fixed grids
//! miss them. The integral is nested adaptive Gauss–Kronrod (7/15 points) in
//! `θo` and `Δφ`, with a break at `θo = θi` where both the retro and the
//! mirror lobe peak (their `Δφ` peaks, 0 and π, are interval ends). Written
//! here rather than taken from a crate because the nesting with breakpoints
//! and an absolute error budget is a few lines on top of the rule.

use super::Directions;
use std::f64::consts::{FRAC_PI_2, PI};

/// Absolute error budget of the outer integral; the inner ones get a tenth.
const TOLERANCE: f64 = 1e-6;
const MAX_DEPTH: u32 = 40;

// QUADPACK's 15-point Kronrod nodes and weights, to the digits published.
#[allow(clippy::excessive_precision)]
mod nodes {

    pub const XGK: [f64; 8] = [
        0.991455371120812639206854697526329,
        0.949107912342758524526189684047851,
        0.864864423359769072789712788640926,
        0.741531185599394439863864773280788,
        0.586087235467691130294144845693013,
        0.405845151377397166906606412076961,
        0.207784955007898467600689403773245,
        0.000000000000000000000000000000000,
    ];
    pub const WGK: [f64; 8] = [
        0.022935322010529224963732008058970,
        0.063092092629978553290700663189204,
        0.104790010322250183839876322541518,
        0.140653259715525918745189590510238,
        0.169004726639267902826583426598550,
        0.190350578064785409913256402421014,
        0.204432940075298892414161999234649,
        0.209482141084727828012999174891714,
    ];
    pub const WG: [f64; 4] = [
        0.129484966168869693270611432679082,
        0.279705391489276667901467771423780,
        0.381830050505118944950369775488975,
        0.417959183673469387755102040816327,
    ];
}
use nodes::{WG, WGK, XGK};

/// One Gauss–Kronrod 7/15 step: the Kronrod estimate and its error.
fn gk15(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
    let (c, h) = ((a + b) / 2.0, (b - a) / 2.0);
    let fc = f(c);
    let (mut k, mut g) = (fc * WGK[7], fc * WG[3]);
    for j in 0..7 {
        let x = h * XGK[j];
        let s = f(c - x) + f(c + x);
        k += WGK[j] * s;
        if j % 2 == 1 {
            g += WG[j / 2] * s;
        }
    }
    (k * h, ((k - g) * h).abs())
}

fn adaptive(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64, tol: f64, depth: u32) -> f64 {
    let (k, err) = gk15(f, a, b);
    if err <= tol || depth >= MAX_DEPTH || (b - a) < 1e-12 {
        return k;
    }
    let m = (a + b) / 2.0;
    adaptive(f, a, m, tol / 2.0, depth + 1) + adaptive(f, m, b, tol / 2.0, depth + 1)
}

/// `∫_a^b f` adaptively, to an absolute error of about `tol`.
pub fn integrate(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    adaptive(&mut f, a, b, tol, 0)
}

/// `ρ(θi)` of a BRDF `f_r(directions)`, `θi` in radians.
pub fn dhr(f_r: impl Fn(&Directions) -> f64, theta_i: f64) -> f64 {
    let ring = |theta_o: f64| {
        let (s, c) = theta_o.sin_cos();
        let azimuths = integrate(
            |dphi| f_r(&Directions::from_angles(theta_i, theta_o, dphi)),
            0.0,
            PI,
            TOLERANCE / 10.0,
        );
        2.0 * azimuths * c * s
    };
    let split = theta_i.clamp(0.0, FRAC_PI_2);
    integrate(ring, 0.0, split, TOLERANCE / 2.0) + integrate(ring, split, FRAC_PI_2, TOLERANCE / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Material, ModelId, Param};

    #[test]
    fn lambert_reflects_its_albedo() {
        let m = Material::parse(ModelId::Lambert, "kd=0.73").unwrap();
        for t in [0.0, 30.0, 80.0] {
            assert!((dhr(|d| m.eval(d), f64::to_radians(t)) - 0.73).abs() < 1e-6);
        }
    }

    /// At normal incidence both normalised Phong lobes of RetroPhong (view
    /// form) point along the normal, and `∫ (n+2)/(2π) cos^n θ cosθ dω = 1`:
    /// ρ(0) = kd + k2 + k3, even for a lobe 0.06 rad wide.
    #[test]
    fn sharp_phong_lobes_at_normal_incidence_are_exact() {
        let mut m = Material::parse(ModelId::RetroPhong, "kd=0.2,n=500,k1=0.8,k2=0.1,k3=0.05,k4=3").unwrap();
        m.param = Param::View;
        let rho = dhr(|d| m.eval(d), 0.0);
        assert!((rho - 0.35).abs() < 1e-5, "{rho}");
        // Back form: cos_B = cos(θo/2) at normal incidence, so the retro lobe
        // is `(n+2)/(2π) cos^n(θo/2)`: its integral is a 1-D one, done here by
        // the midpoint rule on a fine grid.
        m.param = Param::Back;
        let steps = 2_000_000;
        let h = std::f64::consts::FRAC_PI_2 / steps as f64;
        let lobe: f64 = (0..steps)
            .map(|k| {
                let t = (k as f64 + 0.5) * h;
                502.0 / (2.0 * PI) * (t / 2.0).cos().powf(500.0) * t.cos() * t.sin() * 2.0 * PI * h
            })
            .sum();
        let rho = dhr(|d| m.eval(d), 0.0);
        assert!((rho - (0.2 + 0.05 + 0.1 * lobe)).abs() < 1e-5, "{rho} vs {}", 0.25 + 0.1 * lobe);
    }
}
