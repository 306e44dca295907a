//! Measuring while moving: a sweep runs the stages from one geometry to
//! another while the laser chops, and every few chop periods become one
//! swept sample, tagged with where the stages were when its first period
//! began and its last one ended (from the step timer's counts, not from the
//! plan).

use crate::geometry::{AxisAngles, Geometry};
use crate::sample::Signal;
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// One sweep: from `from` (reached first with an ordinary move, where the
/// detector ranges and settles) to `to`, at `speed_dps` on the axis that
/// moves furthest (the others in proportion, so all arrive together).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepRequest {
    pub from: Geometry,
    pub to: Geometry,
    /// Speed of the axis with the longest travel (deg/s), at most its limit.
    pub speed_dps: f32,
    /// Consecutive chop periods demodulated together into one sample.
    pub periods_per_sample: u16,
}

impl SweepRequest {
    /// Fewest periods a swept sample integrates: the drift fit of the
    /// demodulator needs a few.
    pub const PERIODS_MIN: u16 = 4;
    /// Most periods a swept sample integrates (1.1 s at 230 Hz).
    pub const PERIODS_MAX: u16 = 256;
}

/// One sample of a sweep: the signal of its periods, and the stage
/// positions (and their geometry) at its first period's start and its last
/// period's end. Its geometry is the middle of the two; its angular extent,
/// what the fit may weight by, is the distance between them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweptSample {
    /// Sequence number over the head's uptime, shared with [`crate::Sample`].
    pub seq: u32,
    /// Head time at its first period's start (µs since boot) and its length (s).
    pub start_us: u64,
    pub duration_s: f32,
    pub axes_from: AxisAngles,
    pub axes_to: AxisAngles,
    pub from: Geometry,
    pub to: Geometry,
    /// The geometry at the middle of the stage positions.
    pub mid: Geometry,
    pub signal: Signal,
}

/// How a sweep ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepReport {
    pub samples: u32,
    /// Time from the start of the moving part to its end (s).
    pub duration_s: f32,
    pub reached: Geometry,
}
