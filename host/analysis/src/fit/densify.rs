//! Densified data, as Belcour et al. 2014 fitted (§6.A.b): "we densified
//! the data and filled the missing part using Matlab interpolation
//! toolbox", so that a rational function meets fewer places without a
//! sample to hold its denominator away from zero.
//!
//! At each incidence the views are placed in the plane `(θo cosΔφ, θo
//! sinΔφ)` (ALTA's `ISOTROPIC_TL_TV_PROJ_DPHI`, the plane of the paper's
//! densified files), and a square grid of `step` degrees takes the value
//! linear over the samples' Delaunay triangulation: gaps between samples
//! (a blind zone about the retro direction) are filled by the plane
//! through their edges, and nothing is placed outside the samples' hull
//! nor beyond the largest θo measured there. At normal incidence views
//! along one line suffice: an isotropic BRDF is then a function of θo
//! alone, taken linear between them. Linear, where the paper's
//! `griddata` was cubic: a cubic surface overshoots beside a narrow lobe
//! (ALTA's densified yellow tape peaks at 38.8 sr⁻¹ where the measured
//! one peaks at 19.3), a linear one stays within its corners.
//!
//! What it assumes (`docs/models.md`, the rational model): the BRDF is the plane through
//! three neighbouring samples everywhere between them. A grid point then
//! counts as a measurement it is not, its uncertainty is its corners'
//! (correlated with theirs, not independent), and a peak inside a gap is
//! cut to the gap's edges. A function fitted to the grid holds the
//! grid's segments, not the samples': [`crate::rational::RationalFit`]
//! says how many of those it still holds.

use super::data::{Dataset, Observation};
use anyhow::{bail, Result};
use spade::{DelaunayTriangulation, FloatTriangulation, HasPosition, Point2, Triangulation};
use std::collections::BTreeMap;

/// A sample as a vertex of the plane: its place, value and σ.
#[derive(Debug, Clone, Copy)]
struct Vertex {
    at: Point2<f64>,
    value: f64,
    sigma: Option<f64>,
}

impl HasPosition for Vertex {
    type Scalar = f64;

    fn position(&self) -> Point2<f64> {
        self.at
    }
}

/// The finest grid step, degrees: 0.1° over a hemisphere is 2.6 million
/// points per incidence, the most a data set holds (`formats::guard`).
pub const FINEST_STEP_DEG: f64 = 0.1;

/// The plane's point of a view, degrees.
fn place(o: &Observation) -> Point2<f64> {
    let r = o.theta_o.to_degrees();
    Point2::new(r * o.dphi.cos(), r * o.dphi.sin())
}

/// What the grid takes its values from at one incidence.
enum Surface {
    /// Linear over the views' Delaunay triangles.
    Plane(DelaunayTriangulation<Vertex>),
    /// Normal incidence seen along one line: an isotropic BRDF is then a
    /// function of θo alone, linear between the views (ascending θo).
    Radial(Vec<(f64, f64, Option<f64>)>),
}

impl Surface {
    /// The surface of `views` (at one incidence), if they span one.
    fn of(theta_i: f64, views: &[&Observation]) -> Result<Option<Surface>> {
        let mut t = DelaunayTriangulation::<Vertex>::new();
        for o in views {
            t.insert(Vertex {
                at: place(o),
                value: o.value,
                sigma: o.sigma,
            })
            .map_err(|e| anyhow::anyhow!("θi = {:.2}°: {e:?}", theta_i.to_degrees()))?;
        }
        if t.num_inner_faces() > 0 {
            return Ok(Some(Surface::Plane(t)));
        }
        if theta_i.abs() > 1e-6 {
            return Ok(None);
        }
        let mut radial: Vec<(f64, f64, Option<f64>)> = views.iter().map(|o| (o.theta_o.to_degrees(), o.value, o.sigma)).collect();
        radial.sort_by(|a, b| a.0.total_cmp(&b.0));
        radial.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
        Ok((radial.len() >= 2).then_some(Surface::Radial(radial)))
    }

    /// The value and σ at `(x, y)` (degrees), `None` outside the views.
    fn at(&self, x: f64, y: f64, weights: &mut Vec<(spade::handles::FixedVertexHandle, f64)>) -> Option<(f64, Option<f64>)> {
        match self {
            Surface::Plane(t) => {
                t.barycentric().get_weights(Point2::new(x, y), weights);
                if weights.is_empty() {
                    return None;
                }
                let mut value = 0.0;
                let mut sigma = Some(0.0);
                for &(v, w) in weights.iter() {
                    let v = *t.vertex(v).data();
                    value += w * v.value;
                    sigma = sigma.zip(v.sigma).map(|(s, vs)| s + w * vs);
                }
                Some((value, sigma))
            }
            Surface::Radial(r) => {
                let to = x.hypot(y);
                let k = r.partition_point(|v| v.0 < to);
                let (a, b) = (r.get(k.checked_sub(1)?)?, r.get(k)?);
                let w = (to - a.0) / (b.0 - a.0);
                let sigma = a.2.zip(b.2).map(|(sa, sb)| sa + w * (sb - sa));
                Some((a.1 + w * (b.1 - a.1), sigma))
            }
        }
    }
}

/// `data` on a grid of `step_deg` degrees per incidence, in `data`'s units.
/// An incidence whose views lie on one line (away from normal incidence)
/// spans no surface: its samples are kept as measured, and a warning says
/// so.
pub fn densify(data: &Dataset, step_deg: f64) -> Result<Dataset> {
    if !(step_deg.is_finite() && step_deg >= FINEST_STEP_DEG) {
        bail!("--densify {step_deg}: the grid step must be at least {FINEST_STEP_DEG}°");
    }
    // Incidences to 1e-6 rad, as files write them.
    let mut incidences: BTreeMap<i64, Vec<&Observation>> = BTreeMap::new();
    for o in &data.observations {
        incidences.entry((o.theta_i * 1e6).round() as i64).or_default().push(o);
    }
    let mut observations = Vec::new();
    let mut warnings = Vec::new();
    let mut weights = Vec::new();
    for views in incidences.into_values() {
        let theta_i = views[0].theta_i;
        let Some(surface) = Surface::of(theta_i, &views)? else {
            warnings.push(format!(
                "θi = {:.2}°: its {} views lie on one line, no surface to densify between them: kept as measured",
                theta_i.to_degrees(),
                views.len()
            ));
            observations.extend(views.iter().map(|o| **o));
            continue;
        };
        let reach = views.iter().map(|o| o.theta_o.to_degrees()).fold(0.0, f64::max);
        let n = (reach / step_deg).floor() as i64;
        for i in -n..=n {
            for j in -n..=n {
                let (x, y) = (i as f64 * step_deg, j as f64 * step_deg);
                let r = x.hypot(y);
                if r > reach {
                    continue;
                }
                if let Some((value, sigma)) = surface.at(x, y, &mut weights) {
                    observations.push(Observation {
                        theta_i,
                        theta_o: r.to_radians(),
                        dphi: y.atan2(x),
                        value,
                        sigma,
                        shared: Default::default(),
                    });
                }
            }
        }
    }
    Ok(Dataset {
        observations,
        warnings,
        ..data.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::Units;

    fn obs(ti: f64, to: f64, dphi: f64, value: f64) -> Observation {
        Observation {
            theta_i: ti.to_radians(),
            theta_o: to.to_radians(),
            dphi: dphi.to_radians(),
            value,
            sigma: Some(0.1),
            shared: Default::default(),
        }
    }

    #[test]
    fn a_plane_stays_a_plane_within_the_hull_and_no_further() {
        // f = 1 + x/100 over a ring of views to 40°, with a hole about the
        // origin: the grid fills the hole on the same plane, and stops at
        // 40°.
        let f = |to: f64, dphi: f64| 1.0 + to * dphi.to_radians().cos() / 100.0;
        let mut views = Vec::new();
        for to in [10.0, 20.0, 30.0, 40.0] {
            for k in 0..36 {
                let dphi = -180.0 + 10.0 * k as f64;
                views.push(obs(30.0, to, dphi, f(to, dphi)));
            }
        }
        let d = densify(&Dataset::new(Units::Fr, views), 2.0).unwrap();
        assert!(d.observations.len() > 1000, "{}", d.observations.len());
        for o in &d.observations {
            let (to, dphi) = (o.theta_o.to_degrees(), o.dphi.to_degrees());
            assert!(to <= 40.0 + 1e-9);
            assert!((o.value - f(to, dphi)).abs() < 1e-9, "{to} {dphi}: {}", o.value);
            assert!((o.sigma.unwrap() - 0.1).abs() < 1e-12);
        }
        // The hole about the origin is filled.
        assert!(d.observations.iter().any(|o| o.theta_o == 0.0));
    }

    #[test]
    fn a_peak_is_never_overshot_bad_steps_are_refused_and_lines_kept() {
        let mut views = Vec::new();
        for to in (0..=12).map(|k| 5.0 * k as f64) {
            for k in 0..12 {
                let dphi = 30.0 * k as f64;
                views.push(obs(15.0, to, dphi, (-to / 5.0).exp() * 20.0));
            }
        }
        let data = Dataset::new(Units::FrCos, views);
        let d = densify(&data, 1.0).unwrap();
        let peak = d.observations.iter().map(|o| o.value).fold(0.0, f64::max);
        assert!(peak <= 20.0 + 1e-12 && d.units == Units::FrCos);
        assert!(densify(&data, 0.01).unwrap_err().to_string().contains("at least 0.1"));
        // Views on one line: kept as measured away from normal incidence,
        // where an isotropic BRDF depends on θo alone and is densified so.
        let line = |ti: f64| Dataset::new(Units::Fr, (0..5).map(|k| obs(ti, 10.0 * k as f64, 0.0, 1.0 + k as f64)).collect());
        let kept = densify(&line(15.0), 1.0).unwrap();
        assert_eq!(kept.observations, line(15.0).observations);
        assert!(kept.warnings[0].contains("one line"), "{:?}", kept.warnings);
        let normal = densify(&line(0.0), 1.0).unwrap();
        assert!(normal.warnings.is_empty() && normal.observations.len() > 5000);
        for o in &normal.observations {
            let to = o.theta_o.to_degrees();
            assert!((o.value - (1.0 + to / 10.0)).abs() < 1e-9, "{to}: {}", o.value);
        }
    }
}
