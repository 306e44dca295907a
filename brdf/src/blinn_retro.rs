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
