//! Measuring while moving: the speeds of a sweep's axes and the tags of its
//! samples. The head runs a sweep ([`crate::Head::sweep`]): an ordinary move
//! to its start, the detector ranged and settled there, then one move to its
//! end during which the chop runs on and every few periods become a
//! [`SweptSample`], tagged from the step timer's counts at its first period's
//! start and its last one's end.

use crate::config::HeadConfig;
use crate::kinematics;
use crate::motion::{self, Position};
use gonio_shared::{AxisAngles, Fault, Field, Geometry, Signal, SweepRequest, SweptSample, Unreachable};

/// Speeds (deg/s) of the axes moving by `delta` microsteps, so that the one
/// with the longest travel runs at `speed_dps` and all arrive together (a
/// straight line in axis space at cruise); refused beyond an axis's limit.
pub fn speeds(cfg: &HeadConfig, delta: [i32; 3], speed_dps: f32) -> Result<[f32; 3], Fault> {
    if !(speed_dps > 0.0 && speed_dps.is_finite()) {
        return Err(Fault::InvalidValue(Field::SweepSpeed));
    }
    let deg = [0, 1, 2].map(|i| delta[i].unsigned_abs() as f32 / cfg.axes[i].steps_per_deg());
    let longest = deg.iter().copied().fold(0.0, f32::max);
    if longest == 0.0 {
        return Ok(cfg.axes.map(|a| a.max_speed_dps));
    }
    let mut v = [0.0; 3];
    for i in 0..3 {
        v[i] = if deg[i] > 0.0 {
            speed_dps * deg[i] / longest
        } else {
            cfg.axes[i].max_speed_dps
        };
        if v[i] > cfg.axes[i].max_speed_dps {
            return Err(Fault::InvalidValue(Field::SweepSpeed));
        }
    }
    Ok(v)
}

/// Checks what a sweep asks before anything moves.
pub fn check(req: &SweepRequest) -> Result<(), Fault> {
    if !(SweepRequest::PERIODS_MIN..=SweepRequest::PERIODS_MAX).contains(&req.periods_per_sample) {
        return Err(Fault::InvalidValue(Field::Periods));
    }
    kinematics::validate(&req.from)?;
    kinematics::validate(&req.to)
}

/// Points along a sweep's path checked for the sample plane.
const PATH_CHECKS: u32 = 16;

/// Refuses a sweep whose path (a straight line in axis space, between two
/// reachable ends: inside the travel all along) crosses the blind zone of
/// the arm or dips behind the sample plane.
pub fn check_path(cfg: &HeadConfig, from: &AxisAngles, to: &AxisAngles) -> Result<(), Fault> {
    let (lo, hi) = (from.psi_deg.min(to.psi_deg), from.psi_deg.max(to.psi_deg));
    let (near, far) = (cfg.optics.retro_max_deg, cfg.optics.blind_max_deg);
    if (lo < far && hi > near) || (lo < -near && hi > -far) {
        return Err(Fault::Unreachable(Unreachable::BlindZone));
    }
    for k in 1..PATH_CHECKS {
        let f = k as f32 / PATH_CHECKS as f32;
        let at = |a: f32, b: f32| a + (b - a) * f;
        let g = kinematics::forward(&AxisAngles {
            omega_deg: at(from.omega_deg, to.omega_deg),
            tau_deg: at(from.tau_deg, to.tau_deg),
            psi_deg: at(from.psi_deg, to.psi_deg),
        });
        if g.theta_i_deg >= 90.0 || g.theta_o_deg >= 90.0 {
            return Err(Fault::Unreachable(Unreachable::BehindSample));
        }
    }
    Ok(())
}

/// The swept sample of `signal`, whose first period began with the step
/// timer at `first` steps into the move in flight from `pos` and whose last
/// ended at `last`.
pub fn tag(cfg: &HeadConfig, pos: &Position, first: [u32; 3], last: [u32; 3], signal: Signal) -> SweptSample {
    let axes_from = motion::axis_angles(cfg, motion::in_flight_steps(pos, first));
    let axes_to = motion::axis_angles(cfg, motion::in_flight_steps(pos, last));
    let mid = AxisAngles {
        omega_deg: 0.5 * (axes_from.omega_deg + axes_to.omega_deg),
        tau_deg: 0.5 * (axes_from.tau_deg + axes_to.tau_deg),
        psi_deg: 0.5 * (axes_from.psi_deg + axes_to.psi_deg),
    };
    SweptSample {
        seq: 0,
        start_us: 0,
        duration_s: 0.0,
        from: kinematics::forward(&axes_from),
        to: kinematics::forward(&axes_to),
        mid: kinematics::forward(&mid),
        axes_from,
        axes_to,
        signal,
    }
}

/// The geometry of a sweep's end, for its report.
pub fn reached(cfg: &HeadConfig, pos: &Position) -> Geometry {
    kinematics::forward(&pos.angles(cfg))
}
