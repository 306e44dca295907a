//! `abc-retro` (Belcour et al. 2014, §4.B.3; parameter names of Spieringhs
//! Table 7): `kd/π + ar/(1 + br(1 − n·h))^cr · F(v·h; r0) + ab/(1 + bb(1 − c))^cb · F(v'·b; r0)`
//! with `c = cos_B` (back) or `cos_R` (view). Belcour's `(1 − n·h)` is used,
//! not Spieringhs eq. 10's misprint `(1 − o·h)`.

use super::frame::{dot, schlick, Directions, Param};
use std::f64::consts::PI;

/// Parameters in the order `kd, r0, ab, bb, cb, ar, br, cr`.
pub fn eval(d: &Directions, p: &[f64], param: Param) -> f64 {
    let [kd, r0, ab, bb, cb, ar, br, cr] = p[..] else {
        return f64::NAN;
    };
    let h = d.half();
    let b = d.back();
    let specular = ar / (1.0 + br * (1.0 - h[2])).powf(cr) * schlick(dot(d.v, h), r0);
    let c = d.retro_cos(param);
    let retro = ab / (1.0 + bb * (1.0 - c)).powf(cb) * schlick(dot(d.reflected_v(), b), r0);
    kd / PI + specular + retro
}
