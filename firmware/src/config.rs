//! The head's configuration, and the reference head's, in SI units: axis
//! gearing, travel, speed limits, the arm's blind zone, detector gains and
//! the ADC. The chip binary wires them to pins (`chip/pins.rs`); the
//! simulated head builds the same machine.

use gonio_shared::{Axis, AxisMechanics, Mechanics};

/// One stage axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisConfig {
    /// Microsteps per revolution of the *output* (motor steps × microstepping × gear).
    pub microsteps_per_rev: u32,
    /// Soft limits (degrees); moves outside are refused before anything moves.
    pub min_deg: f32,
    pub max_deg: f32,
    /// Angle of the home switch (degrees), just beyond `min_deg`.
    pub home_deg: f32,
    /// Cruise speed (deg/s) of moves and of the fast homing approach.
    pub max_speed_dps: f32,
    /// Acceleration and deceleration (deg/s²).
    pub max_accel_dps2: f32,
    /// Slow homing re-approach speed (deg/s).
    pub home_slow_dps: f32,
    /// Back-off distance after the switch is found (degrees).
    pub home_backoff_deg: f32,
}

impl AxisConfig {
    /// Microsteps per degree (for documentation and tolerances).
    pub fn steps_per_deg(&self) -> f32 {
        self.microsteps_per_rev as f32 / 360.0
    }
}

/// STEP/DIR driver timing (seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriverTiming {
    /// DIR must be stable this long before the first STEP edge...
    pub dir_setup_s: f32,
    /// ...and stay so this long after the last STEP edge of a move.
    pub dir_hold_s: f32,
    /// Width of each STEP pulse.
    pub step_pulse_s: f32,
}

/// Geometry of the beam-splitter plate on the arm (`docs/optics.md`): which
/// arm angles see the sample through the splitter, which are shadowed, and
/// (beyond) which see it directly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmOptics {
    /// Up to this |ψ| (the observation angle α) the return is seen through
    /// the splitter (the retro zone), and carries its factor.
    pub retro_max_deg: f32,
    /// From `retro_max_deg` up to this |ψ| the plate holding splitter and
    /// detector cuts the incident beam: nothing can be measured.
    pub blind_max_deg: f32,
    /// Solid angle (sr) of the detector seen from the sample: a reading is
    /// the BRDF averaged over this field about the view.
    pub detector_sr: f32,
    /// Diameter of the laser beam at the sample (mm, 1/e²): its footprint
    /// on the sample is 1/cosθi as long ([`crate::footprint`]).
    pub beam_diameter_mm: f32,
}

/// Photodiode front end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorConfig {
    /// Transimpedance gains (V/A) selected by the two gain bits, lowest first.
    pub gains_v_per_a: [f32; 4],
    /// ADC reference voltage (V).
    pub adc_vref: f32,
    /// Periods discarded after a gain change while the amplifier settles.
    pub settle_periods: u16,
}

/// The whole head.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadConfig {
    pub axes: [AxisConfig; 3],
    pub driver: DriverTiming,
    pub optics: ArmOptics,
    pub detector: DetectorConfig,
}

impl HeadConfig {
    pub fn axis(&self, axis: Axis) -> &AxisConfig {
        &self.axes[axis.index()]
    }

    /// What the head reports of its stages (`gonio/mechanics`).
    pub fn mechanics(&self) -> Mechanics {
        Mechanics {
            axes: self.axes.map(|a| AxisMechanics {
                microsteps_per_rev: a.microsteps_per_rev,
                min_deg: a.min_deg,
                max_deg: a.max_deg,
                max_speed_dps: a.max_speed_dps,
                max_accel_dps2: a.max_accel_dps2,
            }),
            retro_max_deg: self.optics.retro_max_deg,
            blind_max_deg: self.optics.blind_max_deg,
            detector_sr: self.optics.detector_sr,
            beam_diameter_mm: self.optics.beam_diameter_mm,
        }
    }

    /// This configuration with a head's reported mechanics in place of its
    /// own: what the host plans and estimates a scan with. Homing, driver
    /// timing and the detector stay as they are (a plan does not use them).
    pub fn with_mechanics(&self, m: &Mechanics) -> HeadConfig {
        let mut cfg = *self;
        for (a, r) in cfg.axes.iter_mut().zip(&m.axes) {
            a.microsteps_per_rev = r.microsteps_per_rev;
            a.min_deg = r.min_deg;
            a.max_deg = r.max_deg;
            a.max_speed_dps = r.max_speed_dps;
            a.max_accel_dps2 = r.max_accel_dps2;
        }
        cfg.optics = ArmOptics {
            retro_max_deg: m.retro_max_deg,
            blind_max_deg: m.blind_max_deg,
            detector_sr: m.detector_sr,
            beam_diameter_mm: m.beam_diameter_mm,
        };
        cfg
    }
}

/// Core clock of the reference board (Hz): the PLL's 168 MHz.
pub const CPU_HZ: f64 = 168e6;

/// The reference board's crystal (Hz), which the PLL multiplies to
/// [`CPU_HZ`] and to the USB's 48 MHz; checked at boot (`crate::crystal`).
pub const CRYSTAL_HZ: u32 = 8_000_000;

/// 200-step motors at 16 microsteps: rotation stage on a 90:1 worm (800 µsteps/°),
/// cradle on a 180:1 worm (1600 µsteps/°), arm on a 45:1 reduction (400 µsteps/°).
pub const REFERENCE: HeadConfig = HeadConfig {
    axes: [
        AxisConfig {
            microsteps_per_rev: 200 * 16 * 90,
            min_deg: -100.0,
            max_deg: 100.0,
            home_deg: -101.0,
            max_speed_dps: 20.0,
            max_accel_dps2: 40.0,
            home_slow_dps: 1.0,
            home_backoff_deg: 2.0,
        },
        AxisConfig {
            microsteps_per_rev: 200 * 16 * 180,
            min_deg: -90.0,
            max_deg: 90.0,
            home_deg: -91.0,
            max_speed_dps: 10.0,
            max_accel_dps2: 20.0,
            home_slow_dps: 0.5,
            home_backoff_deg: 2.0,
        },
        AxisConfig {
            microsteps_per_rev: 200 * 16 * 45,
            min_deg: -170.0,
            max_deg: 170.0,
            home_deg: -171.0,
            max_speed_dps: 30.0,
            max_accel_dps2: 60.0,
            home_slow_dps: 1.0,
            home_backoff_deg: 2.0,
        },
    ],
    driver: DriverTiming {
        dir_setup_s: 5.0e-6,
        dir_hold_s: 5.0e-6,
        step_pulse_s: 3.0e-6,
    },
    // The CEA head's (Belcour et al. 2014, §2.A): through the splitter out
    // to 5° from the laser, the plate holding splitter and detector in the
    // incident beam from there to 11.5° (docs/optics.md); its 2.4 × 2.4 mm
    // photodiode subtends 3.6e-5 sr at the sample. A HeNe tube's beam is
    // about 0.8–1 mm across at its waist; 1 mm at the sample.
    optics: ArmOptics {
        retro_max_deg: 5.0,
        blind_max_deg: 11.5,
        detector_sr: 3.6e-5,
        beam_diameter_mm: 1.0,
    },
    detector: DetectorConfig {
        gains_v_per_a: [1.0e4, 1.0e5, 1.0e6, 1.0e7],
        adc_vref: 3.3,
        settle_periods: 1,
    },
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reported_mechanics_rebuild_the_planning_config() {
        let mut other = REFERENCE;
        other.axes[0].microsteps_per_rev *= 2;
        other.axes[1].max_speed_dps = 4.0;
        other.axes[2].max_accel_dps2 = 15.0;
        other.axes[2].min_deg = -120.0;
        other.optics.blind_max_deg = 14.0;
        other.optics.detector_sr = 1.0e-4;
        let rebuilt = REFERENCE.with_mechanics(&other.mechanics());
        assert_eq!(rebuilt, other);
        assert_eq!(REFERENCE.with_mechanics(&REFERENCE.mechanics()), REFERENCE);
    }
}
