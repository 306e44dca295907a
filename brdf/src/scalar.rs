//! The number type the models are written over: `f64` for evaluation, and
//! `num-dual`'s forward-mode dual vectors for the fit's exact Jacobians (one
//! pass gives the value and every partial derivative).

use num_dual::DualNum;

/// `f64` or a dual number over `f64`.
pub trait Scalar: DualNum<f64> + Copy {}

impl<T: DualNum<f64> + Copy> Scalar for T {}

/// `base^e` for a geometric base given as `ln base` (precomputed in
/// `GeometryTerms`) and a parameter exponent; 0 where `base ≤ 0` (`ln_base = −∞`,
/// the lobes' `max(0, ·)^n`), with a zero derivative there.
pub fn pow_geo<T: Scalar>(ln_base: f64, e: T) -> T {
    if ln_base == f64::NEG_INFINITY {
        T::zero()
    } else {
        (e * ln_base).exp()
    }
}

/// `base^e` where both depend on parameters; 0 for `base ≤ 0`.
pub fn pow<T: Scalar>(base: T, e: T) -> T {
    if base.re() <= 0.0 {
        T::zero()
    } else {
        (e * base.ln()).exp()
    }
}

/// `max(0, x)`, keeping the derivative where `x > 0`.
pub fn pos<T: Scalar>(x: T) -> T {
    if x.re() > 0.0 {
        x
    } else {
        T::zero()
    }
}

/// Schlick's Fresnel `r0 + (1 − r0)(1 − u)^5`, `u` clamped to [0, 1].
pub fn schlick<T: Scalar>(u: f64, r0: T) -> T {
    let k = (1.0 - u.clamp(0.0, 1.0)).powi(5);
    r0 * (1.0 - k) + k
}
