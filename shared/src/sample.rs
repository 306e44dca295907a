//! One demodulated measurement, as the head reports it.

use crate::geometry::{AxisAngles, Geometry};
use postcard_schema::schema::{DataModelType, NamedType};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

bitflags::bitflags! {
    /// Quality flags of a sample, one bit each. On the wire (postcard) the
    /// bits as a `u16`; in human-readable formats (JSON) the names, e.g.
    /// `"SATURATED | THROUGH_SPLITTER"`. Unknown bits are kept.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
    #[serde(transparent)]
    pub struct SampleFlags: u16 {
        /// ADC codes reached a rail during integration at the reported gain.
        const SATURATED = 1 << 0;
        /// Amplitude below three times its noise estimate.
        const BELOW_NOISE = 1 << 1;
        /// Phase off the learned reference phase.
        const PHASE_OFF = 1 << 2;
        /// An ADC block was lost or late during integration.
        const OVERRUN = 1 << 3;
        /// Measured value outside the loaded sanity model's band.
        const MODEL_MISMATCH = 1 << 4;
        /// Measured through the beam splitter (retro zone): the host rescales it
        /// by the splitter's transmission factor.
        const THROUGH_SPLITTER = 1 << 5;
        /// This is the second measurement of a point that failed its first.
        const REMEASURED = 1 << 6;
    }
}

/// The schema of a plain `u16` newtype: the bit set travels as one, so its
/// wire bytes and the endpoint keys are those of a `u16` newtype.
impl Schema for SampleFlags {
    const SCHEMA: &'static NamedType = &NamedType {
        name: "SampleFlags",
        ty: &DataModelType::NewtypeStruct(u16::SCHEMA),
    };
}

#[cfg(feature = "defmt")]
impl defmt::Format for SampleFlags {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(f, "SampleFlags({=u16:#x})", self.bits())
    }
}

impl SampleFlags {
    /// Any flag that says the value itself is in doubt (everything but
    /// `THROUGH_SPLITTER`, which only says how to scale it).
    pub fn doubtful(self) -> bool {
        !self.difference(Self::THROUGH_SPLITTER).is_empty()
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
    /// What the detector made of it (last, so that the wire bytes are those
    /// of the same fields written inline in the sample).
    pub signal: Signal,
}

/// What the detector made of one integration, in SI units: the demodulated
/// signal, its noise, the gain it was taken at, and its quality flags. The
/// detector's result, before the head attaches where it was measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Signal {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The bit set has the schema (and so the endpoint keys) and the wire
    /// bytes of a plain `u16` newtype.
    #[test]
    fn the_flags_keep_the_wire_format_of_a_u16_newtype() {
        #[derive(Serialize, Schema)]
        struct SampleFlags(u16);
        assert_eq!(<super::SampleFlags as Schema>::SCHEMA, SampleFlags::SCHEMA);
        let flags = super::SampleFlags::SATURATED | super::SampleFlags::THROUGH_SPLITTER;
        let bytes = postcard::to_allocvec(&flags).unwrap();
        assert_eq!(bytes, postcard::to_allocvec(&SampleFlags(0b10_0001)).unwrap());
        assert_eq!(postcard::from_bytes::<super::SampleFlags>(&bytes).unwrap(), flags);
        let unknown = postcard::to_allocvec(&SampleFlags(0x8001)).unwrap();
        assert_eq!(postcard::from_bytes::<super::SampleFlags>(&unknown).unwrap().bits(), 0x8001);
        assert!(flags.doubtful() && !super::SampleFlags::THROUGH_SPLITTER.doubtful());
    }
}
