//! What the simulated head gets wrong, to match the uncertainty budget's
//! components (`crate::uncertainty`): each stage's zero off by a drawn
//! angle, backlash (the load lags the motor after a reversal), gain ranges
//! off their nominal value, chopped stray light, and a reference plate whose
//! true reflectance differs from its certificate's value. The firmware knows
//! none of it: it reports the angles of its step counts and the nominal gains,
//! as a real head does.

use crate::uncertainty::HeadUncertainty;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
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

impl Imperfections {
    /// One head drawn from the stated uncertainties: zeros and gains normal,
    /// stray light uniform within its bound, backlash as stated, the plate's
    /// reflectance normal about its certificate (standard uncertainty
    /// `plate_rho_u`). The same seed gives the same head.
    pub fn draw(seed: u64, u: &HeadUncertainty, plate_rho_u: f64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed ^ 0x1a9e_77e3_5eed_0b1d);
        let mut normal = |sd: f64| Normal::new(0.0, sd.max(0.0)).map_or(0.0, |d| d.sample(&mut rng));
        let zero_offset_deg = [0, 1, 2].map(|a| normal(u.zero_deg[a]));
        let gain_scale = [0; 4].map(|_| 1.0 + normal(u.gain_rel));
        let plate_rho = (super::PLATE_RHO + normal(plate_rho_u)).min(1.0);
        let stray_a = rng.random_range(-1.0..=1.0) * u.stray_a;
        Imperfections {
            zero_offset_deg,
            backlash_deg: u.backlash_deg,
            gain_scale,
            stray_a,
            plate_rho,
        }
    }
}
