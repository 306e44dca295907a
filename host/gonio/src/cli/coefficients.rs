//! `gonio coefficients`: R_A and R_L (CIE 54.2, ASTM E810, EN 1436) from a
//! fit, a model, or measured data, with standard uncertainties.

use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::text::Table;
use gonio_analysis::coefficients::{self, Asked, Set, Source};
use gonio_brdf::{Material, ModelId};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct CoefficientsArgs {
    /// Fits (FIT.json from `gonio fit --out`, or a report's fits/*.json),
    /// each of the same data: where the data hold a geometry its value is
    /// measured (or interpolated) from them; where they do not but it lies
    /// within their own spacing, the best adequate model (χ² consistent with
    /// the data's σ; lowest AIC; never a rational function) carries it,
    /// scaled to the data at the nearest measured incidences, the adequate
    /// models' spread widening the uncertainty; farther, or with no adequate
    /// model, it is `not measured` (null, with the reason and the scan that
    /// would measure it) unless --extrapolate (docs/retroreflection.md). The
    /// covariance gives the parameters' part (with the plate and the stage
    /// zeros when the fitted data came from `gonio calibrate`).
    #[arg(long, value_name = "FIT.json", num_args = 1.., conflicts_with_all = ["model", "data"])]
    pub fit: Vec<PathBuf>,
    /// A model id of models.md, with --params (no uncertainty).
    #[arg(long, requires = "params", conflicts_with_all = ["data", "material"])]
    pub model: Option<String>,
    /// The model's parameters, NAME=V,... (with --material: a model's, as `gonio scan --sim` takes them).
    #[arg(long)]
    pub params: Option<String>,
    /// A simulated head's material (`glass-beads`, or a model id as `gonio
    /// scan --sim --material` takes it): its own coefficients through the
    /// same apertures, the truth a simulated scan's are checked against.
    #[arg(long, conflicts_with_all = ["fit", "data"])]
    pub material: Option<String>,
    /// Measured data (calibrated CSV or ALTA .dat), interpolated between the
    /// nearest measured geometries, which are named; a geometry the data do
    /// not hold is refused (fit models and give --fit).
    #[arg(long, value_name = "FILE")]
    pub data: Option<PathBuf>,
    /// Named sets of geometries (repeatable).
    #[arg(long, value_enum)]
    pub set: Vec<Set>,
    /// R_A at these observation angles α (degrees), with --beta.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub alpha: Vec<f64>,
    /// ...and these entrance angles β (degrees, coplanar: β2 = 0).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub beta: Vec<f64>,
    /// ...and these rotation angles ε (degrees; no effect on an isotropic BRDF).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub epsilon: Vec<f64>,
    /// Also R_L at the 30 m road-marking geometry (as --set en1436).
    #[arg(long)]
    pub rl: bool,
    /// Angular diameter of the source seen from the sample (degrees); default: each set's own.
    #[arg(long)]
    pub source_aperture_deg: Option<f64>,
    /// Angular diameter of the receiver seen from the sample (degrees); default: each set's own.
    #[arg(long)]
    pub receiver_aperture_deg: Option<f64>,
    /// With --fit: compute the values the data cannot support from the
    /// models all the same (beyond the data's spacing, or with no adequate
    /// model), each marked `extrapolated` with what it rests on.
    #[arg(long, requires = "fit")]
    pub extrapolate: bool,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
}

impl CoefficientsArgs {
    fn source(&self) -> Result<Source> {
        if self.data.is_none() && self.instrument.stated()?.is_some() {
            bail!("--instrument-* state what measured a data file: with --data here, or when fitting it (`gonio fit FILE --instrument-…`), whose fit file keeps it");
        }
        if !self.fit.is_empty() {
            let (source, warning) = coefficients::fit_files::source(&self.fit)?;
            if let Some(w) = warning {
                eprintln!("warning: {w}");
            }
            return Ok(source.extrapolating(self.extrapolate));
        }
        if let Some(name) = &self.material {
            return Ok(Source::Truth(gonio_brdf::Specimen::named(name, self.params.as_deref())?));
        }
        if let (Some(m), Some(p)) = (&self.model, &self.params) {
            return Ok(Source::model(Material::parse(ModelId::parse(m)?, p)?));
        }
        if let Some(path) = &self.data {
            let data = super::load_data(path, None, &self.instrument)?;
            return Source::data(&data).with_context(|| format!("{}", path.display()));
        }
        bail!("give a BRDF: --fit FIT.json, --model M --params ..., --data FILE or --material NAME")
    }

    fn asked(&self) -> Asked {
        Asked {
            sets: self.set.clone(),
            rl: self.rl,
            alpha_deg: self.alpha.clone(),
            beta_deg: self.beta.clone(),
            epsilon_deg: self.epsilon.clone(),
            source_aperture_deg: self.source_aperture_deg,
            receiver_aperture_deg: self.receiver_aperture_deg,
        }
    }
}

pub fn coefficients_cmd(a: CoefficientsArgs) -> Result<()> {
    let source = a.source()?;
    let values = coefficients::compute(&source, &a.asked().requests()?)?;
    let instrument = source.instrument();
    match a.json {
        true => println!("{}", coefficients::json::to_json(&values, instrument)),
        false => print!(
            "{}",
            Table {
                values: &values,
                instrument
            }
        ),
    }
    Ok(())
}
