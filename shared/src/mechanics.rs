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
    /// Solid angle (sr) of the detector's field seen from the sample.
    pub detector_sr: f32,
    /// Diameter of the laser beam at the sample (mm, 1/e²): its footprint,
    /// 1/cosθi as long, must stay on the sample.
    pub beam_diameter_mm: f32,
}

impl Mechanics {
    /// Whether a scan can be planned with these: every gearing, speed and
    /// acceleration positive and finite, every travel a finite range, the
    /// arm's zones ordered. A head reporting otherwise is refused rather
    /// than planned for with infinite or NaN move times.
    pub fn is_plausible(&self) -> bool {
        let positive = |x: f32| x.is_finite() && x > 0.0;
        let axes_ok = self.axes.iter().all(|a| {
            a.microsteps_per_rev > 0
                && positive(a.max_speed_dps)
                && positive(a.max_accel_dps2)
                && a.min_deg.is_finite()
                && a.max_deg.is_finite()
                && a.min_deg < a.max_deg
        });
        axes_ok
            && self.retro_max_deg >= 0.0
            && self.retro_max_deg <= self.blind_max_deg
            && self.blind_max_deg.is_finite()
            && self.detector_sr.is_finite()
            && self.detector_sr >= 0.0
            && self.beam_diameter_mm.is_finite()
            && self.beam_diameter_mm > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implausible_mechanics_are_told_apart() {
        let axis = AxisMechanics {
            microsteps_per_rev: 288_000,
            min_deg: -100.0,
            max_deg: 100.0,
            max_speed_dps: 20.0,
            max_accel_dps2: 40.0,
        };
        let good = Mechanics {
            axes: [axis; 3],
            retro_max_deg: 5.0,
            blind_max_deg: 11.5,
            detector_sr: 3.6e-5,
            beam_diameter_mm: 1.0,
        };
        assert!(good.is_plausible());
        let mut bad = [good; 8];
        bad[0].axes[1].max_speed_dps = 0.0;
        bad[1].axes[2].max_accel_dps2 = f32::NAN;
        bad[2].axes[0].microsteps_per_rev = 0;
        bad[3].axes[0].min_deg = 100.0;
        bad[4].retro_max_deg = 12.0;
        bad[5].blind_max_deg = f32::INFINITY;
        bad[6].detector_sr = -1.0;
        bad[7].beam_diameter_mm = 0.0;
        for (k, m) in bad.iter().enumerate() {
            assert!(!m.is_plausible(), "case {k}");
        }
    }
}
