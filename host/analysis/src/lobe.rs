//! How narrow a material's lobes are: what a sweep scan slows down for
//! ([`gonio_shared::SweepLobe`]), read off the model being fitted.
//!
//! The width of a peak is the angle from it at which the material has
//! fallen to e^(−1/2) of the peak's height above the floor (σ of a Gaussian;
//! `acos(e^(−1/(2n)))` ≈ `1/√n` rad of a cosine lobe to the power n), the
//! floor being the lowest value within [`REACH_DEG`] of the peak. It is
//! found by walking away from the retro and the mirror direction in the
//! plane of incidence, towards the horizon (away from the other peak), for
//! every incidence of the scan:
//! numerically, so every model of `models.md` has one, whatever its lobes'
//! formulas.

use anyhow::{bail, Result};
use gonio_brdf::frame::Directions;
use gonio_brdf::Material;

/// How far from a peak the walk goes (deg): a lobe wider than this is no
/// reason to slow down.
pub const REACH_DEG: f64 = 30.0;
/// Where a walk towards the horizon stops (deg of θo).
const HORIZON_DEG: f64 = 89.0;
/// Step of the walk (deg).
const STEP_DEG: f64 = 0.01;
/// A peak less than this above its floor (relative) is no lobe.
const PROMINENCE: f64 = 0.05;

/// Width (deg) of the narrowest retro or mirror lobe of `material` at the
/// incidences `theta_i_deg`; an error when it has none narrower than
/// [`REACH_DEG`].
pub fn narrowest_deg(material: &Material, theta_i_deg: &[f32]) -> Result<f64> {
    let mut best: Option<f64> = None;
    for &ti in theta_i_deg {
        let ti = ti as f64;
        // Walking towards the horizon, away from the other peak: the view at
        // signed θo in the plane of incidence (negative: the mirror
        // half-plane).
        let reach = REACH_DEG.min(HORIZON_DEG - ti);
        let retro = width_deg(reach, |g| material.eval(&Directions::from_degrees(ti, ti + g, 0.0)));
        let mirror = width_deg(reach, |g| material.eval(&Directions::from_degrees(ti, -ti - g, 0.0)));
        for w in [retro, mirror].into_iter().flatten() {
            best = Some(best.map_or(w, |b: f64| b.min(w)));
        }
    }
    match best {
        Some(w) => Ok(w),
        None => bail!(
            "{} has no retro or mirror lobe narrower than {REACH_DEG}° at θi = {theta_i_deg:?}°: nothing to slow down for",
            material.model.name()
        ),
    }
}

/// Width (deg) of the peak of `f` (the material `γ` degrees from the peak),
/// `None` when it has none within `reach` degrees.
fn width_deg(reach: f64, f: impl Fn(f64) -> f64) -> Option<f64> {
    if reach < 1.0 {
        return None;
    }
    let steps = (reach / STEP_DEG) as usize;
    let values: Vec<f64> = (0..=steps).map(|k| f(k as f64 * STEP_DEG)).collect();
    let floor = values.iter().copied().fold(f64::INFINITY, f64::min);
    let peak = values[0];
    if !(peak.is_finite() && floor.is_finite()) || peak - floor <= PROMINENCE * floor.abs().max(f64::MIN_POSITIVE) {
        return None;
    }
    let level = floor + (-0.5f64).exp() * (peak - floor);
    let k = values.iter().position(|&v| v <= level)?;
    // Between the last step above the level and the first below it.
    let (a, b) = (values[k - 1], values[k]);
    Some((k as f64 - 1.0 + (a - level) / (a - b)) * STEP_DEG)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cosine_lobe_is_about_one_over_root_n_wide() {
        for n in [100.0, 500.0, 1000.0] {
            let mut m = Material::tape();
            m.params[1] = n;
            let want = (-0.5f64 / n).exp().acos().to_degrees();
            let got = narrowest_deg(&m, &[15.0, 30.0, 60.0]).unwrap();
            // Both lobes share n; the floor and the other lobe shift it a little.
            assert!((got - want).abs() < 0.03 * want, "n = {n}: {got}° against {want}°");
        }
    }

    #[test]
    fn a_material_without_lobes_has_no_width() {
        let lambert = Material::parse(gonio_brdf::ModelId::Lambert, "kd=0.5").unwrap();
        assert!(narrowest_deg(&lambert, &[30.0]).is_err());
    }
}
