//! What the simulated head gets wrong, to match the uncertainty budget's
//! components (`gonio_analysis::uncertainty`; the host's command line draws a
//! head from them): each stage's zero off by a drawn angle, backlash (the load lags the motor after a reversal), gain ranges
//! off their nominal value, chopped stray light, and a reference plate whose
//! true reflectance differs from its certificate's value. The firmware knows
//! none of it: it reports the angles of its step counts and the nominal gains,
//! as a real head does.

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

impl Imperfections {
    /// One head drawn from what its maker states: zeros normal about 0
    /// (standard deviations `zero_sd_deg`), the `backlash_deg` as stated,
    /// each gain normal about 1 (`gain_rel_sd`), stray light uniform within
    /// ±`stray_max_a`, and the plate's reflectance normal about its
    /// certificate (`plate_rho_sd`). The same seed gives the same head.
    pub fn drawn(seed: u64, zero_sd_deg: [f64; 3], backlash_deg: [f64; 3], gain_rel_sd: f64, stray_max_a: f64, plate_rho_sd: f64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed ^ 0x1a9e_77e3_5eed_0b1d);
        let mut normal = |sd: f64| Normal::new(0.0, sd.max(0.0)).map_or(0.0, |d| d.sample(&mut rng));
        let zero_offset_deg = zero_sd_deg.map(&mut normal);
        let gain_scale = [0; 4].map(|_| 1.0 + normal(gain_rel_sd));
        let plate_rho = (super::PLATE_RHO + normal(plate_rho_sd)).min(1.0);
        let stray_a = rng.random_range(-1.0..=1.0) * stray_max_a;
        Imperfections {
            zero_offset_deg,
            backlash_deg,
            gain_scale,
            stray_a,
            plate_rho,
        }
    }
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
