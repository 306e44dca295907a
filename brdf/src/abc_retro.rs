//! `abc-retro` (Belcour et al. 2014, §4.B.3; parameter names of Spieringhs
//! Table 7): `kd/π + ar/(1 + br(1 − n·h))^cr · F(v·h; r0) + ab/(1 + bb(1 − c))^cb · F(v'·b; r0)`
//! with `c = cos_B` (back) or `cos_R` (view). Belcour's `(1 − n·h)` is used,
//! not Spieringhs eq. 10's misprint `(1 − o·h)`.
//!
//! `abc-retro-per-lobe` is the same sum with a Fresnel `r0` of each lobe's
//! own (`r0_r`, `r0_b`), as Belcour §4.C describes and ALTA's retro
//! tutorial fits it: a tape's retro lobe (glass beads or prisms behind a
//! cover) and its mirror lobe (the cover) need not share one.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::{pow, schlick, Scalar};
use std::f64::consts::PI;

/// Parameters `kd, r0, ab, bb, cb, ar, br, cr`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T], param: Param) -> T {
    let [kd, r0, ab, bb, cb, ar, br, cr] = [p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]];
    lobes(g, param, kd, [r0, ab, bb, cb], [r0, ar, br, cr])
}

/// Parameters `kd, r0_b, ab, bb, cb, r0_r, ar, br, cr`.
pub fn eval_per_lobe<T: Scalar>(g: &GeometryTerms, p: &[T], param: Param) -> T {
    let [kd, r0_b, ab, bb, cb, r0_r, ar, br, cr] = [p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]];
    lobes(g, param, kd, [r0_b, ab, bb, cb], [r0_r, ar, br, cr])
}

/// `f_r` and its gradient in `kd, r0, ab, bb, cb, ar, br, cr`, by hand:
/// a fit's Jacobian in one pass, without dual numbers (the same operations
/// for the value, so the same bits).
pub fn value_and_gradient(g: &GeometryTerms, p: &[f64], param: Param, grad: &mut [f64]) -> f64 {
    let [kd, r0, ab, bb, cb, ar, br, cr] = [p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]];
    let (specular, ds) = Lobe::of(ar, br, cr, r0, g.nh, g.vh);
    let (retro, dr) = Lobe::of(ab, bb, cb, r0, g.retro_cos(param), g.vpb);
    grad[..8].copy_from_slice(&[1.0 / PI, ds.r0 + dr.r0, dr.a, dr.b, dr.c, ds.a, ds.b, ds.c]);
    kd / PI + specular + retro
}

/// As [`value_and_gradient`] for `kd, r0_b, ab, bb, cb, r0_r, ar, br, cr`.
pub fn value_and_gradient_per_lobe(g: &GeometryTerms, p: &[f64], param: Param, grad: &mut [f64]) -> f64 {
    let [kd, r0_b, ab, bb, cb, r0_r, ar, br, cr] = [p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]];
    let (specular, ds) = Lobe::of(ar, br, cr, r0_r, g.nh, g.vh);
    let (retro, dr) = Lobe::of(ab, bb, cb, r0_b, g.retro_cos(param), g.vpb);
    grad[..9].copy_from_slice(&[1.0 / PI, dr.r0, dr.a, dr.b, dr.c, ds.r0, ds.a, ds.b, ds.c]);
    kd / PI + specular + retro
}

/// A lobe's derivatives in its `a`, `b`, `c` and `r0`.
struct Lobe {
    a: f64,
    b: f64,
    c: f64,
    r0: f64,
}

impl Lobe {
    /// `a/(1 + b(1 − x))^c · F(u; r0)` and its derivatives, as [`lobes`]
    /// computes the value.
    fn of(a: f64, b: f64, c: f64, r0: f64, x: f64, u: f64) -> (f64, Lobe) {
        let base = 1.0 + b * (1.0 - x);
        let ln_base = base.ln();
        // `pow`'s 0 for a base ≤ 0 (none in the box: b ≥ 0, x ≤ 1).
        let power = if base <= 0.0 { 0.0 } else { (c * ln_base).exp() };
        let k = (1.0 - u.clamp(0.0, 1.0)).powi(5);
        let fresnel = r0 * (1.0 - k) + k;
        let value = a / power * fresnel;
        let d = Lobe {
            a: fresnel / power,
            b: -c * (1.0 - x) * value / base,
            c: -ln_base * value,
            r0: a / power * (1.0 - k),
        };
        (value, d)
    }
}

/// The diffuse term and both lobes, each `[r0, a, b, c]`.
fn lobes<T: Scalar>(g: &GeometryTerms, param: Param, kd: T, [r0_b, ab, bb, cb]: [T; 4], [r0_r, ar, br, cr]: [T; 4]) -> T {
    let one = T::one();
    let specular = ar / pow(one + br * (1.0 - g.nh), cr) * schlick(g.vh, r0_r);
    let retro = ab / pow(one + bb * (1.0 - g.retro_cos(param)), cb) * schlick(g.vpb, r0_b);
    kd / PI + specular + retro
}

#[cfg(test)]
mod tests {
    use crate::ModelId;

    /// Both lobes lit, at a mirror and at a retro peak, at grazing and
    /// with the Fresnel term at its ends.
    const GEOMETRIES: [(f64, f64, f64); 6] = [
        (30.0, 31.0, 5.0),
        (60.0, 58.0, 180.0),
        (15.0, 40.0, 90.0),
        (60.0, 60.0, 0.0),
        (85.0, 80.0, 170.0),
        (0.0, 0.0, 0.0),
    ];

    #[test]
    fn hand_gradient_matches_dual_numbers() {
        let p = [0.31, 0.04, 2.5, 120.0, 1.7, 0.8, 40.0, 2.2];
        crate::catalog::assert_hand_gradient(ModelId::AbcRetro, p, &GEOMETRIES);
    }

    #[test]
    fn per_lobe_hand_gradient_matches_dual_numbers() {
        let p = [0.31, 0.6, 2.5, 120.0, 1.7, 0.04, 0.8, 40.0, 2.2];
        crate::catalog::assert_hand_gradient(ModelId::AbcRetroPerLobe, p, &GEOMETRIES);
    }
}
