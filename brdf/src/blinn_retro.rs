//! `blinn-retro` (Spieringhs eq. 8–9, Table 7):
//! `kd/π + max(0, n·h)^alpha_r + max(0, c)^alpha_b`. As published, the lobes
//! have no amplitude of their own: their width is the only free parameter.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::{pow_geo, Scalar};
use std::f64::consts::PI;

/// Parameters `kd, alpha_r, alpha_b`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T], param: Param) -> T {
    let [kd, alpha_r, alpha_b] = [p[0], p[1], p[2]];
    kd / PI + pow_geo(g.ln_nh, alpha_r) + pow_geo(g.retro_ln(param), alpha_b)
}

/// `f_r` and its gradient in `kd, alpha_r, alpha_b`, by hand: a fit's
/// Jacobian in one pass, without dual numbers (the same operations for the
/// value, so the same bits).
pub fn value_and_gradient(g: &GeometryTerms, p: &[f64], param: Param, grad: &mut [f64]) -> f64 {
    let [kd, alpha_r, alpha_b] = [p[0], p[1], p[2]];
    // `base^e` and its derivative in `e`, both 0 where the base is not positive.
    let lobe = |ln_base: f64, e: f64| {
        let l = pow_geo(ln_base, e);
        (l, if l == 0.0 { 0.0 } else { l * ln_base })
    };
    let (mirror, dm) = lobe(g.ln_nh, alpha_r);
    let (retro, dr) = lobe(g.retro_ln(param), alpha_b);
    grad[..3].copy_from_slice(&[1.0 / PI, dm, dr]);
    kd / PI + mirror + retro
}

#[cfg(test)]
mod tests {
    #[test]
    fn hand_gradient_matches_dual_numbers() {
        // Both lobes lit, the mirror lobe's cosine at 0, at the retro peak.
        let geometries = [(30.0, 31.0, 5.0), (60.0, 58.0, 180.0), (89.0, 89.0, 0.0), (60.0, 60.0, 0.0)];
        crate::catalog::assert_hand_gradient(crate::ModelId::BlinnRetro, [0.3, 80.0, 400.0], &geometries);
    }
}
