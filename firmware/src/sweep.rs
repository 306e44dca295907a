//! Measuring while moving: the speeds of a sweep's axes and the tags of its
//! samples. The head runs a sweep ([`crate::Head::sweep`]): an ordinary move
//! to its start, the detector ranged and settled there, then one move to its
//! end during which the chop runs on and every few periods become a
//! [`gonio_shared::SweptSample`], tagged from the step timer's counts at its first period's
//! start and its last one's end.

use crate::config::HeadConfig;
use crate::motion::{self, Limits, Position};
use gonio_shared::{AxisAngles, Fault, Field, SweepRequest, Unreachable};

/// Limits of the axes moving by `delta` microsteps, so that the one with the
/// longest travel cruises at `speed_dps` and every axis follows the same
/// profile scaled to its travel (speeds and accelerations in proportion, the
/// common acceleration the highest every axis allows): the path is a
/// straight line in axis space, ramps included, and all arrive together.
/// Refused beyond an axis's speed limit, below [`SweepRequest::SPEED_MIN_DPS`]
/// or when the sweep would outlast [`SweepRequest::DURATION_MAX_S`].
pub fn limits(cfg: &HeadConfig, delta: [i32; 3], speed_dps: f32) -> Result<[Limits; 3], Fault> {
    if !(speed_dps >= SweepRequest::SPEED_MIN_DPS && speed_dps.is_finite()) {
        return Err(Fault::InvalidValue(Field::SweepSpeed));
    }
    let deg = [0, 1, 2].map(|i| delta[i].unsigned_abs() as f32 / cfg.axes[i].steps_per_deg());
    let longest = deg.iter().copied().fold(0.0, f32::max);
    if longest / speed_dps > SweepRequest::DURATION_MAX_S {
        return Err(Fault::InvalidValue(Field::SweepSpeed));
    }
    let ratio = deg.map(|d| if longest > 0.0 { d / longest } else { 0.0 });
    let accel = (0..3)
        .filter(|&i| ratio[i] > 0.0)
        .map(|i| cfg.axes[i].max_accel_dps2 / ratio[i])
        .fold(f32::INFINITY, f32::min);
    let mut out = cfg.axes.map(|a| Limits::new(a.max_speed_dps, a.max_accel_dps2));
    for i in 0..3 {
        if ratio[i] > 0.0 {
            out[i] = Limits::new(speed_dps * ratio[i], accel * ratio[i]);
            if out[i].speed_dps > cfg.axes[i].max_speed_dps {
                return Err(Fault::InvalidValue(Field::SweepSpeed));
            }
        }
    }
    Ok(out)
}

/// Checks a sweep's sample length (its ends are checked by
/// [`crate::kinematics::inverse`]).
pub fn check(req: &SweepRequest) -> Result<(), Fault> {
    if !(SweepRequest::PERIODS_MIN..=SweepRequest::PERIODS_MAX).contains(&req.periods_per_sample) {
        return Err(Fault::InvalidValue(Field::Periods));
    }
    Ok(())
}

/// Refuses a sweep whose path (a straight line in axis space between two
/// reachable ends, so inside the travel all along) crosses the blind zone of
/// the arm. It cannot dip behind the sample: in the stage frame the light's
/// and the view's polar angles stay below 90° while `cos τ·cos ω` and
/// `cos τ·cos(ω − ψ)` stay positive (`kinematics::forward`), and along the
/// line τ, ω and ω − ψ change linearly between ends that
/// [`crate::kinematics::inverse`] puts inside (−90°, 90°) (tested by walking
/// paths). No trigonometry: two comparisons on the chip.
pub fn check_path(cfg: &HeadConfig, from: &AxisAngles, to: &AxisAngles) -> Result<(), Fault> {
    let (lo, hi) = (from.psi_deg.min(to.psi_deg), from.psi_deg.max(to.psi_deg));
    let (near, far) = (cfg.optics.retro_max_deg, cfg.optics.blind_max_deg);
    if (lo < far && hi > near) || (lo < -near && hi > -far) {
        return Err(Fault::Unreachable(Unreachable::BlindZone));
    }
    Ok(())
}

/// The stage angles of a sample whose first period began with the step
/// timer at `first` steps into the move in flight from `pos` and whose last
/// ended at `last`.
pub fn tag(cfg: &HeadConfig, pos: &Position, first: [u32; 3], last: [u32; 3]) -> (AxisAngles, AxisAngles) {
    (
        motion::axis_angles(cfg, motion::in_flight_steps(pos, first)),
        motion::axis_angles(cfg, motion::in_flight_steps(pos, last)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::REFERENCE;
    use crate::kinematics;
    use gonio_shared::Geometry;
    use proptest::prelude::*;

    /// The path's worst polar angle and whether it enters the blind zone,
    /// looked at densely with the full kinematics.
    fn walked(from: &AxisAngles, to: &AxisAngles) -> (f32, bool) {
        let (near, far) = (REFERENCE.optics.retro_max_deg, REFERENCE.optics.blind_max_deg);
        let mut worst: f32 = 0.0;
        let mut blind = false;
        for k in 0..=400 {
            let f = k as f32 / 400.0;
            let at = |a: f32, b: f32| a + (b - a) * f;
            let a = AxisAngles {
                omega_deg: at(from.omega_deg, to.omega_deg),
                tau_deg: at(from.tau_deg, to.tau_deg),
                psi_deg: at(from.psi_deg, to.psi_deg),
            };
            let g = kinematics::forward(&a);
            worst = worst.max(g.theta_i_deg).max(g.theta_o_deg);
            blind |= a.psi_deg.abs() > near && a.psi_deg.abs() < far;
        }
        (worst, blind)
    }

    proptest! {
        #[test]
        fn the_path_check_agrees_with_walking_the_path(
            ti in 0.0f32..89.0, to in 0.0f32..89.0, dp in -180.0f32..180.0,
            ti2 in 0.0f32..89.0, to2 in 0.0f32..89.0, dp2 in -180.0f32..180.0,
        ) {
            let (Ok(a), Ok(b)) = (
                kinematics::inverse(&REFERENCE, &Geometry::new(ti, to, dp)),
                kinematics::inverse(&REFERENCE, &Geometry::new(ti2, to2, dp2)),
            ) else {
                return Ok(());
            };
            let (worst, blind) = walked(&a, &b);
            match check_path(&REFERENCE, &a, &b) {
                Ok(()) => prop_assert!(worst < 90.0 && !blind, "accepted: θ up to {worst}°, blind {blind}"),
                Err(Fault::Unreachable(Unreachable::BlindZone)) => prop_assert!(blind),
                Err(f) => prop_assert!(false, "{f:?}"),
            }
        }
    }

    #[test]
    fn every_axis_follows_the_same_profile_scaled_to_its_travel() {
        let delta = [1600, -800, 0];
        let l = limits(&REFERENCE, delta, 4.0).unwrap();
        let t = [0, 1].map(|i| motion::ramp(&REFERENCE.axes[i], delta[i].unsigned_abs(), l[i]));
        // Same duration, same fraction of the travel at every instant.
        assert!(
            (t[0].duration() - t[1].duration()).abs() < 1e-3,
            "{} s vs {} s",
            t[0].duration(),
            t[1].duration()
        );
        for k in [1, 100, 400, 800] {
            let (a, b) = (t[0].step_time(2 * k), t[1].step_time(k));
            assert!((a - b).abs() < 2e-3, "step {k}: {a} s vs {b} s");
        }
        assert!(l
            .iter()
            .zip(&REFERENCE.axes)
            .all(|(l, a)| l.accel_dps2 <= a.max_accel_dps2 * 1.0001));
        for bad in [1e4, f32::NAN, 0.0, SweepRequest::SPEED_MIN_DPS * 0.5] {
            assert_eq!(
                limits(&REFERENCE, [1600, 0, 0], bad),
                Err(Fault::InvalidValue(Field::SweepSpeed)),
                "{bad}"
            );
        }
    }
}
