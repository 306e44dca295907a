//! One demodulated measurement, as the head reports it.

use crate::geometry::{AxisAngles, Geometry};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// Quality flags of a sample, one bit each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampleFlags(pub u16);

impl SampleFlags {
    /// ADC codes reached a rail during integration at the reported gain.
    pub const SATURATED: u16 = 1 << 0;
    /// Amplitude below three times its noise estimate.
    pub const BELOW_NOISE: u16 = 1 << 1;
    /// Phase off the calibrated reference phase.
    pub const PHASE_OFF: u16 = 1 << 2;
    /// An ADC block was lost or late during integration.
    pub const OVERRUN: u16 = 1 << 3;
    /// Measured value outside the loaded sanity model's band.
    pub const MODEL_MISMATCH: u16 = 1 << 4;
    /// Measured through the beam splitter (retro zone): the host rescales it
    /// by the splitter's transmission factor.
    pub const THROUGH_SPLITTER: u16 = 1 << 5;
    /// This is the second measurement of a point that failed its first.
    pub const REMEASURED: u16 = 1 << 6;

    pub const NAMES: [(u16, &'static str); 7] = [
        (Self::SATURATED, "saturated"),
        (Self::BELOW_NOISE, "below_noise"),
        (Self::PHASE_OFF, "phase_off"),
        (Self::OVERRUN, "overrun"),
        (Self::MODEL_MISMATCH, "model_mismatch"),
        (Self::THROUGH_SPLITTER, "through_splitter"),
        (Self::REMEASURED, "remeasured"),
    ];

    pub const fn contains(self, bit: u16) -> bool {
        self.0 & bit != 0
    }

    pub fn set(&mut self, bit: u16) {
        self.0 |= bit;
    }
}

/// Position of a sample in a scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanPosition {
    /// Index of the point in the grid's canonical order (see `ScanSpec::point`).
    pub index: u32,
    /// Position in the order the head visits the points.
    pub order: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// Sequence number over the head's uptime; gaps mean lost samples.
    pub seq: u32,
    /// Set when the sample belongs to a scan.
    pub scan: Option<ScanPosition>,
    /// Head time at the end of integration (µs since boot).
    pub timestamp_us: u64,
    /// Geometry that was asked for.
    pub target: Geometry,
    /// Geometry actually reached, from the step counts.
    pub reached: Geometry,
    pub axes: AxisAngles,
    /// In-phase and quadrature amplitudes at the ADC input (V).
    pub in_phase_v: f32,
    pub quadrature_v: f32,
    /// Phase-sensitive amplitude, after the reference-phase correction (V):
    /// against the matched waveform when that reference is selected.
    pub amplitude_v: f32,
    /// Magnitude `√(I² + Q²)` (V): phase-insensitive, biased upwards by noise.
    pub magnitude_v: f32,
    /// Phase of the signal relative to the chop reference (degrees).
    pub phase_deg: f32,
    /// Standard error of the amplitude, from the spread of per-period results (V).
    pub noise_v: f32,
    /// Transimpedance gain used (V/A) and its index.
    pub gain_v_per_a: f32,
    pub gain_index: u8,
    /// Chop periods integrated.
    pub periods: u16,
    pub flags: SampleFlags,
}
