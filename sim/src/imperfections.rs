//! What the simulated head gets wrong, to match the uncertainty budget's
//! components (`gonio_analysis::uncertainty`; the host's command line draws a
//! head from them): each stage's zero off by a drawn angle, backlash (the load lags the motor after a reversal), gain ranges
//! off their nominal value, chopped stray light, and a reference plate whose
//! true reflectance differs from its certificate's value. The firmware knows
//! none of it: it reports the angles of its step counts and the nominal gains,
//! as a real head does.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Imperfections {
    /// Load angle minus the angle the step count says, at the home
    /// reference (degrees), ω, τ, ψ.
    pub zero_offset_deg: [f64; 3],
    /// Backlash per stage (degrees).
    pub backlash_deg: [f64; 3],
    /// True transimpedance of each gain range over its nominal value.
    pub gain_scale: [f64; 4],
    /// Chopped stray-light photocurrent (A) added to the signal with the laser on.
    pub stray_a: f64,
    /// True reflectance of the reference plate (its certificate says
    /// [`super::PLATE_RHO`]).
    pub plate_rho: f64,
}

impl Default for Imperfections {
    /// A perfect head and a plate exactly as certified.
    fn default() -> Self {
        Imperfections {
            zero_offset_deg: [0.0; 3],
            backlash_deg: [0.0; 3],
            gain_scale: [1.0; 4],
            stray_a: 0.0,
            plate_rho: super::PLATE_RHO,
        }
    }
}
