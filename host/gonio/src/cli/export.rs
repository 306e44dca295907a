//! `gonio export`: a fit (`gonio fit --out FIT.json`) or a simulated head's
//! material, written for another tool. The output's extension picks the
//! format: `.brdf`, a Disney BRDF Explorer shader (a model with its
//! parameters, or a rational function with its coefficients); `.bsdf`, the
//! RGL tensor file that Mitsuba 3 and pbrt-v4 render; `.binary`, MERL's
//! half-difference table (docs/render.md).

use anyhow::{bail, Result};
use gonio_analysis::evaluation::Brdf;
use gonio_analysis::formats::export::export;
use gonio_analysis::formats::rgl::{Options, Spectrum};
use gonio_brdf::Specimen;
use std::path::PathBuf;

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

pub fn export_cmd(a: ExportArgs) -> Result<()> {
    let (what, origin, output) = match (&a.material, a.paths.as_slice()) {
        (Some(m), [out]) => {
            let s = Specimen::named(m, a.params.as_deref())?;
            let origin = format!("the simulated material {}", s.describe());
            (Brdf::Specimen(s), origin, out)
        }
        (None, [fit, out]) => (Brdf::fitted(fit)?, format!("the fit {}", fit.display()), out),
        (Some(_), _) => bail!("with --material give only OUTPUT (the material is the source)"),
        (None, _) => bail!("give FIT.json OUTPUT, or OUTPUT with --material NAME"),
    };
    let name = what.name();
    let opt = Options {
        theta_i_step_deg: a.theta_step,
        spectra: a.grid,
        vndf: a.warp_grid,
        spectrum: a.spectrum,
        ..Options::default()
    };
    let written = export(&what, &name, &origin, output, &opt)?;
    match a.json {
        true => println!("{}", written.to_json(&name, output)),
        false => written.lines(&name, output).iter().for_each(|l| eprintln!("{l}")),
    }
    Ok(())
}
