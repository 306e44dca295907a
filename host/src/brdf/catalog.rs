//! The model ids of `models.md` §2, their parameter names (CLI and JSON
//! contract), the bounds a fit searches within, and the dispatch to each
//! model's evaluation.

use super::frame::Param;
use super::geometry::Geometry;
use super::scalar::Scalar;
use super::{abc_retro, beckmann_retro, blinn_retro, five_param, lafortune, lambert, oren_nayar, retro_phong};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

/// `f_r` at a geometry, writing its gradient in every parameter into the slice.
pub type HandGradient = fn(&Geometry, &[f64], &mut [f64]) -> f64;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelId {
    Lambert,
    RetroPhong,
    AbcRetro,
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
}

const fn b(lo: f64, hi: f64, spread: Spread) -> Bound {
    Bound { lo, hi, spread }
}

use Spread::{Amplitude as A, Linear as L, Log as G};

const KD: Bound = b(0.0, 2.0, L);
const EXPONENT: Bound = b(1.0, 1e4, G);
const RETRO_PHONG: &[Bound] = &[KD, EXPONENT, b(0.0, 10.0, A), b(0.0, 10.0, A), b(0.0, 10.0, A), b(-20.0, 20.0, L)];
const ABC_RETRO: &[Bound] = &[
    KD,
    b(0.0, 1.0, L),
    b(0.0, 100.0, A),
    b(0.0, 1e4, A),
    b(0.0, 20.0, L),
    b(0.0, 100.0, A),
    b(0.0, 1e4, A),
    b(0.0, 20.0, L),
];
const BECKMANN_RETRO: &[Bound] = &[KD, b(1e-3, 1e4, G), b(0.0, 1.0, L)];
const BLINN_RETRO: &[Bound] = &[KD, b(1.0, 1e6, G), b(1.0, 1e6, G)];
const LAFORTUNE: &[Bound] = &[
    KD,
    b(-2.0, 0.0, L),
    b(0.0, 2.0, L),
    EXPONENT,
    b(0.0, 2.0, L),
    b(0.0, 2.0, L),
    EXPONENT,
];
const OREN_NAYAR: &[Bound] = &[KD, b(0.0, std::f64::consts::FRAC_PI_2, L)];
const FIVE_PARAM: &[Bound] = &[b(0.0, 100.0, A), b(0.01, 100.0, G), b(0.01, 20.0, G), b(-100.0, 10.0, L), KD];

impl ModelId {
    pub const ALL: [ModelId; 8] = [
        ModelId::Lambert,
        ModelId::RetroPhong,
        ModelId::AbcRetro,
        ModelId::BeckmannRetro,
        ModelId::BlinnRetro,
        ModelId::Lafortune,
        ModelId::OrenNayar,
        ModelId::FiveParam,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelId::Lambert => "lambert",
            ModelId::RetroPhong => "retro-phong",
            ModelId::AbcRetro => "abc-retro",
            ModelId::BeckmannRetro => "beckmann-retro",
            ModelId::BlinnRetro => "blinn-retro",
            ModelId::Lafortune => "lafortune",
            ModelId::OrenNayar => "oren-nayar",
            ModelId::FiveParam => "five-param",
        }
    }

    pub fn param_names(self) -> &'static [&'static str] {
        match self {
            ModelId::Lambert => &["kd"],
            ModelId::RetroPhong => &["kd", "n", "k1", "k2", "k3", "k4"],
            ModelId::AbcRetro => &["kd", "r0", "ab", "bb", "cb", "ar", "br", "cr"],
            ModelId::BeckmannRetro => &["kd", "alpha", "r0"],
            ModelId::BlinnRetro => &["kd", "alpha_r", "alpha_b"],
            ModelId::Lafortune => &["kd", "cxy_s", "cz_s", "n_s", "cxy_r", "cz_r", "n_r"],
            ModelId::OrenNayar => &["rho", "sigma"],
            ModelId::FiveParam => &["kb", "kr", "a", "b", "kd"],
        }
    }

    /// Search bounds, in the order of [`ModelId::param_names`].
    pub fn bounds(self) -> &'static [Bound] {
        match self {
            ModelId::Lambert => &[KD],
            ModelId::RetroPhong => RETRO_PHONG,
            ModelId::AbcRetro => ABC_RETRO,
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
            ModelId::RetroPhong | ModelId::AbcRetro | ModelId::BeckmannRetro | ModelId::BlinnRetro
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
    /// dual numbers by enough to matter in a fit (`lafortune`).
    pub fn hand_gradient(self) -> Option<HandGradient> {
        match self {
            ModelId::Lafortune => Some(lafortune::value_and_gradient),
            _ => None,
        }
    }

    /// `f_r` (sr⁻¹) at one geometry; `p` holds every parameter in order.
    pub fn eval<T: Scalar>(self, g: &Geometry, p: &[T], param: Param) -> T {
        match self {
            ModelId::Lambert => lambert::eval(p),
            ModelId::RetroPhong => retro_phong::eval(g, p, param),
            ModelId::AbcRetro => abc_retro::eval(g, p, param),
            ModelId::BeckmannRetro => beckmann_retro::eval(g, p, param),
            ModelId::BlinnRetro => blinn_retro::eval(g, p, param),
            ModelId::Lafortune => lafortune::eval(g, p),
            ModelId::OrenNayar => oren_nayar::eval(g, p),
            ModelId::FiveParam => five_param::eval(g, p),
        }
    }
}
