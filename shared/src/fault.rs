//! Why a command was refused or a scan stopped. Every variant maps to a code
//! and a sentence on the host; the head never answers a bad command by moving.

use core::fmt;
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// One of the three stage axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// Rotation stage: sample yaw ω.
    Rotation,
    /// Goniometric cradle: sample tilt τ.
    Cradle,
    /// Detector arm: azimuth ψ.
    Arm,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::Rotation, Axis::Cradle, Axis::Arm];

    pub const fn index(self) -> usize {
        match self {
            Axis::Rotation => 0,
            Axis::Cradle => 1,
            Axis::Arm => 2,
        }
    }

    pub const fn name(self) -> &'static str {
        match self {
            Axis::Rotation => "rotation",
            Axis::Cradle => "cradle",
            Axis::Arm => "arm",
        }
    }
}

/// A command field that was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Field {
    ThetaI,
    ThetaO,
    Dphi,
    ChopFrequency,
    SamplesPerPeriod,
    Periods,
    SettleTime,
    ScanRange,
    ScanStart,
    ModelParameter,
    Tolerance,
    HostTimeout,
    IdleTime,
    SweepSpeed,
    SweepLobe,
}

impl Field {
    pub const fn name(self) -> &'static str {
        match self {
            Field::ThetaI => "theta_i",
            Field::ThetaO => "theta_o",
            Field::Dphi => "dphi",
            Field::ChopFrequency => "chop frequency",
            Field::SamplesPerPeriod => "samples per period",
            Field::Periods => "integration periods",
            Field::SettleTime => "settle time",
            Field::ScanRange => "scan range",
            Field::ScanStart => "scan start position",
            Field::ModelParameter => "model parameter",
            Field::Tolerance => "sanity tolerance",
            Field::HostTimeout => "host timeout",
            Field::IdleTime => "idle time",
            Field::SweepSpeed => "sweep speed",
            Field::SweepLobe => "sweep lobe",
        }
    }
}

/// Why a geometry cannot be reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unreachable {
    /// The direction lies at or below the sample plane (θ ≥ 90°).
    BehindSample,
    /// The axis would leave its travel.
    AxisTravel(Axis),
    /// The arm would sit where the beam-splitter plate cuts the incident beam.
    BlindZone,
}

/// A refusal or a fault, with what it concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// A field is NaN, infinite or out of its documented range.
    InvalidValue(Field),
    /// The geometry cannot be reached; nothing moved.
    Unreachable(Unreachable),
    /// A move or measurement was asked for before homing.
    NotHomed,
    /// Another command (a scan) is running; abort it first.
    Busy,
    /// The operation was stopped by an abort command.
    Aborted,
    /// Homing ran the full travel without seeing the switch.
    HomeSwitchNotFound(Axis),
    /// The home switch of an axis stays active after backing off.
    HomeSwitchStuck(Axis),
    /// The step timer could not accept or finish a move.
    StepTimer(Axis),
    /// The ADC stream lost a block (DMA overrun).
    AdcOverrun,
    /// The detector saturates even at the lowest gain (in a scan: at
    /// consecutive points, stray light or a failed amplifier).
    Saturated,
    /// A GPIO write (DIR, enable, gain select, laser) failed.
    Gpio,
    /// The matched reference was asked for before it was learned.
    NotLearned,
    /// The signal is too weak or too noisy to learn the reference from.
    WeakSignal,
    /// Consecutive scan points all below the noise floor: the laser is dead
    /// or the beam blocked.
    NoSignal,
    /// The host sent nothing within the host timeout during a scan.
    HostSilent,
    /// The head restarted because its independent watchdog fired (hung
    /// firmware); it came up in the safe state.
    WatchdogReset,
    /// The E-STOP input is open (pressed, or its wire cut): laser off, motion
    /// braked, drivers disabled; everything is refused until it is closed
    /// and the host asks to continue.
    EmergencyStop,
    /// The link to the host closed (cable pulled, port closed, USB reset or
    /// suspend) during an operation.
    LinkLost,
    /// Pause or continue without a scan to pause or to continue.
    NotScanning,
    /// The crystal (HSE) did not start (`measured_khz` 0) or runs at another
    /// frequency than the head's (`expected_khz`), as counted against the
    /// internal oscillator at boot: the head runs on that oscillator (±1 %),
    /// its laser inhibited until it restarts with a good crystal.
    Crystal { measured_khz: u32, expected_khz: u32 },
    /// The crystal stopped while the head ran: the clock security system's
    /// interrupt made the pins safe and restarted the head.
    ClockStopped,
    /// An interrupt that has no handler of the firmware's fired (its IRQ
    /// number; negative for the core's own exceptions): the pins were made
    /// safe and the head restarted.
    StrayInterrupt(i16),
    /// The image never turns the laser on: built with the firmware's
    /// `no-laser` feature, for a first power-up (docs/bring-up.md).
    LaserDisabled,
}

impl Fault {
    /// A stable numeric code for logs and files.
    pub const fn code(&self) -> u16 {
        match self {
            Fault::InvalidValue(_) => 100,
            Fault::Unreachable(Unreachable::BehindSample) => 200,
            Fault::Unreachable(Unreachable::AxisTravel(_)) => 201,
            Fault::Unreachable(Unreachable::BlindZone) => 202,
            Fault::NotHomed => 300,
            Fault::Busy => 301,
            Fault::Aborted => 302,
            Fault::HomeSwitchNotFound(_) => 400,
            Fault::HomeSwitchStuck(_) => 401,
            Fault::StepTimer(_) => 402,
            Fault::AdcOverrun => 500,
            Fault::Saturated => 501,
            Fault::Gpio => 600,
            Fault::NotLearned => 502,
            Fault::WeakSignal => 503,
            Fault::NoSignal => 504,
            Fault::HostSilent => 303,
            Fault::WatchdogReset => 304,
            Fault::EmergencyStop => 305,
            Fault::LinkLost => 306,
            Fault::NotScanning => 307,
            Fault::Crystal { .. } => 601,
            Fault::ClockStopped => 602,
            Fault::StrayInterrupt(_) => 603,
            Fault::LaserDisabled => 604,
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "E{}: ", self.code())?;
        match self {
            Fault::InvalidValue(field) => write!(f, "invalid {} (NaN, infinite or out of range)", field.name()),
            Fault::Unreachable(Unreachable::BehindSample) => f.write_str("unreachable: direction at or behind the sample plane"),
            Fault::Unreachable(Unreachable::AxisTravel(a)) => write!(f, "unreachable: outside the travel of the {} axis", a.name()),
            Fault::Unreachable(Unreachable::BlindZone) => f.write_str("unreachable: arm in the blind zone of the beam-splitter plate"),
            Fault::NotHomed => f.write_str("axes not homed; run home first"),
            Fault::Busy => f.write_str("head busy (a scan, a pause or a stop); abort it first"),
            Fault::Aborted => f.write_str("aborted"),
            Fault::HomeSwitchNotFound(a) => write!(f, "home switch of the {} axis not found within its travel", a.name()),
            Fault::HomeSwitchStuck(a) => write!(f, "home switch of the {} axis stuck active", a.name()),
            Fault::StepTimer(a) => write!(f, "step timer fault on the {} axis", a.name()),
            Fault::AdcOverrun => f.write_str("ADC block lost (DMA overrun)"),
            Fault::Saturated => f.write_str("detector saturated at the lowest gain"),
            Fault::Gpio => f.write_str("GPIO write failed"),
            Fault::NotLearned => f.write_str("matched reference not learned; learn it on a strong signal first (--learn-at)"),
            Fault::WeakSignal => f.write_str("signal too weak or too noisy to learn the reference from"),
            Fault::NoSignal => f.write_str("no signal at consecutive scan points: laser dead or beam blocked"),
            Fault::HostSilent => f.write_str("the host went silent during the scan (heartbeat timeout)"),
            Fault::WatchdogReset => f.write_str("the head was restarted by its watchdog (hung firmware); it came up safe"),
            Fault::EmergencyStop => f.write_str("E-STOP open: laser off, motion stopped; close it and continue"),
            Fault::LinkLost => f.write_str("the link to the host was lost during the operation"),
            Fault::NotScanning => f.write_str("no scan to pause or to continue"),
            Fault::Crystal { measured_khz: 0, expected_khz } => write!(
                f,
                "the {expected_khz} kHz crystal did not start: running on the internal oscillator, laser inhibited; check the crystal"
            ),
            Fault::Crystal { measured_khz, expected_khz } => write!(
                f,
                "the crystal runs at {measured_khz} kHz, not {expected_khz} kHz: running on the internal oscillator, laser inhibited; fit the board's {expected_khz} kHz crystal"
            ),
            Fault::ClockStopped => f.write_str("the crystal stopped while the head ran: pins made safe, head restarted"),
            Fault::StrayInterrupt(n) => write!(f, "interrupt {n} fired with no handler: pins made safe, head restarted"),
            Fault::LaserDisabled => f.write_str("this image never turns the laser on (built with `no-laser`, for bring-up); flash the full image to measure"),
        }
    }
}
