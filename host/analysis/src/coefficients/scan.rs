//! The scan that measures a set of coefficients (`gonio scan --for`): the
//! incidences and retro rings its geometries lie on, added to a scan's,
//! so that every value of the set is measured, not carried by a model.

use super::Set;
use anyhow::{bail, Context, Result};
use gonio_shared::lobe_pattern::RINGS_MAX;
use gonio_shared::ScanSpec;

/// What a scan must hold for every value of the set to be measured: the
/// incidences (degrees, ascending) and the observation angles α of the
/// rings about the retro direction (degrees, ascending). A coplanar view
/// at α lies on the ring of radius α, on the side of the laser away
/// from the normal (β < 0) or towards it (β > 0).
fn needs(sets: &[Set]) -> (Vec<f64>, Vec<f64>) {
    let (mut incidences, mut alphas) = (Vec::new(), Vec::new());
    for r in sets.iter().flat_map(|s| s.requests()) {
        incidences.push(r.geometry.sample_angles_deg()[0]);
        alphas.push(r.geometry.alpha_deg);
    }
    for v in [&mut incidences, &mut alphas] {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    }
    (incidences, alphas)
}

/// Adds to `spec` the incidences and retro rings the coefficient `sets`
/// need (`--for`): each set's geometries then lie on the scan's pattern
/// points, so that their values are measured, not carried by a model.
pub fn measure_for(spec: &mut ScanSpec, sets: &[Set]) -> Result<()> {
    if sets.is_empty() {
        return Ok(());
    }
    let (incidences, alphas) = needs(sets);
    let Some(patterns) = spec.patterns.as_mut() else {
        bail!("--for measures on the rings about the retro direction: it cannot go with --no-patterns");
    };
    if patterns.retro.azimuths % 2 != 0 {
        bail!(
            "--for needs an even --retro-azimuths ({} given): the standards' views lie on the rings' two coplanar azimuths, 0° and 180°",
            patterns.retro.azimuths
        );
    }
    for t in incidences {
        let t = t as f32;
        if !spec.theta_i_deg.iter().any(|h| (h - t).abs() < 0.05) && spec.theta_i_deg.push(t).is_err() {
            bail!("--for adds θi {t}°: beyond the 8 incidence angles a scan holds; give fewer --theta-i");
        }
    }
    let mut radii: Vec<f32> = patterns.retro.radii_deg.to_vec();
    for a in alphas {
        if !radii.iter().any(|r| (*r as f64 - a).abs() < 1e-4) {
            radii.push(a as f32);
        }
    }
    radii.sort_by(f32::total_cmp);
    patterns.retro.radii_deg = radii
        .as_slice()
        .try_into()
        .ok()
        .with_context(|| format!("--for needs the retro rings {radii:?}: more than the {RINGS_MAX} a scan holds"))?;
    Ok(())
}
