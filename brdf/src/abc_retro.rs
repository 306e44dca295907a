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

/// The diffuse term and both lobes, each `[r0, a, b, c]`.
fn lobes<T: Scalar>(g: &GeometryTerms, param: Param, kd: T, [r0_b, ab, bb, cb]: [T; 4], [r0_r, ar, br, cr]: [T; 4]) -> T {
    let one = T::one();
    let specular = ar / pow(one + br * (1.0 - g.nh), cr) * schlick(g.vh, r0_r);
    let retro = ab / pow(one + bb * (1.0 - g.retro_cos(param)), cb) * schlick(g.vpb, r0_b);
    kd / PI + specular + retro
}
