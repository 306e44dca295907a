//! The sanity policy: what a sample should read according to the loaded model,
//! and whether it does, within a band of relative, absolute and noise terms.

use super::geometry::FixedGeometry;
use super::model::FixedModel;
use gonio_shared::{Fault, Geometry, SanityConfig};

pub struct Sanity {
    cfg: SanityConfig,
    model: FixedModel,
}

impl Sanity {
    pub fn new(cfg: SanityConfig) -> Result<Self, Fault> {
        cfg.validate()?;
        Ok(Sanity {
            model: FixedModel::new(&cfg.model)?,
            cfg,
        })
    }

    pub fn config(&self) -> &SanityConfig {
        &self.cfg
    }

    /// Expected chop amplitude (V) at a geometry: `f_r · cosθo` from the
    /// fixed-point model, times the instrument constant, the gain and, in the
    /// retro zone, the beam splitter's factor.
    pub fn expected_v(&self, g: &Geometry, gain_v_per_a: f32, through_splitter: bool) -> Option<f32> {
        Some(self.expected_at(&FixedGeometry::from_degrees(g)?, gain_v_per_a, through_splitter))
    }

    /// [`Sanity::expected_v`] at a geometry already in fixed point (its
    /// conversion and the model each cost tens of thousands of instructions
    /// on the chip: the serve loop yields between them).
    pub fn expected_at(&self, fg: &FixedGeometry, gain_v_per_a: f32, through_splitter: bool) -> f32 {
        let f_cos = self.model.eval(fg).times(fg.cos_o().max(super::Fx::ZERO)).to_f32();
        let splitter = if through_splitter { self.cfg.splitter_factor } else { 1.0 };
        f_cos * self.cfg.current_a_per_sr_inv * gain_v_per_a * splitter
    }

    /// True when a measurement lies outside the band around the expectation.
    pub fn mismatch(&self, expected_v: f32, measured_v: f32, noise_v: f32) -> bool {
        let band = self.cfg.rel_tol * expected_v.abs() + self.cfg.abs_tol_v + self.cfg.k_noise * noise_v;
        // Written so that a NaN anywhere counts as a mismatch.
        let within = (measured_v - expected_v).abs() <= band;
        !within
    }
}
