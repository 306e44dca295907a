//! The head's watches: on its host, and on itself when nothing is asked of
//! it. During a scan the head acts on its own for hours, so it holds the scan
//! (laser off, motion braked, drivers disabled) when the host has sent
//! nothing for a while; any frame counts as a heartbeat, and the host polls
//! the status during scans for it. At rest, the drivers and the laser let go
//! after their idle times.

use crate::fault::{Fault, Field};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SafetySettings {
    /// Longest silence of the host during a scan or an operation (s), 0 to
    /// switch the watch off (the default: the simulated head's clock is not
    /// the host's).
    pub host_timeout_s: f32,
    /// With no request for this long at rest (s), the drivers are disabled
    /// and the motors hold by detent only; 0 keeps them enabled.
    pub idle_drivers_s: f32,
    /// At rest after a measurement, the laser stays on this long (s) for the
    /// next one (a HeNe drifts while it warms up); 0 switches it off at once.
    pub laser_idle_s: f32,
}

impl Default for SafetySettings {
    fn default() -> Self {
        SafetySettings {
            host_timeout_s: 0.0,
            idle_drivers_s: Self::IDLE_DRIVERS_DEFAULT_S,
            laser_idle_s: 0.0,
        }
    }
}

impl SafetySettings {
    /// Longest timeout accepted (s).
    pub const HOST_TIMEOUT_MAX_S: f32 = 3600.0;
    /// Shortest timeout accepted (s): longer than one scan point.
    pub const HOST_TIMEOUT_MIN_S: f32 = 1.0;
    /// Drivers' idle time at power-up (s).
    pub const IDLE_DRIVERS_DEFAULT_S: f32 = 60.0;

    /// 0, or a finite time within `min..=max`.
    fn valid(t: f32, min: f32, max: f32) -> bool {
        t == 0.0 || (t.is_finite() && (min..=max).contains(&t))
    }

    pub fn validate(&self) -> Result<(), Fault> {
        if !Self::valid(self.host_timeout_s, Self::HOST_TIMEOUT_MIN_S, Self::HOST_TIMEOUT_MAX_S) {
            return Err(Fault::InvalidValue(Field::HostTimeout));
        }
        if !Self::valid(self.idle_drivers_s, 0.001, Self::HOST_TIMEOUT_MAX_S)
            || !Self::valid(self.laser_idle_s, 0.001, Self::HOST_TIMEOUT_MAX_S)
        {
            return Err(Fault::InvalidValue(Field::IdleTime));
        }
        Ok(())
    }
}
