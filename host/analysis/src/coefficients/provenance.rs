//! What a coefficient rests on (`docs/retroreflection.md`, *Provenance*):
//! the measured samples about the retro direction a data set holds (its
//! [`Support`]), and whether a requested geometry lies on them, between
//! them, or where only a model can carry a value.
//!
//! - **measured**: a sample at the geometry (within [`MEASURED_WITHIN_DEG`]:
//!   its value is the coefficient, corrected for the apertures);
//! - **interpolated**: at a measured incidence, surrounded on every side by
//!   the samples within [`INTERPOLATION_GAP_DEG`] (what a ring pattern holds
//!   between its rings and views);
//! - **extrapolated**: anything else: an incidence the data do not hold
//!   (the entrance angles of ASTM E810 outside 15–60°, EN 1436's 88.76°), the
//!   plate's shadow, or a gap wider than the data's own spacing. Only a model
//!   carries the value there, and models that fit the data alike disagree.

use crate::fit::{Dataset, Units};
use anyhow::{bail, Context, Result};
use gonio_brdf::frame::{angle_between, cross, dot, normalize};
use gonio_brdf::Directions;
use serde::Serialize;
use serde_json::{json, Value};

/// Samples within this angle of the retro direction (light–view angle) are
/// the support: every coefficient lies within 10° of it (`validate`).
pub const SUPPORT_DEG: f64 = 12.0;
/// Two incidences within this of each other are one (a head reports θi to
/// f32, its stages to a microstep).
pub const INCIDENCE_TOL_DEG: f64 = 0.1;
/// A sample this close to a requested view (degrees) measured it: below the
/// stages' zero uncertainty (0.02°) and a tenth of the reference detector's
/// field.
pub const MEASURED_WITHIN_DEG: f64 = 0.02;
/// Samples up to this far (degrees) interpolate, when they surround the
/// view: the reference retro rings are at most 1° apart.
pub const INTERPOLATION_GAP_DEG: f64 = 1.0;
/// Samples a view's curvature is fitted through (a quadratic has 6
/// coefficients; on the reference rings these reach the next ring out and in).
pub const CURVATURE_SAMPLES: usize = 40;

/// How a value was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Provenance {
    Measured,
    Interpolated,
    Extrapolated,
}

impl Provenance {
    pub fn name(self) -> &'static str {
        match self {
            Provenance::Measured => "measured",
            Provenance::Interpolated => "interpolated",
            Provenance::Extrapolated => "extrapolated",
        }
    }
}

/// A provenance and the reason for it, in a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Basis {
    pub provenance: Provenance,
    pub why: String,
}

/// A measured value (`f_r`, sr⁻¹), its standard uncertainty, and how much
/// it moves with the arm's zero (`shift_zero_psi_sr`: the calibration's
/// model slope times the zero's uncertainty; 0 where the data say nothing).
#[derive(Debug, Clone)]
pub struct Point {
    pub d: Directions,
    pub angles_deg: [f64; 3],
    pub value: f64,
    pub sigma: f64,
    pub shift_psi: f64,
}

/// The measured `f_r` about a view, to second order: its Laplacian across
/// the view (sr⁻¹ per square degree) with its standard error, and its slope
/// away from the laser (sr⁻¹ per degree of observation angle), which is
/// what the arm's angle moves it along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    pub laplacian: f64,
    pub laplacian_se: f64,
    pub slope_alpha: f64,
}

/// The measured samples a coefficient may rest on: those within
/// [`SUPPORT_DEG`] of the retro direction, and every incidence the data
/// hold.
#[derive(Debug, Clone, Default)]
pub struct Support {
    pub points: Vec<Point>,
    pub incidences_deg: Vec<f64>,
}

fn point(angles_deg: [f64; 3], value: f64, sigma: f64, shift_psi: f64) -> Point {
    Point {
        d: Directions::from_degrees(angles_deg[0], angles_deg[1], angles_deg[2]),
        angles_deg,
        value,
        sigma,
        shift_psi,
    }
}

/// Where `shift_zero_psi_sr` stands among an observation's shared shifts.
const ZERO_PSI: usize = 4;

impl Support {
    /// The support of a data set (values in `f_r·cosθo` are converted).
    pub fn of(data: &Dataset) -> Result<Self> {
        let data = data.in_units(Units::Fr)?;
        let mut incidences_deg: Vec<f64> = Vec::new();
        let mut points = Vec::new();
        for o in &data.observations {
            let ti = o.theta_i.to_degrees();
            if !incidences_deg.iter().any(|t| (t - ti).abs() <= INCIDENCE_TOL_DEG) {
                incidences_deg.push(ti);
            }
            if angle_between(o.directions().l, o.directions().v).to_degrees() <= SUPPORT_DEG {
                let angles = [ti, o.theta_o.to_degrees(), o.dphi.to_degrees()];
                points.push(point(angles, o.value, o.sigma.unwrap_or(0.0), o.shared[ZERO_PSI]));
            }
        }
        incidences_deg.sort_by(f64::total_cmp);
        Ok(Support { points, incidences_deg })
    }

    /// As a fit file keeps it: `{"incidences_deg", "retro": [[θi, θo, Δφ,
    /// f_r, σ, shift_zero_psi], …]}`.
    pub fn to_json(&self) -> Value {
        let rows: Vec<[f64; 6]> = self
            .points
            .iter()
            .map(|p| [p.angles_deg[0], p.angles_deg[1], p.angles_deg[2], p.value, p.sigma, p.shift_psi])
            .collect();
        json!({"incidences_deg": self.incidences_deg, "support_deg": SUPPORT_DEG, "retro": rows})
    }

    pub fn from_json(v: &Value) -> Result<Self> {
        let incidences_deg: Vec<f64> =
            serde_json::from_value(v["incidences_deg"].clone()).context("`support.incidences_deg` is not a list of numbers")?;
        let rows: Vec<[f64; 6]> =
            serde_json::from_value(v["retro"].clone()).context("`support.retro` is not a list of [θi, θo, Δφ, f_r, σ, shift_zero_psi]")?;
        if rows.iter().flatten().any(|x| !x.is_finite()) || incidences_deg.iter().any(|x| !x.is_finite()) {
            bail!("`support` holds a number that is not finite");
        }
        Ok(Support {
            points: rows.iter().map(|r| point([r[0], r[1], r[2]], r[3], r[4], r[5])).collect(),
            incidences_deg,
        })
    }

    /// The measured incidence within [`INCIDENCE_TOL_DEG`] of `theta_i_deg`.
    fn incidence(&self, theta_i_deg: f64) -> Option<f64> {
        self.incidences_deg
            .iter()
            .copied()
            .find(|t| (t - theta_i_deg).abs() <= INCIDENCE_TOL_DEG)
    }

    /// The views measured at the incidence `theta_i_deg` (and their mirror
    /// images across the plane of incidence: the BRDF is isotropic), each
    /// with its distance (rad) from `v`, nearest first.
    fn views_near(&self, theta_i_deg: f64, v: [f64; 3]) -> Vec<([f64; 3], f64)> {
        self.samples_near(theta_i_deg, v).into_iter().map(|(w, d, _)| (w, d)).collect()
    }

    /// As [`Support::views_near`], with each view's sample.
    fn samples_near(&self, theta_i_deg: f64, v: [f64; 3]) -> Vec<([f64; 3], f64, &Point)> {
        let mut out: Vec<([f64; 3], f64, &Point)> = self
            .points
            .iter()
            .filter(|p| (p.angles_deg[0] - theta_i_deg).abs() <= INCIDENCE_TOL_DEG)
            .flat_map(|p| {
                let mirrored = [p.d.v[0], -p.d.v[1], p.d.v[2]];
                [(p.d.v, p), (mirrored, p)]
            })
            .map(|(w, p)| (w, angle_between(w, v), p))
            .collect();
        out.sort_by(|a, b| a.1.total_cmp(&b.1));
        // A view on the plane of incidence is its own mirror image, and a
        // pattern symmetric about the plane holds each image already.
        let mut distinct: Vec<([f64; 3], f64, &Point)> = Vec::with_capacity(out.len());
        for c in out {
            if !distinct
                .iter()
                .rev()
                .take_while(|d| c.1 - d.1 < 1e-9)
                .any(|d| angle_between(d.0, c.0) < 1e-9)
            {
                distinct.push(c);
            }
        }
        distinct
    }

    /// The measured `f_r` about the view of `want` ([`Local`]): a weighted
    /// least-squares quadratic in the tangent plane through the
    /// [`CURVATURE_SAMPLES`] nearest samples at the incidence. Its
    /// Laplacian is what a finite aperture changes a reading by, to second
    /// order, its slope what the arm's zero does (`source.rs`). `None`
    /// where too few samples surround the view for a quadratic.
    pub fn local(&self, want: &Directions) -> Option<Local> {
        let (ti, _, _) = want.angles();
        let at = self.incidence(ti.to_degrees())?;
        let near = self.samples_near(at, want.v);
        let near = &near[..near.len().min(CURVATURE_SAMPLES)];
        if near.len() < CURVATURE_SAMPLES {
            return None;
        }
        let (e1, e2) = tangent(want.v);
        let rows: Vec<([f64; 6], f64, f64)> = near
            .iter()
            .map(|(w, _, p)| {
                let c = dot(*w, want.v);
                let (x, y) = (dot(*w, e1).atan2(c).to_degrees(), dot(*w, e2).atan2(c).to_degrees());
                let weight = if p.sigma > 0.0 { 1.0 / (p.sigma * p.sigma) } else { 1.0 };
                ([1.0, x, y, x * x, x * y, y * y], p.value, weight)
            })
            .collect();
        let mut normal = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        let mut rhs = nalgebra::SVector::<f64, 6>::zeros();
        for (a, f, w) in &rows {
            let a = nalgebra::SVector::<f64, 6>::from_column_slice(a);
            normal += *w * a * a.transpose();
            rhs += *w * *f * a;
        }
        let inv = normal.try_inverse()?;
        let c = inv * rhs;
        // Without budgets (unit weights) the scatter about the quadratic sets
        // the scale of the covariance.
        let scale = if rows.iter().all(|r| r.2 == 1.0) {
            let a_c = |a: &[f64; 6]| a.iter().zip(c.iter()).map(|(x, k)| x * k).sum::<f64>();
            rows.iter().map(|(a, f, _)| (f - a_c(a)).powi(2)).sum::<f64>() / (rows.len() - 6) as f64
        } else {
            1.0
        };
        let var = scale * (inv[(3, 3)] + inv[(5, 5)] + 2.0 * inv[(3, 5)]);
        let lap = 2.0 * (c[3] + c[5]);
        // Away from the laser: along the great circle from l through v.
        let d = [0, 1, 2].map(|i| want.v[i] - want.l[i]);
        let along = [0, 1, 2].map(|i| d[i] - dot(d, want.v) * want.v[i]);
        let n = dot(along, along).sqrt();
        let slope_alpha = match n > 1e-12 {
            true => (c[1] * dot(along, e1) + c[2] * dot(along, e2)) / n,
            false => 0.0,
        };
        (lap.is_finite() && var >= 0.0 && slope_alpha.is_finite()).then_some(Local {
            laplacian: lap,
            laplacian_se: 2.0 * var.sqrt(),
            slope_alpha,
        })
    }

    /// What a coefficient at nominal directions `want` rests on.
    pub fn classify(&self, want: &Directions) -> Basis {
        let (ti, _, _) = want.angles();
        let ti = ti.to_degrees();
        let extrapolated = |why: String| Basis {
            provenance: Provenance::Extrapolated,
            why,
        };
        let Some(at) = self.incidence(ti) else {
            let list: Vec<String> = self.incidences_deg.iter().map(|t| format!("{t:.4}°")).collect();
            return extrapolated(format!("θi {ti:.2}° was not measured (the data hold θi {})", list.join(", ")));
        };
        let views = self.views_near(at, want.v);
        let Some(&(_, nearest)) = views.first() else {
            return extrapolated(format!("no sample within {SUPPORT_DEG}° of the retro direction at θi {at:.4}°"));
        };
        let nearest_deg = nearest.to_degrees();
        if nearest_deg <= MEASURED_WITHIN_DEG {
            return Basis {
                provenance: Provenance::Measured,
                why: format!("a sample {nearest_deg:.3}° from the geometry"),
            };
        }
        let within = views.partition_point(|v| v.1.to_degrees() <= INTERPOLATION_GAP_DEG);
        let near = &views[..within];
        if near.len() >= 3 && surrounds(want.v, near) {
            return Basis {
                provenance: Provenance::Interpolated,
                why: format!(
                    "between the {} samples within {INTERPOLATION_GAP_DEG}°, on every side (the nearest {nearest_deg:.2}° away)",
                    near.len()
                ),
            };
        }
        extrapolated(format!(
            "the nearest sample is {nearest_deg:.2}° away and none surround it within {INTERPOLATION_GAP_DEG}°"
        ))
    }
}

/// Two unit vectors spanning the tangent plane at `v`.
fn tangent(v: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if v[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let e1 = normalize(cross(v, helper));
    (e1, cross(v, e1))
}

/// Whether the views `near` lie around `v` on every side: their azimuths
/// about it, in its tangent plane, leave no gap of half a turn.
fn surrounds(v: [f64; 3], near: &[([f64; 3], f64)]) -> bool {
    let (e1, e2) = tangent(v);
    let mut az: Vec<f64> = near.iter().map(|(w, _)| dot(*w, e2).atan2(dot(*w, e1))).collect();
    az.sort_by(f64::total_cmp);
    let wrap = az[0] + std::f64::consts::TAU - az[az.len() - 1];
    let widest = az.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max);
    widest < std::f64::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_shared::LobePatterns;

    /// The reference rings at 15° and 30°, and the retro point, as a scan holds them.
    fn ring_support() -> Support {
        let p = LobePatterns::cea();
        let mut points = Vec::new();
        for ti in [15.0f32, 30.0] {
            points.push(point([ti as f64, ti as f64, 0.0], 1.0, 0.01, 0.0));
            for k in 0..p.retro.count().unwrap() {
                let g = p.point(ti, k).unwrap();
                points.push(point([ti as f64, g.theta_o_deg as f64, g.dphi_deg as f64], 1.0, 0.01, 0.0));
            }
        }
        Support {
            points,
            incidences_deg: vec![15.0, 30.0, 60.0],
        }
    }

    fn cie(alpha: f64, beta: f64) -> Directions {
        crate::coefficients::Cie::coplanar(alpha, beta, 0.0).directions()
    }

    #[test]
    fn the_standard_geometries_on_the_rings_are_measured() {
        let s = ring_support();
        for alpha in crate::coefficients::ASTM_ALPHAS {
            for beta in [15.0, 30.0] {
                let b = s.classify(&cie(alpha, beta));
                assert_eq!(b.provenance, Provenance::Measured, "α {alpha} β {beta}: {}", b.why);
            }
        }
    }

    #[test]
    fn between_the_rings_is_interpolated_and_beyond_them_extrapolated() {
        let s = ring_support();
        assert_eq!(s.classify(&cie(0.7, 30.0)).provenance, Provenance::Interpolated);
        let b = s.classify(&cie(0.7, 30.0));
        assert_eq!(b.provenance, Provenance::Interpolated, "{}", b.why);
        // Beyond the outermost ring (4.75°): the plate's shadow, no sample.
        let b = s.classify(&cie(7.0, 30.0));
        assert_eq!(b.provenance, Provenance::Extrapolated, "{}", b.why);
    }

    #[test]
    fn an_incidence_the_data_do_not_hold_is_extrapolated() {
        let s = ring_support();
        for beta in [-4.0, 40.0, 45.0, 88.76] {
            let b = s.classify(&cie(0.2, beta));
            assert_eq!(b.provenance, Provenance::Extrapolated, "β {beta}");
            assert!(b.why.contains("was not measured"), "{}", b.why);
        }
        // 60° is held, but no sample about its retro direction.
        let b = s.classify(&cie(0.2, 60.0));
        assert_eq!(b.provenance, Provenance::Extrapolated);
    }

    #[test]
    fn the_support_round_trips_through_json() {
        let s = ring_support();
        let back = Support::from_json(&s.to_json()).unwrap();
        assert_eq!(back.points.len(), s.points.len());
        assert_eq!(back.incidences_deg, s.incidences_deg);
        assert_eq!(back.classify(&cie(0.7, 30.0)), s.classify(&cie(0.7, 30.0)));
        assert!(Support::from_json(&json!({"incidences_deg": [1.0], "retro": [[1.0, 2.0]]})).is_err());
    }
}
