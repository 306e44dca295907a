//! The models in fixed point, with their parameters converted and bounded at
//! upload: a parameter set whose values could leave the Q31.32 range anywhere
//! in the hemisphere is refused, so evaluation never saturates on it.

use super::fixed::Fx;
use super::geometry::FixedGeometry;
use gonio_shared::{Fault, Field, SanityKind, SanityModel};

/// Largest value any model may reach (sr⁻¹), well inside Q31.32.
const F_MAX: f32 = 1.0e8;
/// `exp(k4·(1 − cos θi))` must stay representable.
const K4_MAX: f32 = 20.0;
/// ABC falloff exponents beyond this are indistinguishable from a delta.
const ABC_EXPONENT_MAX: f32 = 1.0e3;

/// A validated model: its kind and its parameters in Q31.32, in the order
/// of `models.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedModel {
    kind: SanityKind,
    p: [Fx; 8],
}

fn fx(x: f32) -> Result<Fx, Fault> {
    Fx::from_f32(x).ok_or(Fault::InvalidValue(Field::ModelParameter))
}

fn bounded(ok: bool) -> Result<(), Fault> {
    if ok {
        Ok(())
    } else {
        Err(Fault::InvalidValue(Field::ModelParameter))
    }
}

/// Schlick's Fresnel `r0 + (1 − r0)(1 − u)^5`, u clamped to [0, 1].
fn schlick(u: Fx, r0: Fx) -> Fx {
    let w = Fx::ONE.minus(u.clamp(Fx::ZERO, Fx::ONE));
    r0.plus(Fx::ONE.minus(r0).times(w.powi(5)))
}

/// `a / (1 + b(1 − c))^e`.
fn falloff(a: Fx, b: Fx, e: Fx, c: Fx) -> Fx {
    let base = Fx::ONE.plus(b.times(Fx::ONE.minus(c)));
    a.times(base.powf(e.negated()))
}

impl FixedModel {
    /// Converts and bounds an uploaded model (after `SanityModel::validate`).
    pub fn new(m: &SanityModel) -> Result<Self, Fault> {
        m.validate()?;
        let v = m.params();
        match (m.kind(), &v[..]) {
            (SanityKind::Lambert, &[kd]) => bounded(kd <= F_MAX)?,
            (SanityKind::RetroPhong, &[kd, n, k1, k2, k3, k4]) => {
                bounded(k4 <= K4_MAX)?;
                let worst = kd + (k3 * libm::expf(k4) + k1 + k2) * (n + 2.0);
                bounded(worst.is_finite() && worst <= F_MAX)?;
            }
            (SanityKind::AbcRetro { .. }, &[kd, r0, ab, _, cb, ar, _, cr]) => {
                bounded(r0 <= 1.0 && kd + ab + ar <= F_MAX && cb <= ABC_EXPONENT_MAX && cr <= ABC_EXPONENT_MAX)?
            }
            _ => return Err(Fault::InvalidValue(Field::ModelParameter)),
        }
        let mut p = [Fx::ZERO; 8];
        for (x, &y) in p.iter_mut().zip(v.iter()) {
            *x = fx(y)?;
        }
        Ok(FixedModel { kind: m.kind(), p })
    }

    /// `f_r` (sr⁻¹) at a geometry, integers only.
    pub fn eval(&self, g: &FixedGeometry) -> Fx {
        let diffuse = self.p[0].times(Fx::INV_PI);
        match self.kind {
            SanityKind::Lambert => diffuse,
            SanityKind::RetroPhong => {
                let [_, n, k1, k2, k3, k4, _, _] = self.p;
                let one_minus = Fx::ONE.minus(g.cos_i());
                let kr = k1.times(one_minus).plus(k2);
                let ks = k3.times(k4.times(one_minus).exp());
                let norm = n.plus(Fx::from_int(2)).times(Fx::INV_TWO_PI);
                let lobe = |c: Fx| if c.0 > 0 { c.powf(n) } else { Fx::ZERO };
                let spec = ks.times(norm).times(lobe(g.mirror_dot_v()));
                let retro = kr.times(norm).times(lobe(g.l_dot_v()));
                diffuse.plus(spec).plus(retro)
            }
            SanityKind::AbcRetro { back } => {
                let [_, r0, ab, bb, cb, ar, br, cr] = self.p;
                let spec = falloff(ar, br, cr, g.half()[2]).times(schlick(g.v_dot_half(), r0));
                let retro = falloff(ab, bb, cb, g.retro_cos(back)).times(schlick(g.reflected_dot_back(), r0));
                diffuse.plus(spec).plus(retro)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_shared::Geometry;
    use proptest::prelude::*;

    fn param() -> impl Strategy<Value = f32> {
        prop_oneof![0f32..1.0, 0f32..100.0, 0f32..1.0e5, Just(0.0), Just(1.0e5), any::<f32>()]
    }

    fn model() -> impl Strategy<Value = SanityModel> {
        (0u8..3, proptest::collection::vec(param(), 8), any::<bool>()).prop_map(|(k, p, back)| match k {
            0 => SanityModel::Lambert { kd: p[0] },
            1 => SanityModel::RetroPhong {
                kd: p[0],
                n: p[1],
                k1: p[2],
                k2: p[3],
                k3: p[4],
                k4: p[5],
            },
            _ => SanityModel::AbcRetro {
                kd: p[0],
                r0: p[1],
                ab: p[2],
                bb: p[3],
                cb: p[4],
                ar: p[5],
                br: p[6],
                cr: p[7],
                back,
            },
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Debug builds check every integer operation for overflow: no panic
        /// here means no wrapped value for any accepted model and any angles.
        #[test]
        fn accepted_models_never_panic_wrap_or_go_negative(m in model(), ti in any::<f32>(), to in any::<f32>(), dp in any::<f32>(),
                                                            a in -720f32..720.0, b in -720f32..720.0) {
            if let Ok(fm) = FixedModel::new(&m) {
                for g in [Geometry::new(ti, to, dp), Geometry::new(a, b, a - b), Geometry::new(a.abs() % 90.0, b.abs() % 90.0, a)] {
                    if let Some(fg) = FixedGeometry::from_degrees(&g) {
                        prop_assert!(fm.eval(&fg).0 >= 0, "{m:?} at {g:?}");
                    }
                }
            }
        }

        #[test]
        fn unrepresentable_parameters_are_refused(k4 in 20.5f32..1.0e5) {
            let m = SanityModel::RetroPhong { kd: 0.1, n: 10.0, k1: 0.1, k2: 0.1, k3: 0.1, k4 };
            prop_assert_eq!(FixedModel::new(&m), Err(Fault::InvalidValue(Field::ModelParameter)));
        }
    }

    #[test]
    fn non_finite_parameters_are_refused() {
        for bad in [f32::NAN, f32::INFINITY, -1.0] {
            assert!(FixedModel::new(&SanityModel::Lambert { kd: bad }).is_err());
        }
    }
}
