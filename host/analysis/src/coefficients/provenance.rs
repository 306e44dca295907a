//! What a coefficient rests on (`docs/retroreflection.md`, *Provenance*):
//! the measured samples about the retro direction a data set holds (its
//! [`Support`]), and whether a requested geometry lies on them, between
//! them, or where only a model can carry a value.
//!
//! - **measured**: a sample at the geometry (within [`MEASURED_WITHIN_DEG`]:
//!   its value is the coefficient, corrected for the apertures);
//! - **interpolated**: at a measured incidence, surrounded on every side by
//!   samples within the standard's aperture (the disc it averages over: finer
//!   structure than that the standard itself does not see);
//! - **extrapolated**: no sample there, but within the data's own spacing of
//!   them (an incidence between measured ones, or beyond them by at most
//!   their finest spacing; an observation angle likewise): only a model
//!   carries the value, and only one consistent with the data (`source.rs`);
//! - **not measured**: farther from the data than their own spacing, in the
//!   incidence or the observation angle (EN 1436's 88.76° on a scan that
//!   ends at 60°): no value, unless the user asks for an extrapolation, and
//!   the scan that would measure it.

use crate::fit::{Dataset, Units};
use crate::instrument::Instrument;
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
/// Observation angles closer than this (degrees) are one ring: the data's
/// spacing in α is taken between distinct rings, not between a ring's
/// views, which the stages place to a microstep.
const SAME_ALPHA_DEG: f64 = 0.005;
/// Samples a view's curvature is fitted through (a quadratic has 6
/// coefficients; on the reference rings these reach the next ring out and in).
pub const CURVATURE_SAMPLES: usize = 40;

/// How a value was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Provenance {
    #[serde(rename = "measured")]
    Measured,
    #[serde(rename = "interpolated")]
    Interpolated,
    #[serde(rename = "extrapolated")]
    Extrapolated,
    #[serde(rename = "not measured")]
    NotMeasured,
}

impl Provenance {
    pub fn name(self) -> &'static str {
        match self {
            Provenance::Measured => "measured",
            Provenance::Interpolated => "interpolated",
            Provenance::Extrapolated => "extrapolated",
            Provenance::NotMeasured => "not measured",
        }
    }

    /// Whether the data hold the value (measured or interpolated).
    pub fn on_data(self) -> bool {
        matches!(self, Provenance::Measured | Provenance::Interpolated)
    }
}

/// A provenance and the reason for it, in a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Basis {
    pub provenance: Provenance,
    pub why: String,
    /// Where the data do not reach: the incidence and observation angle a
    /// scan would have to measure (`gonio scan --theta-i … --retro-rings …`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measure: Option<String>,
}

impl Basis {
    fn new(provenance: Provenance, why: String) -> Basis {
        Basis {
            provenance,
            why,
            measure: None,
        }
    }
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
    /// What measured them: the apertures a measured value is carried from.
    pub instrument: Instrument,
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
        Ok(Support {
            points,
            incidences_deg,
            instrument: data.instrument,
        })
    }

    /// As a fit file keeps it: `{"incidences_deg", "retro": [[θi, θo, Δφ,
    /// f_r, σ, shift_zero_psi], …], "instrument"}`.
    pub fn to_json(&self) -> Value {
        let rows: Vec<[f64; 6]> = self
            .points
            .iter()
            .map(|p| [p.angles_deg[0], p.angles_deg[1], p.angles_deg[2], p.value, p.sigma, p.shift_psi])
            .collect();
        json!({"incidences_deg": self.incidences_deg, "support_deg": SUPPORT_DEG, "retro": rows, "instrument": self.instrument.to_json()})
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
            // A file of an earlier gonio did not say: not known.
            instrument: Instrument::from_json(&v["instrument"]).context("`support.instrument`")?,
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

    /// What a coefficient at nominal directions `want` rests on, samples
    /// within `reach_deg` (the standard's aperture) interpolating it; where
    /// the data do not hold it, the scan that would.
    pub fn classify(&self, want: &Directions, reach_deg: f64) -> Basis {
        let mut basis = self.rests_on(want, reach_deg);
        if !basis.provenance.on_data() {
            let (ti, _, _) = want.angles();
            let alpha = angle_between(want.l, want.v).to_degrees();
            basis.measure = Some(format!(
                "gonio scan --theta-i {} --retro-rings {}",
                figure(ti.to_degrees()),
                figure(alpha)
            ));
        }
        basis
    }

    fn rests_on(&self, want: &Directions, reach_deg: f64) -> Basis {
        let (ti, _, _) = want.angles();
        let ti = ti.to_degrees();
        let alpha = angle_between(want.l, want.v).to_degrees();
        let beyond = |why: String| Basis::new(Provenance::NotMeasured, why);
        let Some(at) = self.incidence(ti) else {
            let list: Vec<String> = self.incidences_deg.iter().map(|t| format!("{t:.4}°")).collect();
            let held = format!("the data hold θi {}", list.join(", "));
            if let Err(why) = spacing_check(ti, &self.incidences_deg) {
                return beyond(format!("θi {ti:.2}° was not measured ({held}): {why} in θi"));
            }
            // The measured incidences about it anchor a model's value: each
            // must hold this observation angle within its own spacing.
            let (below, above) = self.about(ti);
            for t in [below, above].into_iter().flatten() {
                if let Err(why) = spacing_check(alpha, &self.alphas_at(t)) {
                    return beyond(format!(
                        "θi {ti:.2}° was not measured ({held}), and at θi {t:.2}° the observation angle α {}°: {why} in α",
                        figure(alpha)
                    ));
                }
            }
            return Basis::new(
                Provenance::Extrapolated,
                format!("θi {ti:.2}° was not measured ({held}), but lies within their spacing"),
            );
        };
        let views = self.views_near(at, want.v);
        let Some(&(_, nearest)) = views.first() else {
            return beyond(format!("no sample within {SUPPORT_DEG}° of the retro direction at θi {at:.4}°"));
        };
        let nearest_deg = nearest.to_degrees();
        if nearest_deg <= MEASURED_WITHIN_DEG {
            return Basis::new(Provenance::Measured, format!("a sample {nearest_deg:.3}° from the geometry"));
        }
        let within = views.partition_point(|v| v.1.to_degrees() <= reach_deg);
        let near = &views[..within];
        if near.len() >= 3 && surrounds(want.v, near) {
            return Basis::new(
                Provenance::Interpolated,
                format!(
                    "between the {} samples within the standard's {}° aperture, on every side (the nearest {nearest_deg:.3}° away)",
                    near.len(),
                    figure(reach_deg)
                ),
            );
        }
        let alphas = self.alphas_at(at);
        match spacing_check(alpha, &alphas) {
            Ok(()) => Basis::new(
                Provenance::Extrapolated,
                format!(
                    "the nearest sample is {nearest_deg:.2}° away and none surround it within the standard's {}° aperture",
                    figure(reach_deg)
                ),
            ),
            Err(why) => beyond(format!("at θi {at:.2}° the observation angle α {}°: {why} in α", figure(alpha))),
        }
    }

    /// The measured incidences nearest `theta_i_deg` at or below it and at
    /// or above it (degrees): what a model's value there is anchored to.
    pub fn about(&self, theta_i_deg: f64) -> (Option<f64>, Option<f64>) {
        let inc = self.incidences_deg.iter().copied();
        let below = inc.clone().filter(|t| *t <= theta_i_deg).max_by(f64::total_cmp);
        let above = inc.filter(|t| *t >= theta_i_deg).min_by(f64::total_cmp);
        (below, above)
    }

    /// The distinct observation angles (light–view angles, degrees) of the
    /// samples at the incidence `at`, ascending.
    fn alphas_at(&self, at: f64) -> Vec<f64> {
        let mut alphas: Vec<f64> = self
            .points
            .iter()
            .filter(|p| (p.angles_deg[0] - at).abs() <= INCIDENCE_TOL_DEG)
            .map(|p| angle_between(p.d.l, p.d.v).to_degrees())
            .collect();
        alphas.sort_by(f64::total_cmp);
        alphas.dedup_by(|a, b| (*a - *b).abs() < SAME_ALPHA_DEG);
        alphas
    }
}

/// Whether `x` lies within the data's own spacing of the measured values
/// `held` (ascending): between two of them, or beyond them by at most their
/// finest spacing (0 with a single value). The finest, not the nearest gap:
/// a scan at 15°, 30° and 60° says nothing of 88.76° just because its last
/// step was 30° wide.
fn spacing_check(x: f64, held: &[f64]) -> Result<(), String> {
    let (Some(&lo), Some(&hi)) = (held.first(), held.last()) else {
        return Err("there are no data".into());
    };
    if (lo..=hi).contains(&x) {
        return Ok(());
    }
    let finest = held.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
    let (nearest, distance) = if x < lo { (lo, lo - x) } else { (hi, x - hi) };
    if !finest.is_finite() {
        return Err(format!(
            "{}° from the only value measured ({}°): a single one has no spacing to reach across",
            figure(distance),
            figure(nearest)
        ));
    }
    if distance <= finest {
        return Ok(());
    }
    Err(format!(
        "{}° beyond the nearest measured ({}°), farther than the data's finest spacing ({}°)",
        figure(distance),
        figure(nearest),
        figure(finest)
    ))
}

/// An angle in degrees as text: to 0.01°, without trailing zeros.
fn figure(deg: f64) -> String {
    let t = format!("{:.2}", deg);
    t.trim_end_matches('0').trim_end_matches('.').to_string()
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

    /// The reference rings at 15°, 30° and 60°, and the retro point, as a scan holds them.
    fn ring_support() -> Support {
        let p = LobePatterns::cea();
        let mut points = Vec::new();
        for ti in [15.0f32, 30.0, 60.0] {
            points.push(point([ti as f64, ti as f64, 0.0], 1.0, 0.01, 0.0));
            for k in 0..p.retro.count().unwrap() {
                let g = p.point(ti, k).unwrap();
                points.push(point([ti as f64, g.theta_o_deg as f64, g.dphi_deg as f64], 1.0, 0.01, 0.0));
            }
        }
        Support {
            points,
            incidences_deg: vec![15.0, 30.0, 60.0],
            instrument: Instrument::ThisHead,
        }
    }

    fn cie(alpha: f64, beta: f64) -> Directions {
        crate::coefficients::Cie::coplanar(alpha, beta, 0.0).directions()
    }

    /// ASTM E810's aperture (10′), within which samples interpolate.
    const REACH: f64 = 1.0 / 6.0;

    #[test]
    fn the_standard_geometries_on_the_rings_are_measured() {
        let s = ring_support();
        for alpha in crate::coefficients::ASTM_ALPHAS {
            for beta in [15.0, 30.0] {
                let b = s.classify(&cie(alpha, beta), REACH);
                assert_eq!(b.provenance, Provenance::Measured, "α {alpha} β {beta}: {}", b.why);
            }
        }
    }

    #[test]
    fn interpolated_within_the_aperture_extrapolated_between_rings_not_measured_beyond() {
        let s = ring_support();
        // 0.02° outside the 0.33° ring, 0.15° inside the 0.5° one.
        let b = s.classify(&cie(0.35, 30.0), REACH);
        assert_eq!(b.provenance, Provenance::Interpolated, "{}", b.why);
        assert!(b.why.contains("0.17° aperture"), "{}", b.why);
        // Between the 0.5° and 1° rings: farther than the aperture from both.
        let b = s.classify(&cie(0.75, 30.0), REACH);
        assert_eq!(b.provenance, Provenance::Extrapolated, "{}", b.why);
        // Beyond the outermost ring (4.75°) by more than the finest ring
        // spacing (0.1°): the plate's shadow, nothing measured near.
        let b = s.classify(&cie(7.0, 30.0), REACH);
        assert_eq!(b.provenance, Provenance::NotMeasured, "{}", b.why);
        assert!(b.why.contains("in α"), "{}", b.why);
        assert_eq!(b.measure.as_deref(), Some("gonio scan --theta-i 30 --retro-rings 7"));
    }

    #[test]
    fn an_incidence_within_the_data_spacing_is_extrapolated_beyond_it_not_measured() {
        let s = ring_support();
        // Measured 15°, 30°, 60°: finest spacing 15°. 4° is 11° below 15°,
        // 40° and 45° lie between 30° and 60°.
        for beta in [-4.0, 40.0, 45.0] {
            let b = s.classify(&cie(0.2, beta), REACH);
            assert_eq!(b.provenance, Provenance::Extrapolated, "β {beta}: {}", b.why);
            assert!(b.why.contains("was not measured"), "{}", b.why);
        }
        // EN 1436's 88.76°: 28.76° beyond 60°.
        let b = s.classify(&cie(1.05, 88.76), REACH);
        assert_eq!(b.provenance, Provenance::NotMeasured, "{}", b.why);
        assert!(b.why.contains("28.76° beyond the nearest measured (60°)"), "{}", b.why);
        assert_eq!(b.measure.as_deref(), Some("gonio scan --theta-i 88.76 --retro-rings 1.05"));
        // 60° held without a sample about its retro direction: nothing
        // there, and nothing to anchor 45° above.
        let mut s = ring_support();
        s.points.retain(|p| p.angles_deg[0] < 59.0);
        let b = s.classify(&cie(0.2, 60.0), REACH);
        assert_eq!(b.provenance, Provenance::NotMeasured);
        let b = s.classify(&cie(0.2, 45.0), REACH);
        assert_eq!(b.provenance, Provenance::NotMeasured, "{}", b.why);
        assert!(b.why.contains("at θi 60.00°") && b.why.contains("in α"), "{}", b.why);
    }

    #[test]
    fn the_spacing_rule() {
        assert!(spacing_check(45.0, &[15.0, 30.0, 60.0]).is_ok());
        assert!(spacing_check(0.0, &[15.0, 30.0, 60.0]).is_ok());
        assert!(spacing_check(75.0, &[15.0, 30.0, 60.0]).is_ok());
        assert!(spacing_check(75.1, &[15.0, 30.0, 60.0]).is_err());
        // One incidence: nothing else is within its spacing.
        assert!(spacing_check(30.0, &[30.0]).is_ok());
        assert!(spacing_check(31.0, &[30.0]).is_err());
        assert!(spacing_check(1.0, &[]).is_err());
    }

    #[test]
    fn the_support_round_trips_through_json() {
        let s = ring_support();
        let back = Support::from_json(&s.to_json()).unwrap();
        assert_eq!(back.points.len(), s.points.len());
        assert_eq!(back.incidences_deg, s.incidences_deg);
        assert_eq!(back.classify(&cie(0.7, 30.0), REACH), s.classify(&cie(0.7, 30.0), REACH));
        assert!(Support::from_json(&json!({"incidences_deg": [1.0], "retro": [[1.0, 2.0]]})).is_err());
    }
}
