//! The model the head checks samples against (RetroPhong / ABC-Retro /
//! Lambert, `docs/models.md` §2), uploaded by the host.

use crate::fault::{Fault, Field};
use crate::models::{self, ModelSpec};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SanityModel {
    Lambert {
        kd: f32,
    },
    RetroPhong {
        kd: f32,
        n: f32,
        k1: f32,
        k2: f32,
        k3: f32,
        k4: f32,
    },
    /// `back` selects the back-vector cosine for the retro lobe, else the view cosine.
    AbcRetro {
        kd: f32,
        r0: f32,
        ab: f32,
        bb: f32,
        cb: f32,
        ar: f32,
        br: f32,
        cr: f32,
        back: bool,
    },
}

/// Which model, and for `abc-retro` which cosine its retro lobe takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SanityKind {
    Lambert,
    RetroPhong,
    AbcRetro { back: bool },
}

impl SanityKind {
    /// Its row of the model table.
    pub const fn spec(self) -> &'static ModelSpec {
        match self {
            SanityKind::Lambert => &models::LAMBERT,
            SanityKind::RetroPhong => &models::RETRO_PHONG,
            SanityKind::AbcRetro { .. } => &models::ABC_RETRO,
        }
    }

    /// Number of parameters.
    pub const fn arity(self) -> usize {
        self.spec().arity()
    }
}

impl SanityModel {
    /// Builds a model from its parameters in the order of the model table
    /// ([`SanityKind::spec`]); `None` when the count is wrong. The fields are
    /// named as the table's parameters (`model_contract.rs` checks the order).
    pub fn from_params(kind: SanityKind, p: &[f32]) -> Option<Self> {
        Some(match (kind, p) {
            (SanityKind::Lambert, &[kd]) => SanityModel::Lambert { kd },
            (SanityKind::RetroPhong, &[kd, n, k1, k2, k3, k4]) => SanityModel::RetroPhong { kd, n, k1, k2, k3, k4 },
            (SanityKind::AbcRetro { back }, &[kd, r0, ab, bb, cb, ar, br, cr]) => SanityModel::AbcRetro {
                kd,
                r0,
                ab,
                bb,
                cb,
                ar,
                br,
                cr,
                back,
            },
            _ => return None,
        })
    }

    pub fn kind(&self) -> SanityKind {
        match self {
            SanityModel::Lambert { .. } => SanityKind::Lambert,
            SanityModel::RetroPhong { .. } => SanityKind::RetroPhong,
            SanityModel::AbcRetro { back, .. } => SanityKind::AbcRetro { back: *back },
        }
    }

    /// The parameters in the order of the model table.
    pub fn params(&self) -> heapless::Vec<f32, 8> {
        let s: &[f32] = match self {
            SanityModel::Lambert { kd } => &[*kd],
            SanityModel::RetroPhong { kd, n, k1, k2, k3, k4 } => &[*kd, *n, *k1, *k2, *k3, *k4],
            SanityModel::AbcRetro {
                kd,
                r0,
                ab,
                bb,
                cb,
                ar,
                br,
                cr,
                ..
            } => &[*kd, *r0, *ab, *bb, *cb, *ar, *br, *cr],
        };
        // At most eight parameters by construction.
        heapless::Vec::from_slice(s).unwrap_or_default()
    }

    /// Every parameter finite and non-negative (all of them are magnitudes,
    /// exponents or reflectances in `models.md`), exponents ≤ 1e5.
    pub fn validate(&self) -> Result<(), Fault> {
        if self.params().iter().any(|p| !p.is_finite() || *p < 0.0 || *p > 1.0e5) {
            return Err(Fault::InvalidValue(Field::ModelParameter));
        }
        Ok(())
    }
}

/// Model, scale and tolerance band of the on-device check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SanityConfig {
    pub model: SanityModel,
    /// Instrument constant: chop photocurrent (A) per unit of `f_r·cosθo`
    /// (sr⁻¹), as the reference-plate measurement gives it; the expected
    /// amplitude is this times `f_r·cosθo` times the gain (V/A).
    pub current_a_per_sr_inv: f32,
    /// Factor of the beam splitter on samples seen through it (retro zone).
    pub splitter_factor: f32,
    /// Tolerance: relative, absolute (V) and in units of the sample's noise.
    pub rel_tol: f32,
    pub abs_tol_v: f32,
    pub k_noise: f32,
    /// Measure a failing point once more before flagging it.
    pub remeasure: bool,
}

impl SanityConfig {
    pub fn validate(&self) -> Result<(), Fault> {
        self.model.validate()?;
        let ok = |x: f32| x.is_finite() && x >= 0.0;
        let factor_ok = self.splitter_factor.is_finite() && self.splitter_factor > 0.0 && self.splitter_factor <= 1.0;
        if !(ok(self.current_a_per_sr_inv) && factor_ok && ok(self.rel_tol) && ok(self.abs_tol_v) && ok(self.k_noise)) {
            return Err(Fault::InvalidValue(Field::Tolerance));
        }
        Ok(())
    }
}
