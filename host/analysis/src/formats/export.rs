//! A fit or a material written for another tool, as `gonio export` and
//! `gonio fit --out` write it: a BRDF Explorer `.brdf`, and an RGL `.bsdf`
//! checked as a renderer reads it back, with the warning its check may
//! call for.

use super::merl::Merl;
use super::{brdf_explorer, rgl};
use crate::evaluation::Brdf;
use crate::fit::file::FittedBrdf;
use anyhow::{bail, Context, Result};
use gonio_brdf::Directions;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// What a fit is drawn as besides its own file: a BRDF Explorer shader, a
/// renderer's `.bsdf` at the default resolution, pictures over its data.
#[derive(Debug, Clone, Default)]
pub struct Drawn {
    pub brdf: Option<PathBuf>,
    pub bsdf: Option<PathBuf>,
    pub plot: Option<PathBuf>,
}

impl Drawn {
    /// Writes `fitted` (from `origin`) as asked, its pictures over `data`;
    /// returns the warning of a `.bsdf` too coarse for it, if any.
    pub fn write(&self, fitted: &FittedBrdf, origin: &str, data: &crate::fit::Dataset) -> Result<Option<String>> {
        if let Some(out) = &self.brdf {
            write_brdf(fitted, &format!("from {origin}"), out)?;
        }
        let mut warning = None;
        if let Some(out) = &self.bsdf {
            let written = write_bsdf(&|d| fitted.eval(d), fitted.name(), origin, out, &rgl::Options::default())?;
            warning = coarse_warning(&written.accuracy);
        }
        if let Some(dir) = &self.plot {
            crate::plot::render(data, std::slice::from_ref(fitted), dir, &Default::default())?;
        }
        Ok(warning)
    }
}

/// A file written, by format.
pub enum Export {
    Brdf,
    Bsdf(Written),
    Merl { bytes: usize },
}

/// Writes `what` (called `name`, from `origin`) to `output`, in the format
/// its extension names: `.brdf` (a fit only), `.bsdf` with `opt`, or `.binary`.
pub fn export(what: &Brdf, name: &str, origin: &str, output: &Path, opt: &rgl::Options) -> Result<Export> {
    match output.extension().and_then(|e| e.to_str()) {
        Some("brdf") => {
            let Brdf::Fit(fitted) = what else {
                bail!("a BRDF Explorer .brdf is written from a fit (FIT.json), not from --material");
            };
            write_brdf(fitted, &format!("from {origin}"), output)?;
            Ok(Export::Brdf)
        }
        Some("bsdf") => Ok(Export::Bsdf(write_bsdf(&|d| what.eval(d), name, origin, output, opt)?)),
        Some("binary") => {
            let merl = Merl::tabulate(&|d: &Directions| what.eval(d)).with_context(|| format!("{name} as MERL .binary"))?;
            let bytes = merl.bytes();
            std::fs::write(output, &bytes).with_context(|| format!("cannot write {}", output.display()))?;
            Ok(Export::Merl { bytes: bytes.len() })
        }
        _ => bail!(
            "{}: the extension must be .brdf (BRDF Explorer), .bsdf (RGL, for Mitsuba 3 and pbrt-v4) or .binary (MERL)",
            output.display()
        ),
    }
}

impl Export {
    /// What was written, as `gonio export --json` prints it.
    pub fn to_json(&self, name: &str, output: &Path) -> Value {
        match self {
            Export::Brdf => json!({ "written": output, "format": "brdf-explorer", "model": name }),
            Export::Merl { bytes } => json!({ "written": output, "format": "merl-binary", "model": name, "bytes": bytes }),
            Export::Bsdf(w) => {
                let [median, p95, peak] = rgl::TOLERANCE;
                json!({"written": output, "format": "rgl-bsdf", "model": name, "bytes": w.bytes, "incidences": w.incidences,
                       "accuracy": w.accuracy, "tolerance": {"median": median, "p95": p95, "retro_peak": peak},
                       "within_tolerance": w.accuracy.within_tolerance()})
            }
        }
    }

    /// What was written, in words for the operator, with a too-coarse
    /// table's warning last.
    pub fn lines(&self, name: &str, output: &Path) -> Vec<String> {
        let out = output.display();
        match self {
            Export::Brdf => vec![format!("{name} written to {out}")],
            Export::Merl { .. } => vec![format!(
                "{name} written to {out} (MERL 90 × 90 × 180, grey; isotropic and reciprocal by assumption: docs/render.md)"
            )],
            Export::Bsdf(w) => {
                let acc = &w.accuracy;
                let mut lines = vec![
                    format!("{name} written to {out} ({:.1} MB, {} incidences)", w.bytes as f64 / 1e6, w.incidences),
                    format!(
                        "read back as a renderer reads it, at {} direction pairs: median error {:.2} %, 95th percentile {:.2} %, largest {:.1} % (at θi {:.1}°, θo {:.1}°, Δφ {:.1}°), retro peak {:.2} %",
                        acc.pairs,
                        100.0 * acc.median,
                        100.0 * acc.p95,
                        100.0 * acc.max,
                        acc.worst_deg[0],
                        acc.worst_deg[1],
                        acc.worst_deg[2],
                        100.0 * acc.retro_peak
                    ),
                ];
                lines.extend(coarse_warning(acc));
                lines
            }
        }
    }
}

/// Writes a fit as `.brdf`, `comment` (where it came from) in its header.
pub fn write_brdf(fitted: &FittedBrdf, comment: &str, out: &Path) -> Result<()> {
    let comments = [comment.to_string()];
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
pub fn write_bsdf(brdf: &rgl::Brdf, name: &str, origin: &str, output: &Path, opt: &rgl::Options) -> Result<Written> {
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
