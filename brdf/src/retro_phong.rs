//! `retro-phong` (Spieringhs et al. 2023, eq. 15, 17, 18; the equations, not
//! the swapped Mitsuba listing of their Appendix A):
//! `kd/π + ks(θi)(n+2)/(2π)·max(0, r(l)·v)^n + kr(θi)(n+2)/(2π)·max(0, c)^n`,
//! `kr(θi) = k1(1 − cosθi) + k2`, `ks(θi) = k3·exp(k4(1 − cosθi))`.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::{pow_geo, Scalar};
use std::f64::consts::PI;

/// Parameters `kd, n, k1, k2, k3, k4`; `c = l·v` in the view parametrization
/// (the published model) or `cos_B`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T], param: Param) -> T {
    let [kd, n, k1, k2, k3, k4] = [p[0], p[1], p[2], p[3], p[4], p[5]];
    let one_minus_cos = 1.0 - g.cos_i;
    let kr = k1 * one_minus_cos + k2;
    let ks = k3 * (k4 * one_minus_cos).exp();
    let norm = (n + 2.0) / (2.0 * PI);
    kd / PI + ks * norm * pow_geo(g.ln_mirror, n) + kr * norm * pow_geo(g.retro_ln(param), n)
}

/// `f_r` and its gradient, by hand: with `N = (n+2)/(2π)` and the lobes
/// `M = (r(l)·v)^n`, `R = c^n`, `∂f/∂n = ks(M/2π + N·M·ln r(l)·v) +
/// kr(R/2π + N·R·ln c)` and the coefficients' derivatives are the lobes'
/// factors. As for lafortune: the three `exp` are computed once, where dual
/// numbers carry six derivatives through each (measured in the global
/// search's race, where retro-phong fits spend their time).
pub fn value_and_gradient(g: &GeometryTerms, p: &[f64], param: Param, grad: &mut [f64]) -> f64 {
    let [kd, n, k1, k2, k3, k4] = [p[0], p[1], p[2], p[3], p[4], p[5]];
    let one_minus_cos = 1.0 - g.cos_i;
    let kr = k1 * one_minus_cos + k2;
    let e = (k4 * one_minus_cos).exp();
    let ks = k3 * e;
    let norm = (n + 2.0) / (2.0 * PI);
    // A lobe and its derivative in n; both 0 where its cosine is not positive.
    let lobe = |ln_base: f64| {
        let l = pow_geo(ln_base, n);
        (l, if l == 0.0 { 0.0 } else { l / (2.0 * PI) + norm * l * ln_base })
    };
    let (m, dm) = lobe(g.ln_mirror);
    let (r, dr) = lobe(g.retro_ln(param));
    grad[0] = 1.0 / PI;
    grad[1] = ks * dm + kr * dr;
    grad[2] = one_minus_cos * norm * r;
    grad[3] = norm * r;
    grad[4] = e * norm * m;
    grad[5] = ks * one_minus_cos * norm * m;
    kd / PI + ks * norm * m + kr * norm * r
}

/// Spieringhs §8's energy check: `kd + ks(θi) + kr(θi)`, below 1 when energy is conserved.
pub fn energy_sum(p: &[f64], cos_i: f64) -> f64 {
    let one_minus_cos = 1.0 - cos_i;
    p[0] + p[4] * (p[5] * one_minus_cos).exp() + p[2] * one_minus_cos + p[3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Directions;

    #[test]
    fn hand_gradient_matches_dual_numbers() {
        let p = [0.62, 24.0, 0.158, 0.0415, 0.00133, 5.47];
        // Both lobes lit; the mirror lobe dark (its cosine negative); at the retro peak.
        let geometries = [(30.0, 31.0, 5.0), (60.0, 58.0, 180.0), (15.0, 40.0, 90.0), (60.0, 60.0, 0.0)];
        crate::catalog::assert_hand_gradient(crate::ModelId::RetroPhong, p, &geometries);
    }

    #[test]
    fn retro_peak_and_mirror_peak() {
        let (kd, n, k1, k2, k3, k4) = (0.62, 24.0, 0.158, 0.0415, 0.00133, 5.47);
        let norm = (n + 2.0) / (2.0 * PI);
        let p = [kd, n, k1, k2, k3, k4];
        let at = |ti, to, dp| GeometryTerms::new(&Directions::from_degrees(ti, to, dp));
        // Pure retroreflection at 60°: l·v = 1, mirror lobe r(l)·v = cos 120° < 0.
        let want = kd / PI + (k1 * 0.5 + k2) * norm;
        assert!((eval(&at(60.0, 60.0, 0.0), &p, Param::View) - want).abs() < 1e-12);
        // At pure retroreflection the back vector is the normal: cos_B = 1 too.
        assert!((eval(&at(60.0, 60.0, 0.0), &p, Param::Back) - want).abs() < 1e-12);
        // Mirror direction at 60°: r(l)·v = 1, l·v = cos 120°.
        let want = kd / PI + k3 * (k4 * 0.5).exp() * norm;
        assert!((eval(&at(60.0, 60.0, 180.0), &p, Param::View) - want).abs() < 1e-12);
    }
}
