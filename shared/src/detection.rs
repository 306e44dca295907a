//! Chop and integration settings of the synchronous detector, in SI units.
//! Conversion to timer reloads and ADC trigger rates happens in the firmware's
//! `units` module, never here.

use crate::fault::{Fault, Field};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// The reference waveform the photodiode signal is demodulated against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reference {
    /// ±1 square wave in phase with the chop (boxcar demodulation).
    Square,
    /// Sine at the chop frequency.
    Sine,
    /// The signal's own waveform (the chop through the amplifier's response),
    /// learned by [`crate::icd::LearnEndpoint`]: the least-squares
    /// amplitude of a known waveform in white noise, which reaches the
    /// Cramér–Rao bound where square and sine references fall short.
    Matched,
}

/// What the host asks of the detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DetectionSettings {
    /// Laser chop frequency (Hz); the ADC is triggered from the same timer.
    pub chop_hz: f32,
    /// ADC samples per chop period (even, so each half-period is whole).
    pub samples_per_period: u16,
    /// Chop periods integrated per sample (23 at 230 Hz = 100 ms, a whole
    /// number of 50 Hz and 60 Hz mains periods).
    pub periods: u16,
    /// Settle time after a move, before integrating (s).
    pub settle_s: f32,
    pub reference: Reference,
    /// Pick the transimpedance gain per sample.
    pub auto_range: bool,
}

// Every accepted trigger rate is converted (checked when compiling).
const _: () = assert!(DetectionSettings::ADC_RATE_MAX_HZ < DetectionSettings::ADC_CONVERSIONS_MAX_HZ);

impl DetectionSettings {
    /// Limits of the reference hardware (ADC rate ≤ 200 kS/s, integration ≤ 10 s).
    pub const CHOP_HZ_MIN: f32 = 1.0;
    /// The fastest chop: the ADC's DMA ring holds two periods, so the
    /// thread must read each period within one period, whatever else it
    /// does. `board-faults` measures at this chop with 200 samples a period
    /// (200 kS/s): five measurements made, the longest turn of the thread
    /// 584 µs with the laser on, 416 µs of slack (at 5 kHz, the earlier
    /// limit, every measurement failed with E500). A sweep's sample end
    /// and the serve loop's budget between polls fit in a period too
    /// (`chip-bench`'s `sweep_sample_end_instructions`).
    pub const CHOP_HZ_MAX: f32 = 1_000.0;
    pub const SAMPLES_PER_PERIOD_MAX: u16 = 512;
    /// Conversions ADC1 completes per second on the reference board: a
    /// 21 MHz ADC clock (APB2 84 MHz / 4), 84 sampling cycles and 12 of
    /// conversion, 21 MHz / 96 = 218.75 kS/s. A trigger that comes during a
    /// conversion is lost without a word, and a chop period then holds
    /// fewer samples than it should.
    pub const ADC_CONVERSIONS_MAX_HZ: f32 = 21.0e6 / 96.0;
    /// Highest trigger rate accepted: the conversions' limit less 8 %.
    pub const ADC_RATE_MAX_HZ: f32 = 200_000.0;
    pub const INTEGRATION_MAX_S: f32 = 10.0;
    pub const SETTLE_MAX_S: f32 = 60.0;

    /// Periods that make an integration of `seconds` at this chop frequency
    /// (at least one).
    pub fn periods_for(&self, seconds: f32) -> u16 {
        let p = seconds * self.chop_hz;
        if p.is_finite() && p >= 1.0 {
            (p + 0.5).min(u16::MAX as f32) as u16
        } else {
            1
        }
    }

    /// Integration time (s) of one sample.
    pub fn integration_s(&self) -> f32 {
        self.periods as f32 / self.chop_hz
    }

    /// ADC sampling rate (Hz).
    pub fn sample_rate_hz(&self) -> f32 {
        self.chop_hz * self.samples_per_period as f32
    }

    /// Checks every field; the head applies nothing of a refused setting.
    pub fn validate(&self) -> Result<(), Fault> {
        let bad = |f| Err(Fault::InvalidValue(f));
        if !(self.chop_hz.is_finite() && (Self::CHOP_HZ_MIN..=Self::CHOP_HZ_MAX).contains(&self.chop_hz)) {
            return bad(Field::ChopFrequency);
        }
        let m = self.samples_per_period;
        if !(4..=Self::SAMPLES_PER_PERIOD_MAX).contains(&m) || m % 4 != 0 || self.sample_rate_hz() > Self::ADC_RATE_MAX_HZ {
            return bad(Field::SamplesPerPeriod);
        }
        if self.periods == 0 || self.integration_s() > Self::INTEGRATION_MAX_S {
            return bad(Field::Periods);
        }
        if !(self.settle_s.is_finite() && (0.0..=Self::SETTLE_MAX_S).contains(&self.settle_s)) {
            return bad(Field::SettleTime);
        }
        Ok(())
    }
}

impl Default for DetectionSettings {
    /// 230 Hz chop, 64 samples per period, 23 periods (100 ms), 50 ms settle.
    fn default() -> Self {
        Self {
            chop_hz: 230.0,
            samples_per_period: 64,
            periods: 23,
            settle_s: 0.05,
            reference: Reference::Square,
            auto_range: true,
        }
    }
}

/// The settings as applied, with derived figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DetectionReport {
    pub settings: DetectionSettings,
    /// Chop frequency actually produced by the timer (Hz).
    pub chop_hz_actual: f32,
    pub integration_s: f32,
    /// Equivalent noise bandwidth of the integration, `1/(2T)` (Hz).
    pub enbw_hz: f32,
    /// Chop periods discarded after each gain change while the amplifier
    /// settles (the head's front end): part of every point's dwell.
    pub settle_periods: u16,
}

/// Ask the head to learn its detection chain at the current position, on a
/// strong, steady signal (the reference plate or a retroreflector): the
/// electronics' phase delay and the waveform for [`Reference::Matched`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LearnRequest {
    /// Chop periods averaged (230 = 1 s at 230 Hz).
    pub periods: u16,
}

/// What the detector learned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LearnReport {
    /// Phase of the signal relative to the chop, now the reference phase (degrees).
    pub phase_deg: f32,
    /// Chop amplitude seen while learning (V at the ADC) and the gain used.
    pub amplitude_v: f32,
    pub gain_index: u8,
    /// Signal-to-noise ratio of the learned waveform (amplitude / standard error).
    pub snr: f32,
    pub periods: u16,
}
