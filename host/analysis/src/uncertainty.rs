//! The uncertainty budget of a calibrated value (GUM, JCGM 100:2008): the
//! head's stated type-B uncertainties, the named components of one sample's
//! budget, and their combination. Every component is a standard uncertainty
//! in the value's own unit (sr⁻¹); expanded intervals use k = 2.
//! `docs/retroreflection.md#uncertainty` explains each component and how
//! the simulated head is given the matching imperfections.

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Coverage factor of the expanded intervals (≈ 95 % for a normal distribution).
pub const K_COVERAGE: f64 = 2.0;

/// What the head's maker states about its imperfections (type B).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeadUncertainty {
    /// Standard uncertainty of each stage's zero after homing (degrees),
    /// ω, τ, ψ: the home switch's repeatability.
    pub zero_deg: [f64; 3],
    /// Backlash of each stage (degrees): after a reversal the load lags the
    /// motor by this much.
    pub backlash_deg: [f64; 3],
    /// Relative standard uncertainty of each gain range's transimpedance.
    pub gain_rel: f64,
    /// Largest chopped stray-light photocurrent (A), of either sign after
    /// demodulation (a rectangular distribution).
    pub stray_a: f64,
}

impl Default for HeadUncertainty {
    /// The reference head: switches repeatable to 0.02°, 0.01° of backlash,
    /// 0.1 % resistors (0.2 % per range with the amplifier's own spread),
    /// 2 pA of chopped stray light at most.
    fn default() -> Self {
        HeadUncertainty {
            zero_deg: [0.02; 3],
            backlash_deg: [0.01; 3],
            gain_rel: 0.002,
            stray_a: 2e-12,
        }
    }
}

impl HeadUncertainty {
    /// What a user states, each part left out the reference head's: the
    /// zeros and the backlash as one value for every axis or three (ω, τ,
    /// ψ), each finite and ≥ 0.
    pub fn stated(zero_deg: Option<&[f64]>, backlash_deg: Option<&[f64]>, gain_rel: Option<f64>, stray_a: Option<f64>) -> Result<Self> {
        let reference = HeadUncertainty::default();
        let valid = |x: f64| x.is_finite() && x >= 0.0;
        let three = |v: Option<&[f64]>, default: [f64; 3], name: &str| -> Result<[f64; 3]> {
            match v {
                None => Ok(default),
                Some(v) if v.iter().any(|x| !valid(*x)) => bail!("--{name} must be finite and ≥ 0"),
                Some([x]) => Ok([*x; 3]),
                Some([a, b, c]) => Ok([*a, *b, *c]),
                Some(v) => bail!("--{name} takes one value or three (ω, τ, ψ), found {}", v.len()),
            }
        };
        let one = |v: Option<f64>, default: f64, name: &str| -> Result<f64> {
            match v {
                None => Ok(default),
                Some(x) if valid(x) => Ok(x),
                Some(_) => bail!("--{name} must be finite and ≥ 0"),
            }
        };
        Ok(HeadUncertainty {
            zero_deg: three(zero_deg, reference.zero_deg, "u-zero-deg")?,
            backlash_deg: three(backlash_deg, reference.backlash_deg, "backlash-deg")?,
            gain_rel: one(gain_rel, reference.gain_rel, "u-gain")?,
            stray_a: one(stray_a, reference.stray_a, "stray-a")?,
        })
    }

    /// Standard uncertainty of one stage angle (degrees): the zero, and the
    /// backlash. Homing ends on a move towards the switch, so the zero is
    /// taken with the load half a backlash to one side of the motor's mean
    /// position; later the load sits half a backlash to either side,
    /// depending on the direction of the last move, which the calibration
    /// does not know: ±b/2 with equal weight, a standard uncertainty of b/2.
    pub fn axis_deg(&self, axis: usize) -> f64 {
        self.zero_deg[axis].hypot(self.backlash_deg[axis] / 2.0)
    }

    /// Standard uncertainty of the stray photocurrent (A).
    pub fn stray_u_a(&self) -> f64 {
        self.stray_a / 3f64.sqrt()
    }

    /// Relative standard uncertainty of the ratio of two gain ranges (the
    /// plate's and the sample's), each known to `gain_rel`.
    pub fn gain_ratio_rel(&self) -> f64 {
        self.gain_rel * std::f64::consts::SQRT_2
    }
}

/// Inputs every sample of a scan shares: the plate's certificate, the
/// scale `K`, and each stage's zero. A fit cannot average them out, so each
/// sample carries, per shared input, how much its value moves when that
/// input is off by one standard uncertainty (`Observation::shared`), and the
/// fit's covariance adds their effect on the parameters.
pub const SHARED: [&str; 5] = ["rho_ref", "scale", "zero_omega", "zero_tau", "zero_psi"];

/// The named components of one value's budget, standard uncertainties in sr⁻¹.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Components {
    /// The lock-in's own estimate (spread of the per-period amplitudes).
    pub noise: f64,
    /// The reference plate's reflectance (its certificate).
    pub rho_ref: f64,
    /// The scale `K` fitted over the plate (its statistical spread).
    pub scale: f64,
    /// The beam splitter's factor, for samples seen through it.
    pub splitter: f64,
    /// The laser-drift correction from the monitor.
    pub drift: f64,
    /// Ratio of the sample's gain range to the plate's.
    pub gain: f64,
    /// Stage-angle errors times the local slope of the BRDF.
    pub angle: f64,
    /// Chopped stray light and residual offset.
    pub stray: f64,
}

impl Components {
    /// Column names of the components in `calibrated.csv`, in [`Self::values`] order.
    pub const NAMES: [&'static str; 8] = ["noise", "rho_ref", "scale", "splitter", "drift", "gain", "angle", "stray"];

    pub fn values(&self) -> [f64; 8] {
        [
            self.noise,
            self.rho_ref,
            self.scale,
            self.splitter,
            self.drift,
            self.gain,
            self.angle,
            self.stray,
        ]
    }

    /// Combined standard uncertainty: the components are independent, added
    /// in quadrature (GUM eq. 10).
    pub fn combined(&self) -> f64 {
        self.values().iter().map(|u| u * u).sum::<f64>().sqrt()
    }

    /// The largest component and its name.
    pub fn largest(&self) -> (&'static str, f64) {
        Self::NAMES
            .iter()
            .zip(self.values())
            .fold(("noise", f64::NEG_INFINITY), |best, (n, u)| if u > best.1 { (n, u) } else { best })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_add_in_quadrature() {
        let c = Components {
            noise: 3.0,
            angle: 4.0,
            ..Components::default()
        };
        assert!((c.combined() - 5.0).abs() < 1e-12);
        assert_eq!(c.largest(), ("angle", 4.0));
    }

    #[test]
    fn backlash_counts_as_half_its_width() {
        let u = HeadUncertainty {
            zero_deg: [0.0; 3],
            backlash_deg: [0.02; 3],
            ..HeadUncertainty::default()
        };
        assert!((u.axis_deg(0) - 0.01).abs() < 1e-15);
    }
}
