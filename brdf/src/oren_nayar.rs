//! `oren-nayar` (qualitative model, as Spieringhs benchmarks it):
//! `ρ/π·(A + B·max(0, cosΔφ)·sin(max(θi,θo))·tan(min(θi,θo)))`,
//! `A = 1 − 0.5σ²/(σ² + 0.33)`, `B = 0.45σ²/(σ² + 0.09)`, σ in radians.

use super::geometry::GeometryTerms;
use super::scalar::Scalar;
use std::f64::consts::PI;

/// Parameters `rho, sigma`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T]) -> T {
    let [rho, sigma] = [p[0], p[1]];
    let s2 = sigma * sigma;
    let a = -(s2 * 0.5 / (s2 + 0.33)) + 1.0;
    let b = s2 * 0.45 / (s2 + 0.09);
    rho / PI * (a + b * g.oren_nayar)
}
