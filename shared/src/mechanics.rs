//! What the head says of its stages, so that the host plans and estimates
//! a scan for the machine it talks to rather than for the reference board.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// One stage axis: gearing, travel and motion limits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisMechanics {
    /// Microsteps per revolution of the output (motor steps × microstepping × gear).
    pub microsteps_per_rev: u32,
    /// Soft limits (degrees).
    pub min_deg: f32,
    pub max_deg: f32,
    /// Cruise speed (deg/s) and acceleration (deg/s²) of moves.
    pub max_speed_dps: f32,
    pub max_accel_dps2: f32,
}

/// The stages and the arm's optics, in the order rotation, cradle, arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mechanics {
    pub axes: [AxisMechanics; 3],
    /// Up to this |ψ| (degrees) the return is seen through the beam splitter.
    pub retro_max_deg: f32,
    /// From `retro_max_deg` up to this |ψ| the splitter plate cuts the beam.
    pub blind_max_deg: f32,
}
