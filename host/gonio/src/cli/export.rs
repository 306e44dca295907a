//! `gonio export`: a fit (`gonio fit --out FIT.json`) or a simulated head's
//! material, written for another tool. The output's extension picks the
//! format: `.brdf`, a Disney BRDF Explorer shader (a model with its
//! parameters, or a rational function with its coefficients); `.bsdf`, the
//! RGL tensor file that Mitsuba 3 and pbrt-v4 render; `.binary`, MERL's
//! half-difference table (docs/render.md).

use super::material;
use anyhow::{bail, Context, Result};
use gonio_analysis::fit::file::{read_fitted, FittedBrdf};
use gonio_analysis::formats::export::{coarse_warning, write_brdf, write_bsdf, Written};
use gonio_analysis::formats::merl::Merl;
use gonio_analysis::formats::rgl::{self, Options, Spectrum};
use gonio_brdf::Directions;
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  gonio export fits/retro-phong.json tape.bsdf\n  gonio export --material glass-beads beads.bsdf\n  gonio export fits/abc-retro.json abc.brdf"
)]
pub struct ExportArgs {
    /// `FIT.json OUTPUT`, or `OUTPUT` alone with --material. FIT is a fit
    /// written by `gonio fit --out`; OUTPUT's extension picks the format:
    /// `.brdf` (BRDF Explorer GLSL), `.bsdf` (RGL tensor file for Mitsuba 3
    /// and pbrt-v4) or `.binary` (MERL's 90 × 90 × 180 half-difference table).
    #[arg(value_name = "[FIT] OUTPUT", num_args = 1..=2, required = true)]
    pub paths: Vec<PathBuf>,
    /// Export a simulated head's material instead of a fit: `glass-beads`,
    /// or a model id with --params (the truth a simulated scan is checked against).
    #[arg(long)]
    pub material: Option<String>,
    /// The material's parameters, NAME=V,... (with --material and a model id).
    #[arg(long, requires = "material")]
    pub params: Option<String>,
    /// `.bsdf`: step between incidence slices (degrees; a quarter of it up to 4°).
    #[arg(long, default_value_t = Options::default().theta_i_step_deg)]
    pub theta_step: f64,
    /// `.bsdf`: side of the warped grid the values are tabulated on (odd keeps the retro direction on a node).
    #[arg(long, default_value_t = Options::default().spectra)]
    pub grid: usize,
    /// `.bsdf`: side of the warp's own grid over the half vectors.
    #[arg(long, default_value_t = Options::default().vndf)]
    pub warp_grid: usize,
    /// `.bsdf`: the values at the laser's 633 nm only (`laser`, for a
    /// renderer's spectral variants), copied over the visible as a grey
    /// material (`visible`), or as grey red, green and blue (`rgb`, for its
    /// RGB variants); the description states the assumption.
    #[arg(long, value_enum, default_value = "laser")]
    pub spectrum: Spectrum,
    /// Print one JSON object: what was written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// What is exported: a fit or a material, its name and where it came from.
enum Source {
    Fit(FittedBrdf),
    Material(gonio_brdf::Specimen),
}

impl Source {
    fn eval(&self, d: &Directions) -> f64 {
        match self {
            Source::Fit(f) => f.eval(d),
            Source::Material(s) => s.eval(d),
        }
    }
}

pub fn export_cmd(a: ExportArgs) -> Result<()> {
    let (source, name, origin, output) = match (&a.material, a.paths.as_slice()) {
        (Some(m), [out]) => {
            let s = material::specimen(m, a.params.as_deref())?;
            let described = s.describe();
            (
                Source::Material(s),
                m.clone(),
                format!("the simulated material {described}"),
                out.clone(),
            )
        }
        (None, [fit, out]) => {
            let f = read_fitted(fit)?;
            let name = f.name().to_string();
            (Source::Fit(f), name, format!("the fit {}", fit.display()), out.clone())
        }
        (Some(_), _) => bail!("with --material give only OUTPUT (the material is the source)"),
        (None, _) => bail!("give FIT.json OUTPUT, or OUTPUT with --material NAME"),
    };
    match output.extension().and_then(|e| e.to_str()) {
        Some("brdf") => {
            let Source::Fit(fitted) = &source else {
                bail!("a BRDF Explorer .brdf is written from a fit (FIT.json), not from --material");
            };
            write_brdf(fitted, &origin, &output)?;
            match a.json {
                true => println!("{}", json!({ "written": output, "format": "brdf-explorer", "model": name })),
                false => eprintln!("{name} written to {}", output.display()),
            }
        }
        Some("bsdf") => export_bsdf(&a, &source, &name, &origin, &output)?,
        Some("binary") => {
            let merl = Merl::tabulate(&|d: &Directions| source.eval(d)).with_context(|| format!("{name} as MERL .binary"))?;
            let bytes = merl.bytes();
            std::fs::write(&output, &bytes).with_context(|| format!("cannot write {}", output.display()))?;
            match a.json {
                true => println!(
                    "{}",
                    json!({ "written": output, "format": "merl-binary", "model": name, "bytes": bytes.len() })
                ),
                false => eprintln!(
                    "{name} written to {} (MERL 90 × 90 × 180, grey; isotropic and reciprocal by assumption: docs/render.md)",
                    output.display()
                ),
            }
        }
        _ => bail!(
            "{}: the extension must be .brdf (BRDF Explorer), .bsdf (RGL, for Mitsuba 3 and pbrt-v4) or .binary (MERL)",
            output.display()
        ),
    }
    Ok(())
}

fn export_bsdf(a: &ExportArgs, source: &Source, name: &str, origin: &str, output: &Path) -> Result<()> {
    let opt = Options {
        theta_i_step_deg: a.theta_step,
        spectra: a.grid,
        vndf: a.warp_grid,
        spectrum: a.spectrum,
        ..Options::default()
    };
    let written = write_bsdf(&|d: &Directions| source.eval(d), name, origin, output, &opt)?;
    report_bsdf(a.json, name, output, &written);
    Ok(())
}

fn report_bsdf(json: bool, name: &str, output: &Path, w: &Written) {
    let [median, p95, peak] = rgl::TOLERANCE;
    let acc = &w.accuracy;
    if json {
        println!(
            "{}",
            json!({"written": output, "format": "rgl-bsdf", "model": name, "bytes": w.bytes, "incidences": w.incidences,
                   "accuracy": acc, "tolerance": {"median": median, "p95": p95, "retro_peak": peak}, "within_tolerance": acc.within_tolerance()})
        );
        return;
    }
    eprintln!(
        "{name} written to {} ({:.1} MB, {} incidences)",
        output.display(),
        w.bytes as f64 / 1e6,
        w.incidences
    );
    eprintln!(
        "read back as a renderer reads it, at {} direction pairs: median error {:.2} %, 95th percentile {:.2} %, largest {:.1} % (at θi {:.1}°, θo {:.1}°, Δφ {:.1}°), retro peak {:.2} %",
        acc.pairs,
        100.0 * acc.median,
        100.0 * acc.p95,
        100.0 * acc.max,
        acc.worst_deg[0],
        acc.worst_deg[1],
        acc.worst_deg[2],
        100.0 * acc.retro_peak
    );
    if let Some(w) = coarse_warning(acc) {
        eprintln!("{w}");
    }
}
