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
