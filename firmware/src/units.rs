//! The edge between SI units and hardware units: degrees ↔ microsteps,
//! seconds ↔ timer ticks, hertz ↔ timer reloads, ADC codes ↔ volts. Nothing
//! else in the firmware converts.

use crate::config::{AxisConfig, DriverTiming};
use crate::hw::ChopTiming;
use gonio_shared::DetectionSettings;

/// Degrees → microsteps (nearest).
pub fn deg_to_steps(axis: &AxisConfig, deg: f32) -> i32 {
    libm::round(deg as f64 * axis.microsteps_per_rev as f64 / 360.0) as i32
}

/// An angle in degrees wrapped into (−180°, 180°]: Δφ from the kinematics,
/// phase offsets in the detector.
pub fn wrap_deg(d: f64) -> f64 {
    let x = libm::fmod(d, 360.0);
    if x <= -180.0 {
        x + 360.0
    } else if x > 180.0 {
        x - 360.0
    } else {
        x
    }
}

/// Microsteps → degrees.
pub fn steps_to_deg(axis: &AxisConfig, steps: i32) -> f32 {
    (steps as f64 * 360.0 / axis.microsteps_per_rev as f64) as f32
}

/// Seconds → ticks of a `tick_hz` timer (rounded up, saturating).
pub fn seconds_to_ticks(s: f32, tick_hz: u32) -> u32 {
    let t = libm::ceil(s as f64 * tick_hz as f64);
    if t <= 0.0 {
        0
    } else {
        t.min(u32::MAX as f64) as u32
    }
}

/// The braking constant of an axis on a `tick_hz` step timer: `sqrt(2/a)`
/// in ticks, `a` its deceleration limit in microsteps/tick² (see
/// [`crate::motion::executor::Executor::brake`]).
pub fn brake_ticks(axis: &AxisConfig, tick_hz: u32) -> f32 {
    let a = axis.max_accel_dps2 as f64 * axis.microsteps_per_rev as f64 / 360.0;
    (libm::sqrt(2.0 / a) * tick_hz as f64) as f32
}

/// A STEP pulse's width in ticks of a `tick_hz` step timer: the driver's
/// minimum in whole ticks, and one tick more. The executor raises a pin at
/// a counter value it read and drops it once the counter reaches that value
/// plus the width; the read may come up to a tick after the value began,
/// so without the extra tick a pulse could be a tick short (2 µs of 3).
/// The whole ticks are rounded up, but not for the f32's representation
/// error (3 µs reads as 3.0000001 ticks): the extra tick is meant, not an
/// accident of rounding.
pub fn step_pulse_ticks(driver: &DriverTiming, tick_hz: u32) -> u64 {
    let ticks = driver.step_pulse_s as f64 * tick_hz as f64 * (1.0 - f32::EPSILON as f64);
    libm::ceil(ticks).max(0.0) as u64 + 1
}

/// Seconds → nanoseconds for `DelayNs` (rounded up, saturating).
pub fn seconds_to_ns(s: f32) -> u32 {
    seconds_to_ticks(s, 1_000_000_000)
}

/// Seconds → microseconds for `DelayNs::delay_us` (rounded up, saturating).
pub fn seconds_to_us(s: f32) -> u32 {
    seconds_to_ticks(s, 1_000_000)
}

/// Ticks of a `tick_hz` timer → microseconds (rounded up, saturating): a
/// wait that must not end before the ticks have passed.
pub fn ticks_to_us(ticks: u64, tick_hz: u32) -> u64 {
    (ticks as u128 * 1_000_000).div_ceil(tick_hz.max(1) as u128).min(u64::MAX as u128) as u64
}

/// Chop settings → ADC trigger period of a `timer_hz` timer. The chop
/// frequency actually produced is returned by [`chop_hz_actual`].
pub fn chop_timing(s: &DetectionSettings, timer_hz: u32) -> ChopTiming {
    let ticks = libm::round(timer_hz as f64 / s.sample_rate_hz() as f64).max(1.0);
    ChopTiming {
        ticks_per_sample: ticks.min(u32::MAX as f64) as u32,
        samples_per_period: s.samples_per_period,
    }
}

/// Chop frequency (Hz) that a timing really produces.
pub fn chop_hz_actual(t: ChopTiming, timer_hz: u32) -> f32 {
    (timer_hz as f64 / (t.ticks_per_sample as f64 * t.samples_per_period as f64)) as f32
}

/// ADC codes → volts at the ADC input.
pub fn codes_to_volts(codes: f32, bits: u8, vref: f32) -> f32 {
    codes * vref / (1u32 << bits) as f32
}

#[cfg(test)]
mod tests {
    use super::{step_pulse_ticks, ticks_to_us, wrap_deg};
    use crate::config::REFERENCE;

    #[test]
    fn ticks_become_whole_microseconds_never_short() {
        assert_eq!(ticks_to_us(84, 84_000_000), 1);
        assert_eq!(ticks_to_us(85, 84_000_000), 2);
        assert_eq!(ticks_to_us(0, 84_000_000), 0);
        assert_eq!(ticks_to_us(3 * 32 * 11_413, 84_000_000), 13_044);
        assert_eq!(ticks_to_us(u64::MAX, 1), u64::MAX);
    }

    #[test]
    fn a_step_pulse_outlasts_the_drivers_minimum_by_the_counters_lag() {
        // 3 µs on a 1 MHz timer: 3 ticks, and one for the counter read
        // that lags its tick by up to one.
        assert_eq!(step_pulse_ticks(&REFERENCE.driver, 1_000_000), 4);
        for (s, ticks) in [(2.5e-6, 4), (3.5e-6, 5), (1.0e-6, 2), (0.0, 1)] {
            let mut driver = REFERENCE.driver;
            driver.step_pulse_s = s;
            assert_eq!(step_pulse_ticks(&driver, 1_000_000), ticks, "{s} s");
        }
    }

    #[test]
    fn angles_wrap_into_the_half_open_turn() {
        for (d, want) in [
            (0.0, 0.0),
            (180.0, 180.0),
            (-180.0, 180.0),
            (540.0, 180.0),
            (-540.0, 180.0),
            (190.0, -170.0),
            (-190.0, 170.0),
            (719.5, -0.5),
            (-359.0, 1.0),
        ] {
            assert_eq!(wrap_deg(d), want, "wrap_deg({d})");
        }
    }
}
