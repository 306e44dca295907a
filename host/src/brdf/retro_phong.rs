//! `retro-phong` (Spieringhs et al. 2023, eq. 15, 17, 18; the equations, not
//! the swapped Mitsuba listing of their Appendix A):
//! `kd/π + ks(θi)(n+2)/(2π)·max(0, r(l)·v)^n + kr(θi)(n+2)/(2π)·max(0, l·v)^n`,
//! `kr(θi) = k1(1 − cosθi) + k2`, `ks(θi) = k3·exp(k4(1 − cosθi))`.

use super::frame::{dot, Directions};
use std::f64::consts::PI;

pub fn eval(d: &Directions, kd: f64, n: f64, k1: f64, k2: f64, k3: f64, k4: f64) -> f64 {
    let one_minus_cos = 1.0 - d.cos_i();
    let kr = k1 * one_minus_cos + k2;
    let ks = k3 * (k4 * one_minus_cos).exp();
    let norm = (n + 2.0) / (2.0 * PI);
    let lobe = |c: f64| c.max(0.0).powf(n);
    kd / PI + ks * norm * lobe(dot(d.mirror_l(), d.v)) + kr * norm * lobe(dot(d.l, d.v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn retro_peak_and_mirror_peak() {
        let (kd, n, k1, k2, k3, k4) = (0.62, 24.0, 0.158, 0.0415, 0.00133, 5.47);
        let norm = (n + 2.0) / (2.0 * PI);
        // Pure retroreflection at 60°: l·v = 1, mirror lobe r(l)·v = cos 120° < 0.
        let d = Directions::from_degrees(60.0, 60.0, 0.0);
        let want = kd / PI + (k1 * 0.5 + k2) * norm;
        assert!((eval(&d, kd, n, k1, k2, k3, k4) - want).abs() < 1e-12);
        // Mirror direction at 60°: r(l)·v = 1, l·v = cos 120°.
        let d = Directions::from_degrees(60.0, 60.0, 180.0);
        let want = kd / PI + k3 * (k4 * 0.5).exp() * norm;
        assert!((eval(&d, kd, n, k1, k2, k3, k4) - want).abs() < 1e-12);
    }
}
