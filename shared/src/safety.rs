//! The head's watch on its host: during a scan the head acts on its own for
//! hours, so it stops (laser off, drivers disabled) when the host has sent
//! nothing for a while. Any frame counts as a heartbeat; the host polls the
//! status during scans for it.

use crate::fault::{Fault, Field};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SafetySettings {
    /// Longest silence of the host during a scan (s), 0 to switch the watch
    /// off (the default: the simulated head's clock is not the host's).
    pub host_timeout_s: f32,
}

impl SafetySettings {
    /// Longest timeout accepted (s).
    pub const HOST_TIMEOUT_MAX_S: f32 = 3600.0;
    /// Shortest timeout accepted (s): longer than one scan point.
    pub const HOST_TIMEOUT_MIN_S: f32 = 1.0;

    pub fn validate(&self) -> Result<(), Fault> {
        let t = self.host_timeout_s;
        if t == 0.0 || (t.is_finite() && (Self::HOST_TIMEOUT_MIN_S..=Self::HOST_TIMEOUT_MAX_S).contains(&t)) {
            Ok(())
        } else {
            Err(Fault::InvalidValue(Field::HostTimeout))
        }
    }
}
