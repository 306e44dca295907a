//! Measuring while moving: a sweep runs the stages from one geometry to
//! another while the laser chops, and every few chop periods become one
//! swept sample, tagged with where the stages were when its first period
//! began and its last one ended (from the step timer's counts, not from the
//! plan).

use crate::geometry::{AxisAngles, Geometry};
use crate::sample::{ScanPosition, Signal};
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
    /// Most periods a swept sample integrates (35 ms at 230 Hz): the
    /// regression's design of its samples is computed in one stretch of the
    /// serve loop, 65 000 instructions for 8 periods on the chip
    /// (`chip-bench`), within its budget of 100 000; longer ones cost more
    /// than it allows (657 000 for 23).
    pub const PERIODS_MAX: u16 = 8;
    /// Slowest sweep (deg/s).
    pub const SPEED_MIN_DPS: f32 = 0.01;
    /// Longest sweep (s at cruise): the step timer counts 2³² ticks of
    /// 1 µs (71 min) per move.
    pub const DURATION_MAX_S: f32 = 3000.0;
}

/// How narrow the material's lobes are (from the model being fitted or a
/// pre-scan) and how much of that one swept sample may span: a sweep scan's
/// row runs slower within [`SweepLobe::ZONE_WIDTHS`] widths of the retro
/// and of the mirror direction, so that a sample there spans at most
/// `extent_fraction` of the width, and at its own speed elsewhere, where
/// the lobes have fallen to the floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepLobe {
    /// Width (deg) of the narrower lobe, retro or mirror: the angle from its
    /// peak at which it has fallen to e^(−1/2) of its height above the floor
    /// (σ of a Gaussian, `acos(e^(−1/(2n)))` ≈ `1/√n` rad of a cosine lobe
    /// to the power n).
    pub width_deg: f32,
    /// Largest angle a sample near a peak spans, over the width (0–1].
    pub extent_fraction: f32,
}

impl SweepLobe {
    /// How far either side of a peak (in widths) a row runs slow: a
    /// Gaussian lobe there is down to e^(−4.5), 1.1 % of its height.
    pub const ZONE_WIDTHS: f32 = 3.0;
    /// Narrowest width accepted (deg): the arm's microstep, 0.0025°, is far
    /// below it.
    pub const WIDTH_MIN_DEG: f32 = 0.05;

    /// The speed (deg/s) at which a sample of `sample_s` spans its
    /// `extent_fraction` of the width: a row's speed within the zones, where
    /// its own is faster.
    pub fn slow_dps(&self, sample_s: f32) -> f32 {
        self.extent_fraction * self.width_deg / sample_s
    }

    /// Whether the widths and the fraction are in range.
    pub fn valid(&self) -> bool {
        self.width_deg.is_finite()
            && (Self::WIDTH_MIN_DEG..=90.0).contains(&self.width_deg)
            && self.extent_fraction > 0.0
            && self.extent_fraction <= 1.0
    }
}

/// One sample of a sweep: the signal of its periods, and the stage
/// positions at its first period's start and its last period's end. Its
/// position is the middle of the two ([`SweptSample::mid_axes`]); its
/// angular extent, what the fit may weight by, the distance between them.
/// The head sends stage angles only: the geometry is the kinematics' pure
/// function of them, which the host computes (on the chip, three of them
/// would cost a sample some 120 000 instructions, `chip-bench`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweptSample {
    /// Sequence number over the head's uptime, shared with [`crate::Sample`].
    pub seq: u32,
    /// The row of a sweep scan it belongs to.
    pub scan: Option<ScanPosition>,
    /// Head time at its first period's start (µs since boot) and its length (s).
    pub start_us: u64,
    pub duration_s: f32,
    pub axes_from: AxisAngles,
    pub axes_to: AxisAngles,
    pub signal: Signal,
}

impl SweptSample {
    /// The stage angles halfway between the sample's start and end.
    pub fn mid_axes(&self) -> AxisAngles {
        let (a, b) = (&self.axes_from, &self.axes_to);
        AxisAngles {
            omega_deg: 0.5 * (a.omega_deg + b.omega_deg),
            tau_deg: 0.5 * (a.tau_deg + b.tau_deg),
            psi_deg: 0.5 * (a.psi_deg + b.psi_deg),
        }
    }
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
