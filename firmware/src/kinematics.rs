//! Forward and inverse kinematics of the head (the lab frame below, the
//! reference head's travel and blind zone in [`crate::config::REFERENCE`]),
//! and the reachability check that refuses a target before anything moves.
//!
//! Lab frame: laser at `L = (1,0,0)`, detector at `D(ψ) = (cosψ, sinψ, 0)`,
//! sample normal `n(ω,τ) = (cosτ cosω, cosτ sinω, sinτ)`. The sign of τ
//! follows the sign of `sin Δφ` (the other sign is the mirror solution), and
//! ψ ≥ 0. Computed in f64 (`libm`) through `atan2` forms, which keep full
//! precision near the retro direction and near normal incidence where `acos`
//! would lose half the digits; one inverse solution per move makes the cost of
//! soft-float f64 on the Cortex-M4 irrelevant.

use crate::config::HeadConfig;
use crate::units;
use gonio_shared::{Axis, AxisAngles, Fault, Field, Geometry, Unreachable};
use libm::{atan2, cos, sin, sqrt};

const DEG: f64 = core::f64::consts::PI / 180.0;

fn norm3(a: [f64; 3]) -> f64 {
    sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Angle between two unit vectors, accurate at 0 and π.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    atan2(norm3(cross(a, b)), dot(a, b))
}

/// Checks a requested geometry's fields (finite, θ in [0°, 90°), |Δφ| ≤ 360°).
pub fn validate(g: &Geometry) -> Result<(), Fault> {
    let field = |x: f32, f: Field, max: f32| {
        if !x.is_finite() || x < -max || x > max {
            Err(Fault::InvalidValue(f))
        } else {
            Ok(())
        }
    };
    field(g.theta_i_deg, Field::ThetaI, 360.0)?;
    field(g.theta_o_deg, Field::ThetaO, 360.0)?;
    field(g.dphi_deg, Field::Dphi, 360.0)?;
    if g.theta_i_deg < 0.0 {
        return Err(Fault::InvalidValue(Field::ThetaI));
    }
    if g.theta_o_deg < 0.0 {
        return Err(Fault::InvalidValue(Field::ThetaO));
    }
    if g.theta_i_deg >= 90.0 || g.theta_o_deg >= 90.0 {
        return Err(Fault::Unreachable(Unreachable::BehindSample));
    }
    Ok(())
}

/// Stage angles for a geometry, without travel checks.
pub fn inverse_unchecked(g: &Geometry) -> AxisAngles {
    let (ti, to, dp) = (g.theta_i_deg as f64 * DEG, g.theta_o_deg as f64 * DEG, g.dphi_deg as f64 * DEG);
    // Light and view in the sample frame.
    let l = [sin(ti), 0.0, cos(ti)];
    let v = [sin(to) * cos(dp), sin(to) * sin(dp), cos(to)];
    let psi = angle(l, v);
    if psi < 1e-12 {
        return AxisAngles {
            omega_deg: g.theta_i_deg,
            tau_deg: 0.0,
            psi_deg: 0.0,
        };
    }
    let (ci, co, cpsi, spsi) = (l[2], v[2], cos(psi), sin(psi));
    let a = ci; // cosτ·cosω
    let b = (co - ci * cpsi) / spsi; // cosτ·sinω
    let ctau = sqrt(a * a + b * b);
    let stau_abs = sqrt((1.0 - ctau * ctau).max(0.0));
    let stau = if sin(dp) < 0.0 { -stau_abs } else { stau_abs };
    AxisAngles {
        omega_deg: (atan2(b, a) / DEG) as f32,
        tau_deg: (atan2(stau, ctau) / DEG) as f32,
        psi_deg: (psi / DEG) as f32,
    }
}

/// Geometry seen at given stage angles.
pub fn forward(a: &AxisAngles) -> Geometry {
    let (om, ta, ps) = (a.omega_deg as f64 * DEG, a.tau_deg as f64 * DEG, a.psi_deg as f64 * DEG);
    let n = [cos(ta) * cos(om), cos(ta) * sin(om), sin(ta)];
    let l = [1.0, 0.0, 0.0];
    let d = [cos(ps), sin(ps), 0.0];
    let (ti, to) = (angle(n, l), angle(n, d));
    // sinΔφ·sinθi·sinθo = n·(L×D), cosΔφ·sinθi·sinθo = L·D − cosθi cosθo.
    let y = dot(n, cross(l, d));
    let x = dot(l, d) - dot(n, l) * dot(n, d);
    let dphi = if sin(ti) * sin(to) < 1e-12 { 0.0 } else { atan2(y, x) };
    Geometry::new((ti / DEG) as f32, (to / DEG) as f32, units::wrap_deg(dphi / DEG) as f32)
}

/// Stage angles for a geometry the head can reach, or why it cannot.
pub fn inverse(cfg: &HeadConfig, g: &Geometry) -> Result<AxisAngles, Fault> {
    validate(g)?;
    let a = inverse_unchecked(g);
    let psi = a.psi_deg.abs();
    if psi > cfg.optics.retro_max_deg && psi < cfg.optics.blind_max_deg {
        return Err(Fault::Unreachable(Unreachable::BlindZone));
    }
    check_travel(cfg, &a)?;
    Ok(a)
}

/// Refuses stage angles outside any axis's soft limits.
pub fn check_travel(cfg: &HeadConfig, a: &AxisAngles) -> Result<(), Fault> {
    for (axis, deg) in [(Axis::Rotation, a.omega_deg), (Axis::Cradle, a.tau_deg), (Axis::Arm, a.psi_deg)] {
        let c = cfg.axis(axis);
        if !(deg >= c.min_deg && deg <= c.max_deg) {
            return Err(Fault::Unreachable(Unreachable::AxisTravel(axis)));
        }
    }
    Ok(())
}

/// True when the detector sees the sample through the beam splitter.
pub fn through_splitter(cfg: &HeadConfig, a: &AxisAngles) -> bool {
    a.psi_deg.abs() <= cfg.optics.retro_max_deg
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::REFERENCE;
    use proptest::prelude::*;

    #[test]
    fn retro_direction_is_arm_zero() {
        let a = inverse(&REFERENCE, &Geometry::new(30.0, 30.0, 0.0)).unwrap();
        assert_eq!((a.omega_deg, a.tau_deg, a.psi_deg), (30.0, 0.0, 0.0));
        assert!(through_splitter(&REFERENCE, &a));
    }

    #[test]
    fn refusals_name_the_reason() {
        let r = |g| inverse(&REFERENCE, &g).unwrap_err();
        assert_eq!(r(Geometry::new(30.0, 38.0, 0.0)), Fault::Unreachable(Unreachable::BlindZone));
        // Within 5° of the laser the splitter shows the sample.
        assert!(through_splitter(
            &REFERENCE,
            &inverse(&REFERENCE, &Geometry::new(30.0, 34.5, 0.0)).unwrap()
        ));
        assert_eq!(r(Geometry::new(30.0, 90.0, 0.0)), Fault::Unreachable(Unreachable::BehindSample));
        assert_eq!(r(Geometry::new(f32::NAN, 10.0, 0.0)), Fault::InvalidValue(Field::ThetaI));
        assert_eq!(r(Geometry::new(10.0, -1.0, 0.0)), Fault::InvalidValue(Field::ThetaO));
        // Mirror configuration at grazing angles puts the arm past its travel.
        assert_eq!(
            r(Geometry::new(87.0, 87.0, 180.0)),
            Fault::Unreachable(Unreachable::AxisTravel(Axis::Arm))
        );
    }

    proptest! {
        #[test]
        fn forward_inverts_inverse(ti in 0.5f32..89.5, to in 0.5f32..89.5, dp in -179.5f32..179.5) {
            let g = Geometry::new(ti, to, dp);
            let back = forward(&inverse_unchecked(&g));
            // Well under the finest microstep (1/1600°).
            prop_assert!((back.theta_i_deg - ti).abs() < 1e-4);
            prop_assert!((back.theta_o_deg - to).abs() < 1e-4);
            prop_assert!((back.dphi_deg - dp).abs() < 1e-3, "{:?} -> {:?}", g, back);
        }
    }
}
