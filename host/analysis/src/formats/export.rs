//! A fit or a material written for another tool, as `gonio export` and
//! `gonio fit --out` write it: a BRDF Explorer `.brdf`, and an RGL `.bsdf`
//! checked as a renderer reads it back, with the warning its check may
//! call for.

use super::{brdf_explorer, rgl};
use crate::fit::file::FittedBrdf;
use anyhow::{Context, Result};
use gonio_brdf::Directions;
use std::path::Path;

/// Writes a fit as `.brdf`, naming where it came from in the header.
pub fn write_brdf(fitted: &FittedBrdf, source: &str, out: &Path) -> Result<()> {
    let comments = [format!("from {source}")];
    let text = match fitted {
        FittedBrdf::Model(m) => brdf_explorer::write(m, &comments),
        FittedBrdf::Rational(r) => brdf_explorer::write_rational(r, &comments),
    };
    std::fs::write(out, text).with_context(|| format!("cannot write {}", out.display()))
}

/// What a `.bsdf` written holds: its size, its incidences, and how closely
/// a renderer reading it gives the material back.
pub struct Written {
    pub bytes: usize,
    pub incidences: usize,
    pub accuracy: rgl::Accuracy,
}

/// Tabulates `brdf` as an RGL `.bsdf` at `output` and checks it as a renderer reads it.
pub fn write_bsdf(brdf: &dyn Fn(&Directions) -> f64, name: &str, origin: &str, output: &Path, opt: &rgl::Options) -> Result<Written> {
    let description = rgl::description(&format!("{origin} ({name})"), opt.spectrum);
    let table = rgl::Table::new(brdf, &description, opt).with_context(|| format!("{name} as .bsdf"))?;
    let bytes = table.bytes();
    std::fs::write(output, &bytes).with_context(|| format!("cannot write {}", output.display()))?;
    let accuracy = rgl::accuracy(&table, brdf, rgl::CHECK_PAIRS, rgl::CHECK_LOBE_DEG.to_radians());
    Ok(Written {
        bytes: bytes.len(),
        incidences: table.theta_i().len(),
        accuracy,
    })
}

/// The warning for a table outside the tolerance, with its measured errors.
pub fn coarse_warning(acc: &rgl::Accuracy) -> Option<String> {
    let [median, p95, peak] = rgl::TOLERANCE;
    let [ti, to, dphi] = acc.worst_deg;
    (!acc.within_tolerance()).then(|| {
        format!(
            "warning: the table is too coarse for this material (median {:.2} %, 95th percentile {:.2} %, retro peak {:.2} %, largest {:.1} % at θi {ti:.1}°, θo {to:.1}°, Δφ {dphi:.1}°; tolerance {} %, {} %, {} %); raise --grid or --warp-grid, or lower --theta-step (gonio export)",
            100.0 * acc.median,
            100.0 * acc.p95,
            100.0 * acc.retro_peak,
            100.0 * acc.max,
            100.0 * median,
            100.0 * p95,
            100.0 * peak
        )
    })
}
