//! `retro-phong` (Spieringhs et al. 2023, eq. 15, 17, 18; the equations, not
//! the swapped Mitsuba listing of their Appendix A):
//! `kd/π + ks(θi)(n+2)/(2π)·max(0, r(l)·v)^n + kr(θi)(n+2)/(2π)·max(0, l·v)^n`,
//! `kr(θi) = k1(1 − cosθi) + k2`, `ks(θi) = k3·exp(k4(1 − cosθi))`.

use super::frame::{dot, Directions, Param};
use std::f64::consts::PI;

/// Parameters in the order `kd, n, k1, k2, k3, k4`; the retro lobe's cosine is
/// `l·v` in the view parametrization (the published model) or `cos_B`.
pub fn eval(d: &Directions, p: &[f64], param: Param) -> f64 {
    let [kd, n, k1, k2, k3, k4] = p[..] else {
        return f64::NAN;
    };
    let one_minus_cos = 1.0 - d.cos_i();
    let kr = k1 * one_minus_cos + k2;
    let ks = k3 * (k4 * one_minus_cos).exp();
    let norm = (n + 2.0) / (2.0 * PI);
    let lobe = |c: f64| c.max(0.0).powf(n);
    kd / PI + ks * norm * lobe(dot(d.mirror_l(), d.v)) + kr * norm * lobe(d.retro_cos(param))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn retro_peak_and_mirror_peak() {
        let (kd, n, k1, k2, k3, k4) = (0.62, 24.0, 0.158, 0.0415, 0.00133, 5.47);
        let norm = (n + 2.0) / (2.0 * PI);
        // Pure retroreflection at 60°: l·v = 1, mirror lobe r(l)·v = cos 120° < 0.
        let p = [kd, n, k1, k2, k3, k4];
        let d = Directions::from_degrees(60.0, 60.0, 0.0);
        let want = kd / PI + (k1 * 0.5 + k2) * norm;
        assert!((eval(&d, &p, Param::View) - want).abs() < 1e-12);
        // At pure retroreflection the back vector is the normal: cos_B = 1 too.
        assert!((eval(&d, &p, Param::Back) - want).abs() < 1e-12);
        // Mirror direction at 60°: r(l)·v = 1, l·v = cos 120°.
        let d = Directions::from_degrees(60.0, 60.0, 180.0);
        let want = kd / PI + k3 * (k4 * 0.5).exp() * norm;
        assert!((eval(&d, &p, Param::View) - want).abs() < 1e-12);
    }
}
