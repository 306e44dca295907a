//! `beckmann-retro` (Belcour et al. 2014; Spieringhs Table 7):
//! `kd/π + D_b(c)·F(v'·b; r0)·G(l,v)/(4(n·l)(n·v))` with the Beckmann
//! distribution of the retro cosine `D_b(c) = exp((c² − 1)/(α²c²))/(π α² c⁴)`
//! and Smith–Beckmann shadowing in Walter et al.'s rational approximation.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::{schlick, Scalar};
use std::f64::consts::PI;

/// Below this retro cosine `D_b` underflows to 0 for every α of the bounds.
const MIN_C: f64 = 1e-4;

/// Parameters `kd, alpha, r0`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T], param: Param) -> T {
    let [kd, alpha, r0] = [p[0], p[1], p[2]];
    let c = g.retro_cos(param);
    let diffuse = kd / PI;
    if c < MIN_C || g.cos_i <= 0.0 || g.cos_o <= 0.0 {
        return diffuse;
    }
    let a2 = alpha * alpha;
    let c2 = c * c;
    let d = ((a2 * c2).recip() * (c2 - 1.0)).exp() / (a2 * (PI * c2 * c2));
    let shadowing = smith_g1(g.tan_i, alpha) * smith_g1(g.tan_o, alpha);
    diffuse + d * schlick(g.vpb, r0) * shadowing / (4.0 * g.cos_i * g.cos_o)
}

/// `G1 = (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²)` for `a = 1/(α tanθ) < 1.6`, else 1.
fn smith_g1<T: Scalar>(tan: f64, alpha: T) -> T {
    let at = alpha * tan;
    // a < 1.6  ⇔  α tanθ > 1/1.6 (α, tanθ ≥ 0).
    if at.re() <= 1.0 / 1.6 {
        return T::one();
    }
    let a = at.recip();
    (a * 3.535 + a * a * 2.181) / (a * 2.276 + a * a * 2.577 + 1.0)
}

/// `f_r` and its gradient in `kd, alpha, r0`, by hand: a fit's Jacobian in
/// one pass, without dual numbers (the same operations for the value, so
/// the same bits).
pub fn value_and_gradient(g: &GeometryTerms, p: &[f64], param: Param, grad: &mut [f64]) -> f64 {
    let [kd, alpha, r0] = [p[0], p[1], p[2]];
    let c = g.retro_cos(param);
    let diffuse = kd / PI;
    grad[..3].copy_from_slice(&[1.0 / PI, 0.0, 0.0]);
    if c < MIN_C || g.cos_i <= 0.0 || g.cos_o <= 0.0 {
        return diffuse;
    }
    let a2 = alpha * alpha;
    let c2 = c * c;
    let d = ((a2 * c2).recip() * (c2 - 1.0)).exp() / (a2 * (PI * c2 * c2));
    // d ln D / dα = −2(c² − 1)/(α³c²) − 2/α.
    let dd = d * (-2.0 * (c2 - 1.0) / (a2 * alpha * c2) - 2.0 / alpha);
    let (gi, dgi) = smith_g1_and_slope(g.tan_i, alpha);
    let (go, dgo) = smith_g1_and_slope(g.tan_o, alpha);
    let shadowing = gi * go;
    let k = (1.0 - g.vpb.clamp(0.0, 1.0)).powi(5);
    let fresnel = r0 * (1.0 - k) + k;
    let over = 4.0 * g.cos_i * g.cos_o;
    grad[1] = fresnel * (dd * shadowing + d * (dgi * go + gi * dgo)) / over;
    grad[2] = d * (1.0 - k) * shadowing / over;
    diffuse + d * fresnel * shadowing / over
}

/// [`smith_g1`] and its derivative in α.
fn smith_g1_and_slope(tan: f64, alpha: f64) -> (f64, f64) {
    let at = alpha * tan;
    if at <= 1.0 / 1.6 {
        return (1.0, 0.0);
    }
    let a = at.recip();
    let (num, den) = (a * 3.535 + a * a * 2.181, a * 2.276 + a * a * 2.577 + 1.0);
    let slope_a = ((3.535 + 2.0 * 2.181 * a) * den - num * (2.276 + 2.0 * 2.577 * a)) / (den * den);
    // a = 1/(α tanθ): da/dα = −a/α.
    (num / den, slope_a * (-a / alpha))
}

#[cfg(test)]
mod tests {
    #[test]
    fn hand_gradient_matches_dual_numbers() {
        // The lobe lit and shadowed, dark below its cosine's floor, at grazing.
        let geometries = [
            (30.0, 31.0, 5.0),
            (60.0, 58.0, 0.0),
            (15.0, 40.0, 90.0),
            (80.0, 75.0, 3.0),
            (60.0, 60.0, 180.0),
        ];
        for alpha in [0.08, 0.35, 1.2] {
            crate::catalog::assert_hand_gradient(crate::ModelId::BeckmannRetro, [0.3, alpha, 0.06], &geometries);
        }
    }
}
