//! `five-param` (Zhang et al., eq. 1–5): a Torrance–Sparrow model with an
//! elliptical facet distribution and an exponential Fresnel substitute,
//! `kb·D(α)·exp(b(1 − cosγ)^a)·G/cosθo + kd`,
//! `D(α) = kr²cosα/(1 + (kr² − 1)cos²α)` (the text's `cos²α`, not eq. 5's
//! misprint). `kd` is not divided by π. `G/cosθo` depends on the geometry
//! only and is precomputed in [`GeometryTerms`].

use super::geometry::GeometryTerms;
use super::scalar::{pow_geo, Scalar};

/// Parameters `kb, kr, a, b, kd`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T]) -> T {
    let [kb, kr, a, b, kd] = [p[0], p[1], p[2], p[3], p[4]];
    let kr2 = kr * kr;
    let cos_a = g.nh;
    let d = kr2 * cos_a / ((kr2 - 1.0) * (cos_a * cos_a) + 1.0);
    let fresnel = (b * pow_geo(g.ln_one_minus_cos_gamma, a)).exp();
    kb * d * fresnel * g.zhang_g_over_cos_o + kd
}
