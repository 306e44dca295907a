//! What learning the detection chain found (`learn.rs`), which the matched
//! reference is built from (`reference.rs`).

/// Largest supported samples per period: the settings' own limit, so a
/// validated setting always fits the tables.
pub const MAX_M: usize = gonio_shared::DetectionSettings::SAMPLES_PER_PERIOD_MAX as usize;

/// What learning found, valid for one number of samples per period.
#[derive(Debug, Clone, PartialEq)]
pub struct Learned {
    pub(super) m: usize,
    /// Mean period waveform, zero-mean, in codes.
    pub(super) waveform: [f64; MAX_M],
    /// Phase of the waveform against the square and the sine (radians).
    pub phase_square: f64,
    pub phase_sine: f64,
}

impl Learned {
    pub fn samples_per_period(&self) -> usize {
        self.m
    }

    pub fn waveform(&self) -> &[f64] {
        &self.waveform[..self.m]
    }
}
