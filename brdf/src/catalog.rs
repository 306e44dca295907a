//! The models of `docs/models.md` §2 as the host knows them: ids and
//! parameter names from the shared model table (CLI and JSON contract), the
//! bounds a fit searches within, and the dispatch to each model's evaluation.

use super::frame::Param;
use super::geometry::GeometryTerms;
use super::scalar::Scalar;
use super::{abc_retro, beckmann_retro, blinn_retro, five_param, lafortune, lambert, oren_nayar, retro_phong};
use anyhow::{Context, Result};
use gonio_shared::{ModelSpec, MODELS};
use serde::{Deserialize, Serialize};

/// `f_r` at a geometry, writing its gradient in every parameter into the slice.
pub type HandGradient = fn(&GeometryTerms, &[f64], Param, &mut [f64]) -> f64;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelId {
    Lambert,
    RetroPhong,
    AbcRetro,
    AbcRetroPerLobe,
    BeckmannRetro,
    BlinnRetro,
    Lafortune,
    OrenNayar,
    FiveParam,
}

/// How a global search spreads its trials over a parameter's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spread {
    /// Uniform in the value.
    Linear,
    /// Uniform in the logarithm (`lo > 0`): exponents, widths.
    Log,
    /// `lo + (hi − lo)·u³`: amplitudes that range over decades down to 0.
    Amplitude,
}

/// The range a fit keeps a parameter in: physical limits (a reflectance is
/// not negative, a Fresnel `r0` is at most 1) and generous ones elsewhere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub lo: f64,
    pub hi: f64,
    pub spread: Spread,
    /// The model is proportional to this parameter (a reflectance, a lobe's
    /// amplitude): its upper bound follows the data's scale, so data in
    /// relative units (ALTA files often are) fit in the box.
    pub scales: bool,
    /// Which edges (low, high) are only a default, not a physical limit: a
    /// fit that ends on one widens the box there and goes on
    /// (`Bound::widened`). Zero under a quantity that cannot be negative,
    /// 1 over a Fresnel `r0`, π/2 over a roughness angle, an exponent's
    /// floor of 1 stay.
    pub open: (bool, bool),
}

/// A box whose high edge is a default and whose low edge a limit.
const fn b(lo: f64, hi: f64, spread: Spread) -> Bound {
    Bound {
        lo,
        hi,
        spread,
        scales: false,
        open: (false, true),
    }
}

/// An amplitude: `b` whose upper bound follows the data's scale.
const fn a(lo: f64, hi: f64, spread: Spread) -> Bound {
    Bound {
        scales: true,
        ..b(lo, hi, spread)
    }
}

/// A box held at both edges by physics.
const fn held(lo: f64, hi: f64, spread: Spread) -> Bound {
    Bound {
        open: (false, false),
        ..b(lo, hi, spread)
    }
}

/// A box open at both edges (a signed shape parameter).
const fn free(lo: f64, hi: f64, spread: Spread) -> Bound {
    Bound {
        open: (true, true),
        ..b(lo, hi, spread)
    }
}

impl Bound {
    /// How far a box grows at an open edge, per widening.
    pub const GROWTH: f64 = 10.0;

    /// The box widened at its open edges among `(low, high)`: ×10 in width
    /// (×10 beyond the edge on a log spread); `None` where neither is open.
    pub fn widened(&self, (low, high): (bool, bool)) -> Option<Bound> {
        let (low, high) = (low && self.open.0, high && self.open.1);
        if !(low || high) {
            return None;
        }
        let grow = Self::GROWTH - 1.0;
        let (mut lo, mut hi) = (self.lo, self.hi);
        match self.spread {
            Spread::Log if lo > 0.0 => {
                if low {
                    lo /= Self::GROWTH;
                }
                if high {
                    hi *= Self::GROWTH;
                }
            }
            _ => {
                let width = hi - lo;
                if low {
                    lo -= grow * width;
                }
                if high {
                    hi += grow * width;
                }
            }
        }
        Some(Bound { lo, hi, ..*self })
    }
}

/// The median `f_r` (sr⁻¹) the default boxes are written for: a calibrated
/// BRDF's median is a diffuse level, below 1 sr⁻¹ (a white Lambertian
/// surface is 0.32), however high its lobes reach. Data whose median is
/// higher are in other units (ALTA files of uncalibrated measurements):
/// every amplitude's upper bound is multiplied by `median /
/// REFERENCE_MEDIAN_SR` (`ModelId::bounds_for`).
pub const REFERENCE_MEDIAN_SR: f64 = 1.0;

use Spread::{Amplitude as A, Linear as L, Log as G};

// The default boxes hold every published fit of the three papers (the
// largest values in brackets). Spieringhs et al. 2023 Table 7 (road markings
// 1–3; Tables 3–5 repeat RetroPhong's): RetroPhong kd ≤ 0.70, n 24–68,
// k1 ≤ 0.18, k2 ≤ 0.073, k3 ≤ 0.0057, k4 3.4–8.74; ABC-Retro kd ≤ 0.75,
// R0 ≤ 0.14, A_b ≤ 6.7, B_b ≤ 37.8, C_b ≤ 1.51, A_r ≤ 3.58, B_r ≤ 22.9,
// C_r ≤ 6.97; Beckmann-Retro kd ≤ 1.0, α 8.2–1.61e3, R0 ≤ 1.0;
// Blinn-Retro kd ≤ 0.99, α_b ≤ 6.72e3, α_r ≤ 1.65e4; Oren–Nayar ρ ≤ 0.47,
// σ ≤ 1.26 rad. Zhang et al. §5 (five-param, six surfaces): kb ≤ 5.71,
// kr 0.478–16.1, a 0.452–15.6, b −58.7 to −18.3, kd ≤ 2.27 (polyimide
// film: hence kd up to 4). Belcour et al. 2014 publish no parameters (Table
// 1 holds L² errors); their fits run in ALTA, whose plugins leave the box
// to the user: the ABC lobe exponents (C_b, C_r) are opened to 100 (a fit
// of a measured tape in ALTA's data ran into C_r = 20). Blinn's exponents
// stay ≥ 1: below it a lobe is broader than a cosine, which the diffuse term
// already is; a fit that ends there says so (`at_bound`), and `--bounds`
// opens the box (the local fit from the box's centre is 3× slower with it
// opened to 0.01, fit-bench).
const KD: Bound = a(0.0, 4.0, L);
const EXPONENT: Bound = b(1.0, 1e4, G);
const RETRO_PHONG: &[Bound] = &[
    KD,
    EXPONENT,
    a(0.0, 10.0, A),
    a(0.0, 10.0, A),
    a(0.0, 10.0, A),
    free(-20.0, 20.0, L),
];
/// A Fresnel `r0`, held in [0, 1].
const R0: Bound = held(0.0, 1.0, L);
/// An ABC lobe's `a` (amplitude), `b` and `c`.
const ABC_A: Bound = a(0.0, 100.0, A);
const ABC_B: Bound = b(0.0, 1e4, A);
const ABC_C: Bound = b(0.0, 100.0, A);
const ABC_RETRO: &[Bound] = &[KD, R0, ABC_A, ABC_B, ABC_C, ABC_A, ABC_B, ABC_C];
const ABC_RETRO_PER_LOBE: &[Bound] = &[KD, R0, ABC_A, ABC_B, ABC_C, R0, ABC_A, ABC_B, ABC_C];
const BECKMANN_RETRO: &[Bound] = &[KD, b(1e-3, 1e4, G), held(0.0, 1.0, L)];
const BLINN_RETRO: &[Bound] = &[KD, b(1.0, 1e6, G), b(1.0, 1e6, G)];
// Lafortune's lobe r is the retro lobe (cxy_r, cz_r ≥ 0: its peak at
// l = v); lobe s is the other one, of any kind: a mirror lobe (cxy_s < 0), a
// second, wider retro lobe (a tape's halo about its core), or a lobe at
// grazing angles (cz_s < 0). ALTA's fit, unbounded, finds each of these on
// the misfit materials (fit-bench alta); a box held at cxy_s ≤ 0, cz_s ≥ 0
// kept the fit 1.07–1.29× above ALTA's RMSE there. cxy_s spans both signs
// from the start; cz_s starts at 0 and widens below it where a fit ends
// there: a search box of [−2, 2] in both from the start lost lafortune's
// own retro lobe in 37 of 60 σ-weighted fits of 500 samples (fit-bench gof),
// this one in 2.
const LAFORTUNE: &[Bound] = &[
    KD,
    free(-2.0, 2.0, L),
    free(0.0, 2.0, L),
    EXPONENT,
    b(0.0, 2.0, L),
    b(0.0, 2.0, L),
    EXPONENT,
];
const OREN_NAYAR: &[Bound] = &[KD, held(0.0, std::f64::consts::FRAC_PI_2, L)];
const FIVE_PARAM: &[Bound] = &[a(0.0, 100.0, A), b(0.01, 100.0, G), b(0.01, 20.0, G), free(-100.0, 10.0, L), KD];

impl ModelId {
    pub const ALL: [ModelId; 9] = [
        ModelId::Lambert,
        ModelId::RetroPhong,
        ModelId::AbcRetro,
        ModelId::AbcRetroPerLobe,
        ModelId::BeckmannRetro,
        ModelId::BlinnRetro,
        ModelId::Lafortune,
        ModelId::OrenNayar,
        ModelId::FiveParam,
    ];

    /// Its row of the model table (`gonio_shared::models`), which `ALL`
    /// follows in order.
    pub fn spec(self) -> &'static ModelSpec {
        MODELS[self as usize]
    }

    pub fn name(self) -> &'static str {
        self.spec().id
    }

    pub fn param_names(self) -> &'static [&'static str] {
        self.spec().params
    }

    /// The search box for data whose median `f_r` is `median` (sr⁻¹): the
    /// defaults, with the amplitudes' upper bounds scaled up where the data
    /// exceed [`REFERENCE_MEDIAN_SR`].
    pub fn bounds_for(self, median: f64) -> Vec<Bound> {
        let k = if median.is_finite() {
            (median / REFERENCE_MEDIAN_SR).max(1.0)
        } else {
            1.0
        };
        self.bounds()
            .iter()
            .map(|b| if b.scales { Bound { hi: b.hi * k, ..*b } } else { *b })
            .collect()
    }

    /// Search bounds, in the order of [`ModelId::param_names`].
    pub fn bounds(self) -> &'static [Bound] {
        match self {
            ModelId::Lambert => &[KD],
            ModelId::RetroPhong => RETRO_PHONG,
            ModelId::AbcRetro => ABC_RETRO,
            ModelId::AbcRetroPerLobe => ABC_RETRO_PER_LOBE,
            ModelId::BeckmannRetro => BECKMANN_RETRO,
            ModelId::BlinnRetro => BLINN_RETRO,
            ModelId::Lafortune => LAFORTUNE,
            ModelId::OrenNayar => OREN_NAYAR,
            ModelId::FiveParam => FIVE_PARAM,
        }
    }

    /// Whether the model has a retro lobe whose cosine is `cos_B` or `cos_R`.
    pub fn has_retro_cosine(self) -> bool {
        matches!(
            self,
            ModelId::RetroPhong | ModelId::AbcRetro | ModelId::AbcRetroPerLobe | ModelId::BeckmannRetro | ModelId::BlinnRetro
        )
    }

    pub fn parse(s: &str) -> Result<Self> {
        ModelId::ALL.into_iter().find(|m| m.name() == s).with_context(|| {
            let valid: Vec<_> = ModelId::ALL.iter().map(|m| m.name()).collect();
            format!("unknown model `{s}`; valid models: {}", valid.join(", "))
        })
    }

    /// Index of a parameter name, or an error listing the valid names.
    pub fn param_index(self, name: &str) -> Result<usize> {
        let names = self.param_names();
        names
            .iter()
            .position(|n| *n == name)
            .with_context(|| format!("unknown parameter `{name}` for {}; valid: {}", self.name(), names.join(", ")))
    }

    /// A hand-written `f_r` and gradient in every parameter, where one beats
    /// dual numbers by enough to matter in a fit.
    pub fn hand_gradient(self) -> Option<HandGradient> {
        match self {
            ModelId::Lafortune => Some(lafortune::value_and_gradient),
            ModelId::RetroPhong => Some(retro_phong::value_and_gradient),
            ModelId::AbcRetro => Some(abc_retro::value_and_gradient),
            ModelId::AbcRetroPerLobe => Some(abc_retro::value_and_gradient_per_lobe),
            ModelId::BeckmannRetro => Some(beckmann_retro::value_and_gradient),
            ModelId::BlinnRetro => Some(blinn_retro::value_and_gradient),
            _ => None,
        }
    }

    /// `f_r` (sr⁻¹) at one geometry; `p` holds every parameter in order.
    pub fn eval<T: Scalar>(self, g: &GeometryTerms, p: &[T], param: Param) -> T {
        match self {
            ModelId::Lambert => lambert::eval(p),
            ModelId::RetroPhong => retro_phong::eval(g, p, param),
            ModelId::AbcRetro => abc_retro::eval(g, p, param),
            ModelId::AbcRetroPerLobe => abc_retro::eval_per_lobe(g, p, param),
            ModelId::BeckmannRetro => beckmann_retro::eval(g, p, param),
            ModelId::BlinnRetro => blinn_retro::eval(g, p, param),
            ModelId::Lafortune => lafortune::eval(g, p),
            ModelId::OrenNayar => oren_nayar::eval(g, p),
            ModelId::FiveParam => five_param::eval(g, p),
        }
    }
}

/// Asserts that `model`'s hand-written gradient gives the value and the
/// derivatives that dual numbers give through its `eval`, at `p`, every one
/// of `geometries` (θi, θo, Δφ in degrees) and both retro cosines.
#[cfg(test)]
pub(crate) fn assert_hand_gradient<const N: usize>(model: ModelId, p: [f64; N], geometries: &[(f64, f64, f64)]) {
    use num_dual::DualSVec64;
    let hand = model.hand_gradient().expect("a hand-written gradient");
    for &(ti, to, dp) in geometries {
        let g = GeometryTerms::new(&super::Directions::from_degrees(ti, to, dp));
        for param in [Param::View, Param::Back] {
            let duals: Vec<DualSVec64<N>> = p.iter().enumerate().map(|(i, &v)| DualSVec64::from_re(v).derivative(i)).collect();
            let want = model.eval(&g, &duals, param);
            let mut grad = [0.0; N];
            let f = hand(&g, &p, param, &mut grad);
            assert!(
                (f - want.re).abs() <= 1e-12 * want.re.abs(),
                "{ti} {to} {dp} {param:?}: {f} vs {}",
                want.re
            );
            let d = want.eps.unwrap_generic(nalgebra::Const::<N>, nalgebra::U1);
            for i in 0..N {
                assert!(
                    (grad[i] - d[i]).abs() <= 1e-10 * d[i].abs().max(1e-10),
                    "{ti} {to} {dp} {param:?} ∂/∂p{i}: {} vs {}",
                    grad[i],
                    d[i]
                );
            }
        }
    }
}
