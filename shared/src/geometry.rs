//! Measurement geometry: the isotropic BRDF coordinates and the three axis
//! angles of the head (their lab frame and kinematics:
//! `firmware/src/kinematics.rs`).

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// An isotropic BRDF direction pair, in degrees.
///
/// `dphi_deg = 0` is the retro half-plane, `±180` the mirror half-plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Geometry {
    /// Polar angle of the light from the sample normal.
    pub theta_i_deg: f32,
    /// Polar angle of the view (detector) from the sample normal.
    pub theta_o_deg: f32,
    /// Azimuth of the view relative to the light, `φo − φi`.
    pub dphi_deg: f32,
}

impl Geometry {
    pub const fn new(theta_i_deg: f32, theta_o_deg: f32, dphi_deg: f32) -> Self {
        Self {
            theta_i_deg,
            theta_o_deg,
            dphi_deg,
        }
    }

    /// True when every angle is a finite number.
    pub fn is_finite(&self) -> bool {
        self.theta_i_deg.is_finite() && self.theta_o_deg.is_finite() && self.dphi_deg.is_finite()
    }
}

/// The three stage angles, in degrees: sample yaw ω (rotation stage), sample
/// tilt τ (cradle) and detector azimuth ψ (arm; `ψ = 0` is the retro direction
/// seen through the beam splitter).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisAngles {
    pub omega_deg: f32,
    pub tau_deg: f32,
    pub psi_deg: f32,
}
