//! Planning a sweep: the speeds of its axes within their limits, a sweep
//! scan's row (its ends, speed and slow levels across the lobes), the
//! checks a sweep must pass, and the tags of its samples from the step
//! counts.

use crate::config::HeadConfig;
use crate::kinematics;
use crate::motion::{self, Level, Levels, Limits, Position};
use gonio_shared::{Axis, AxisAngles, Fault, Field, SweepLobe, SweepRequest, SweepRow, Unreachable};
use libm::{acos, cos, sin};

const DEG: f64 = core::f64::consts::PI / 180.0;
/// How far beyond the blind zone a row begins (deg of arm): the arm's
/// microstep rounding and its backlash keep clear of it.
const BLIND_MARGIN_DEG: f64 = 0.5;

/// Limits of the axes moving by `delta` microsteps, so that the one with the
/// longest travel cruises at `speed_dps` and every axis follows the same
/// profile scaled to its travel (speeds and accelerations in proportion, the
/// common acceleration the highest every axis allows): the path is a
/// straight line in axis space, ramps included, and all arrive together.
/// Refused beyond an axis's speed limit, below [`SweepRequest::SPEED_MIN_DPS`]
/// or when the sweep would outlast [`SweepRequest::DURATION_MAX_S`].
pub fn limits(cfg: &HeadConfig, delta: [i32; 3], speed_dps: f32) -> Result<[Limits; 3], Fault> {
    if !speed_ok(speed_dps) {
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

fn speed_ok(speed_dps: f32) -> bool {
    speed_dps >= SweepRequest::SPEED_MIN_DPS && speed_dps.is_finite()
}

/// The stage angles at a sweep scan's row's start and end ([`SweepRow`]),
/// in the order it runs. The sample's normal `n(ω, τ)` stays put, at θi
/// from the light (`cos θi = cos τ·cos ω`), turned so that the view circle
/// of the arm, `D(ψ)`, meets the sample's horizon at azimuth Δφ: there
/// `D ⟂ n`, so `ψ_H = ω + 90°`, and `cos Δφ = cos ψ_H / sin θi`, the sign of
/// τ that of `sin Δφ` (`kinematics::forward`). Along the row
/// `cos θo = cos τ·cos(ω − ψ)`: the row ends where θo reaches its stop on
/// the way to the horizon, and begins just beyond the blind zone (all of it
/// in view: `|ω − ψ| < 90°` from there to `ψ_H`). Refused when the arm
/// would leave its travel or the stop lies short of the blind zone. Some
/// 25 trigonometric calls in f64 on the chip (`chip-bench`), against 90
/// for the two inverse kinematics of a [`SweepRequest`].
pub fn row_ends(cfg: &HeadConfig, row: &SweepRow) -> Result<(AxisAngles, AxisAngles), Fault> {
    let field = |x: f32, f: Field| {
        if x.is_finite() && (0.0..90.0).contains(&x) {
            Ok(x as f64 * DEG)
        } else {
            Err(Fault::InvalidValue(f))
        }
    };
    let (ti, stop) = (field(row.theta_i_deg, Field::ThetaI)?, field(row.theta_o_stop_deg, Field::ThetaO)?);
    if !row.dphi_deg.is_finite() {
        return Err(Fault::InvalidValue(Field::Dphi));
    }
    let dp = row.dphi_deg as f64 * DEG;
    let psi_h = acos((sin(ti) * cos(dp)).clamp(-1.0, 1.0));
    let omega = psi_h - 90.0 * DEG;
    // cos ω = sin ψ_H ≥ cos θi: the quotient is at most 1 but for rounding.
    let tau_abs = acos((cos(ti) / cos(omega)).min(1.0));
    let tau = if sin(dp) < 0.0 { -tau_abs } else { tau_abs };
    // θo never falls below |τ| on the circle: a stop below it is never reached.
    let reach = cos(stop) / cos(tau);
    if reach > 1.0 {
        return Err(Fault::InvalidValue(Field::ThetaO));
    }
    let psi_end = omega + acos(reach);
    let psi_start = cfg.optics.blind_max_deg as f64 * DEG + BLIND_MARGIN_DEG * DEG;
    if psi_end <= psi_start {
        return Err(Fault::Unreachable(Unreachable::BlindZone));
    }
    let at = |psi: f64| AxisAngles {
        omega_deg: (omega / DEG) as f32,
        tau_deg: (tau / DEG) as f32,
        psi_deg: (psi / DEG) as f32,
    };
    let (a, b) = (at(psi_start), at(psi_end));
    kinematics::check_travel(cfg, &a)?;
    kinematics::check_travel(cfg, &b)?;
    Ok(if row.outward { (a, b) } else { (b, a) })
}

/// What a sweep scan's row runs, worked out once for the head
/// (`Head::sweep_turn`) and for the host's estimate alike: the stage targets
/// of its start and end, the axes' limits at its speed and its stretches.
pub struct RowPlan {
    pub start: [i32; 3],
    pub end: [i32; 3],
    pub limits: [Limits; 3],
    pub levels: Levels,
}

impl RowPlan {
    /// The microsteps each axis moves from the row's start to its end.
    pub fn delta(&self) -> [i32; 3] {
        [0, 1, 2].map(|i| self.end[i] - self.start[i])
    }
}

/// The plan of a sweep scan's row ([`row_ends`], [`row_speed`], [`limits`],
/// [`row_levels`]) for samples of its periods at `chop_hz`.
pub fn row_plan(cfg: &HeadConfig, row: &SweepRow, chop_hz: f32) -> Result<RowPlan, Fault> {
    let (from, to) = row_ends(cfg, row)?;
    let speed = row_speed(cfg, row);
    let (start, end) = (motion::target_steps(cfg, &from), motion::target_steps(cfg, &to));
    let limits = limits(cfg, [0, 1, 2].map(|i| end[i] - start[i]), speed)?;
    let levels = row_levels(row, &from, &to, speed, row.periods_per_sample as f32 / chop_hz);
    Ok(RowPlan {
        start,
        end,
        limits,
        levels,
    })
}

/// The speed a sweep scan's row runs at: its own, at most the arm's limit
/// (the arm alone moves).
pub fn row_speed(cfg: &HeadConfig, row: &SweepRow) -> f32 {
    row.speed_dps.min(cfg.axes[Axis::Arm.index()].max_speed_dps)
}

/// The stretches of a sweep scan's row from `from` to `to` (its ends,
/// [`row_ends`]) at `speed_dps`, with samples of `sample_s`: slower within
/// [`SweepLobe::ZONE_WIDTHS`] lobe widths of the retro and of the mirror
/// direction, so that a sample there spans at most the lobe's
/// `extent_fraction` of its width; none without a lobe or where the row's
/// own speed is slow enough. The arm alone moves, so a fraction of the way is
/// one of ψ. The retro direction is ψ = 0. The mirror direction `m`:
/// `D(ψ)·m = 2cosθi·(n·D(ψ)) − cos ψ = A cos ψ + B sin ψ = R cos(ψ − ψm)`
/// with `A = cos 2θi`, `B = 2 cosθi·cosτ·sinω` (`n·D(ψ) = cosτ·cos(ω − ψ)`,
/// `cosθi = cosτ·cosω`): its zone is `|ψ − ψm| < acos(cos(3w)/R)` where
/// the row comes that close. Ten trigonometric calls in f64.
pub fn row_levels(row: &SweepRow, from: &AxisAngles, to: &AxisAngles, speed_dps: f32, sample_s: f32) -> Levels {
    let mut out = Levels::new();
    let Some(lobe) = row.lobe else {
        return out;
    };
    // `lobe.slow_dps(sample_s) / speed_dps`, in an order of rounding of its
    // own, kept so that `scan-bench`'s sweep figures reproduce bit for bit.
    let scale = lobe.extent_fraction * lobe.width_deg / (sample_s * speed_dps);
    if !(scale < 1.0 && scale > 0.0) {
        return out;
    }
    let half = (SweepLobe::ZONE_WIDTHS * lobe.width_deg) as f64 * DEG;
    let (ti, omega, tau) = (row.theta_i_deg as f64 * DEG, from.omega_deg as f64 * DEG, from.tau_deg as f64 * DEG);
    let (a, b) = (cos(2.0 * ti), 2.0 * cos(ti) * cos(tau) * sin(omega));
    let r = libm::hypot(a, b);
    let mut zones: heapless::Vec<(f64, f64), 2> = heapless::Vec::new();
    let _ = zones.push((-half, half));
    if r > cos(half) {
        // A zone wider than 90° a side (lobes over 30° wide) spans the row.
        let (mid, h) = (libm::atan2(b, a), acos((cos(half) / r).clamp(-1.0, 1.0)));
        let _ = zones.push((mid - h, mid + h));
    }
    // Each zone as a stretch of the way (0 at `from`, 1 at `to`), in order.
    let (p0, p1) = (from.psi_deg as f64 * DEG, to.psi_deg as f64 * DEG);
    let way = |psi: f64| ((psi - p0) / (p1 - p0)).clamp(0.0, 1.0) as f32;
    let mut stretches: heapless::Vec<(f32, f32), 2> = zones
        .iter()
        .map(|&(lo, hi)| {
            let (x, y) = (way(lo), way(hi));
            (x.min(y), x.max(y))
        })
        .collect();
    stretches.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut at = 0.0f32;
    for (lo, hi) in stretches {
        if hi <= at || hi <= lo {
            continue;
        }
        match out.last_mut() {
            // Overlapping zones make one slow stretch.
            Some(last) if lo <= at => last.until = hi,
            _ => {
                if lo > at {
                    let _ = out.push(Level { until: lo, scale: 1.0 });
                }
                let _ = out.push(Level { until: hi, scale });
            }
        }
        at = hi;
    }
    if out.is_empty() {
        return out;
    }
    if at < 1.0 {
        let _ = out.push(Level { until: 1.0, scale: 1.0 });
    }
    out
}

/// Checks a sweep's sample length, speed and lobe (its ends are checked by
/// [`crate::kinematics::inverse`], its speed against the axes by [`limits`]).
/// A lobe is refused when its slow stretches would go slower than
/// [`SweepRequest::SPEED_MIN_DPS`], or when the arm's whole travel at that
/// speed would outlast [`SweepRequest::DURATION_MAX_S`] (what the step timer
/// counts): a row whose stretches overflow the queue runs slow all along
/// ([`motion::plan`]), so no row of the scan can.
pub fn check(cfg: &HeadConfig, periods_per_sample: u16, speed_dps: f32, lobe: Option<&SweepLobe>, chop_hz: f32) -> Result<(), Fault> {
    if !(SweepRequest::PERIODS_MIN..=SweepRequest::PERIODS_MAX).contains(&periods_per_sample) {
        return Err(Fault::InvalidValue(Field::Periods));
    }
    if !speed_ok(speed_dps) {
        return Err(Fault::InvalidValue(Field::SweepSpeed));
    }
    if let Some(l) = lobe {
        let slow = l.slow_dps(periods_per_sample as f32 / chop_hz);
        let arm = &cfg.axes[Axis::Arm.index()];
        let (travel, slowest) = (arm.max_deg - arm.min_deg, slow.min(speed_dps).min(arm.max_speed_dps));
        if !l.valid() || !speed_ok(slow) || travel / slowest > SweepRequest::DURATION_MAX_S {
            return Err(Fault::InvalidValue(Field::SweepLobe));
        }
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
    use gonio_shared::{AngleRange, Geometry, ScanSpec, SweepScan, Visit};
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

    proptest! {
        /// A row keeps its incidence all along, stays in view, begins just
        /// beyond the blind zone, ends at its θo stop, and its circle meets
        /// the horizon at its Δφ.
        #[test]
        fn a_row_holds_its_incidence_from_the_blind_zone_to_its_stop(
            ti in 0.0f32..85.0, dp in -180.0f32..180.0, stop in 1.0f32..89.5, outward: bool,
        ) {
            let row = SweepRow { theta_i_deg: ti, dphi_deg: dp, theta_o_stop_deg: stop, outward, speed_dps: 10.0, periods_per_sample: 8, lobe: None };
            let (a, b) = match row_ends(&REFERENCE, &row) {
                Ok(ends) => ends,
                Err(Fault::InvalidValue(Field::ThetaO) | Fault::Unreachable(_)) => return Ok(()),
                Err(f) => return Err(TestCaseError::fail(format!("{f:?}"))),
            };
            let (near, far) = if outward { (a, b) } else { (b, a) };
            prop_assert_eq!((a.omega_deg, a.tau_deg), (b.omega_deg, b.tau_deg));
            prop_assert!((near.psi_deg - REFERENCE.optics.blind_max_deg - 0.5).abs() < 1e-3);
            prop_assert!((kinematics::forward(&far).theta_o_deg - stop).abs() < 0.01, "{:?}", kinematics::forward(&far));
            let (worst, blind) = walked(&a, &b);
            prop_assert!(worst < 90.0 && !blind);
            for k in 0..=20 {
                let psi = near.psi_deg + (far.psi_deg - near.psi_deg) * k as f32 / 20.0;
                let g = kinematics::forward(&AxisAngles { psi_deg: psi, ..a });
                prop_assert!((g.theta_i_deg - ti).abs() < 0.01, "θi {} at ψ {psi}", g.theta_i_deg);
            }
            if ti > 1.0 {
                let horizon = kinematics::forward(&AxisAngles { psi_deg: a.omega_deg + 90.0, ..a });
                let off = crate::units::wrap_deg((horizon.dphi_deg - dp) as f64).abs();
                prop_assert!((horizon.theta_o_deg - 90.0).abs() < 0.01 && off < 0.05, "{horizon:?} for Δφ {dp}");
            }
        }
    }

    proptest! {
        /// Neighbouring rows of a sweep scan lie nowhere farther apart than
        /// the grid's Δφ step where its span closes the circle, from any
        /// start, the last row beside the first included: the angle between
        /// their planes, each through the laser and a point of the row as
        /// the forward kinematics place it, is at most the step (rows evenly
        /// spaced at the horizon instead are 19.4° apart next to the plane
        /// of incidence at θi = 60° for a 10° step). Over a part of the
        /// circle they are turned evenly, at most 1/cos θi times the step
        /// apart.
        #[test]
        fn neighbouring_rows_are_at_most_the_dphi_step_apart(
            ti in 0.5f32..72.0, step in 2u32..40, start in -180i32..180, part in 0.0f32..1.0,
        ) {
            // (Beyond θi ≈ 75° a row towards the horizon would start past
            // it: rows start beyond the plate's shadow, 11.5° from the laser.)
            // Whole degrees: the span's ends exact in f32, a whole circle
            // never a rounding beyond 360°.
            let (step, start) = (step as f32, start as f32);
            let whole = (360.0 / step) as u32 + 1;
            // The span over the whole circle (both ends on it, or beyond
            // it), a step short of it (where the step divides 360°), and a
            // part of it.
            let short = (360.0 / step).ceil() as u32;
            for n in [whole, short, 2 + ((whole - 3) as f32 * part) as u32] {
                let spec = ScanSpec {
                    theta_i_deg: heapless::Vec::from_slice(&[ti]).unwrap(),
                    theta_o: AngleRange::new(0.0, 87.0, 3.0),
                    dphi: AngleRange::new(start, start + step * (n - 1) as f32, step),
                    first_order: 0,
                    sweep: Some(SweepScan { speed_dps: 30.0, periods_per_sample: 8, lobe: None }),
                    patterns: None,
                };
                // Positions 1..=n are the rows (0 is the retro point).
                prop_assert_eq!(spec.len(), n + 1);
                let normal = |i: u32| {
                    let Some(Visit::Row(row)) = spec.visit(i, 0) else { return None };
                    let (a, _) = row_ends(&REFERENCE, &row).ok()?;
                    let g = kinematics::forward(&AxisAngles { psi_deg: 60.0, ..a });
                    let (i, o, d) = (g.theta_i_deg as f64 * DEG, g.theta_o_deg as f64 * DEG, g.dphi_deg as f64 * DEG);
                    let (l, v) = ([sin(i), 0.0, cos(i)], [sin(o) * cos(d), sin(o) * sin(d), cos(o)]);
                    let n = [l[1] * v[2] - l[2] * v[1], l[2] * v[0] - l[0] * v[2], l[0] * v[1] - l[1] * v[0]];
                    let norm = libm::sqrt(n.iter().map(|x| x * x).sum::<f64>());
                    Some(n.map(|x| x / norm))
                };
                let apart = |p: [f64; 3], q: [f64; 3]| acos(p.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>().clamp(-1.0, 1.0)) / DEG;
                let closing = n >= short;
                let pairs = (1..n).map(|k| (k, k + 1)).chain(closing.then_some((n, 1)));
                let gaps: Vec<f64> = pairs.filter_map(|(a, b)| Some(apart(normal(a)?, normal(b)?))).collect();
                prop_assert!(gaps.len() as u32 >= n - 1, "rows refused: {gaps:?}");
                let bound = match closing {
                    true => step as f64,
                    false => step as f64 / cos(ti as f64 * DEG),
                };
                prop_assert!(gaps.iter().all(|&g| g <= bound + 0.01), "θi {ti}, {n} rows from {start}: {gaps:?}");
                if !closing {
                    prop_assert!(gaps.iter().all(|&g| (g - gaps[0]).abs() < 0.02), "not evenly turned: {gaps:?}");
                }
            }
        }
    }

    proptest! {
        /// A row runs slow exactly within three lobe widths of the retro and
        /// of the mirror direction, as the forward kinematics place them
        /// (not the formula `row_levels` uses), and at its own speed
        /// elsewhere.
        #[test]
        fn a_row_slows_down_within_three_widths_of_either_peak(
            ti in 5.0f32..75.0, dp in -180.0f32..180.0, width in 0.3f32..40.0, fraction in 0.01f32..1.0, outward: bool,
        ) {
            let lobe = SweepLobe { width_deg: width, extent_fraction: fraction };
            let row = SweepRow {
                theta_i_deg: ti, dphi_deg: dp, theta_o_stop_deg: 87.0, outward, speed_dps: 30.0, periods_per_sample: 8,
                lobe: Some(lobe),
            };
            let Ok((a, b)) = row_ends(&REFERENCE, &row) else {
                return Ok(());
            };
            let sample_s = 8.0 / 230.0;
            let levels = row_levels(&row, &a, &b, 30.0, sample_s);
            let slow = fraction * width / (sample_s * 30.0);
            prop_assert!(levels.windows(2).all(|w| w[0].until < w[1].until));
            let zone = SweepLobe::ZONE_WIDTHS * width;
            for k in 0..=400 {
                let x = k as f32 / 400.0;
                let g = kinematics::forward(&AxisAngles { psi_deg: a.psi_deg + (b.psi_deg - a.psi_deg) * x, ..a });
                let (i, o, d) = (g.theta_i_deg as f64 * DEG, g.theta_o_deg as f64 * DEG, g.dphi_deg as f64 * DEG);
                let angle = |sign: f64| acos((cos(i) * cos(o) + sign * sin(i) * sin(o) * cos(d)).clamp(-1.0, 1.0)) / DEG;
                let near = angle(1.0).min(angle(-1.0)) as f32;
                let scale = levels.iter().find(|l| x <= l.until).map_or(1.0, |l| l.scale);
                if near < zone - 0.05 {
                    prop_assert!((scale - slow.min(1.0)).abs() < 1e-6, "{near}° from a peak at {x}: scale {scale} {levels:?}");
                } else if near > zone + 0.05 {
                    prop_assert!(scale == 1.0, "{near}° from the peaks at {x}: scale {scale} {levels:?}");
                }
            }
        }
    }

    #[test]
    fn a_lobe_that_would_make_a_row_outlast_the_step_timer_is_refused() {
        let lobe = |width_deg, extent_fraction| SweepLobe {
            width_deg,
            extent_fraction,
        };
        let ok = |l: SweepLobe, chop_hz| check(&REFERENCE, 8, 30.0, Some(&l), chop_hz);
        assert_eq!(ok(lobe(1.8, 0.25), 230.0), Ok(()));
        // 0.05° at a hundredth: 0.014°/s, the arm's travel in hours.
        assert_eq!(ok(lobe(0.05, 0.01), 230.0), Err(Fault::InvalidValue(Field::SweepLobe)));
        // A chop of 1 Hz: 8 s samples.
        assert_eq!(ok(lobe(0.05, 0.25), 1.0), Err(Fault::InvalidValue(Field::SweepLobe)));
        // At the bound: the arm's travel in 3 000 s at a hundredth of the
        // width a sample (8 periods at 230 Hz).
        let arm = &REFERENCE.axes[Axis::Arm.index()];
        let width = (arm.max_deg - arm.min_deg) / SweepRequest::DURATION_MAX_S * 8.0 / (0.01 * 230.0);
        assert_eq!(ok(lobe(width * 1.01, 0.01), 230.0), Ok(()));
        assert_eq!(ok(lobe(width * 0.99, 0.01), 230.0), Err(Fault::InvalidValue(Field::SweepLobe)));
        for bad in [lobe(f32::NAN, 0.25), lobe(1.0, 0.0), lobe(1.0, 1.5), lobe(f32::INFINITY, 0.25)] {
            assert_eq!(ok(bad, 230.0), Err(Fault::InvalidValue(Field::SweepLobe)), "{bad:?}");
        }
    }

    #[test]
    fn every_axis_follows_the_same_profile_scaled_to_its_travel() {
        let delta = [1600, -800, 0];
        let l = limits(&REFERENCE, delta, 4.0).unwrap();
        let t = [0, 1].map(|i| motion::ramp(&REFERENCE.axes[i], delta[i].unsigned_abs(), l[i], &[]));
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
