//! `lafortune`: isotropic generalized cosine lobes (Lafortune et al. 1997, as
//! Belcour uses it for retroreflection): a retro lobe (`cxy_r, cz_r ≥ 0`) and
//! another of any kind (`s`: a mirror lobe `cxy_s < 0`, a second retro lobe,
//! a grazing one),
//! `kd/π + Σ_j max(0, cxy_j(lx vx + ly vy) + cz_j lz vz)^n_j`. The retro lobe is
//! already a function of `l·v`-like products, so it has no back/view form.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::{pos, pow, Scalar};
use std::f64::consts::PI;

/// Parameters `kd, cxy_s, cz_s, n_s, cxy_r, cz_r, n_r`.
pub fn eval<T: Scalar>(g: &GeometryTerms, p: &[T]) -> T {
    let lobe = |cxy: T, cz: T, n: T| pow(pos(cxy * g.lv_xy + cz * g.lv_z), n);
    p[0] / PI + lobe(p[1], p[2], p[3]) + lobe(p[4], p[5], p[6])
}

/// `f_r` and its gradient, by hand: with `s = cxy·a + cz·b` and `L = s^n`,
/// `∂L/∂cxy = n·L·a/s`, `∂L/∂cz = n·L·b/s`, `∂L/∂n = L·ln s`. A fit of this
/// model is dominated by the `ln`/`exp` of its two lobes; the hand-written
/// gradient reuses them, where dual numbers carry seven derivatives through
/// every step (measured: a 7 000-sample Jacobian 2.3× faster).
/// `Param` is the fitting interface's: this model has one form.
pub fn value_and_gradient(g: &GeometryTerms, p: &[f64], _: Param, grad: &mut [f64]) -> f64 {
    grad[0] = 1.0 / PI;
    let mut f = p[0] / PI;
    for k in [1usize, 4] {
        let o = &mut grad[k..k + 3];
        let (cxy, cz, n) = (p[k], p[k + 1], p[k + 2]);
        let s = cxy * g.lv_xy + cz * g.lv_z;
        if s <= 0.0 {
            o.fill(0.0);
            continue;
        }
        let ln_s = s.ln();
        let lobe = (n * ln_s).exp();
        let dlobe_ds = n * lobe / s;
        o[0] = dlobe_ds * g.lv_xy;
        o[1] = dlobe_ds * g.lv_z;
        o[2] = lobe * ln_s;
        f += lobe;
    }
    f
}

#[cfg(test)]
mod tests {
    use crate::catalog::assert_hand_gradient;
    use crate::ModelId;

    #[test]
    fn hand_gradient_matches_dual_numbers() {
        let p = [0.4, -1.02, 0.97, 23.0, 1.05, 0.93, 140.0];
        let geometries = [(30.0, 30.0, 0.0), (30.0, 31.0, 5.0), (60.0, 58.0, 180.0), (15.0, 40.0, 90.0)];
        assert_hand_gradient(ModelId::Lafortune, p, &geometries);
    }
}
