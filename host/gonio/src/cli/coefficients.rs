//! `gonio coefficients`: R_A and R_L (CIE 54.2, ASTM E810, EN 1436) from a
//! fit, a model, or measured data, with standard uncertainties.

use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::{self, Apertures, Kind, Provenance, Request, Set, Source};
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
            return Ok(Source::Truth(super::material::specimen(name, self.params.as_deref())?));
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

    fn requests(&self) -> Result<Vec<Request>> {
        let mut out = Vec::new();
        for s in &self.set {
            out.extend(s.requests());
        }
        if self.rl {
            out.extend(Set::En1436.requests());
        }
        match (self.alpha.is_empty(), self.beta.is_empty()) {
            (false, false) => out.extend(coefficients::grid(
                &self.alpha,
                &self.beta,
                &self.epsilon,
                coefficients::ASTM_APERTURES,
            )),
            (true, true) => {}
            _ => bail!("--alpha and --beta go together"),
        }
        if out.is_empty() {
            bail!("no geometry: give --set astm-e810, --set en1436, --rl, or --alpha with --beta");
        }
        for r in &mut out {
            r.apertures = Apertures {
                source_deg: self.source_aperture_deg.unwrap_or(r.apertures.source_deg),
                receiver_deg: self.receiver_aperture_deg.unwrap_or(r.apertures.receiver_deg),
            };
        }
        Ok(out)
    }
}

pub fn coefficients_cmd(a: CoefficientsArgs) -> Result<()> {
    let source = a.source()?;
    let requests = a.requests()?;
    let values = coefficients::compute(&source, &requests)?;
    let instrument = source.instrument();
    if a.json {
        println!("{}", coefficients::json::to_json(&values, instrument));
        return Ok(());
    }
    match instrument {
        Some(i) => println!("at {}, not photometric; u: standard uncertainty (k = 1)", i.wavelength_text()),
        None => println!("a model's values: at no instrument's wavelength, not photometric; u: standard uncertainty (k = 1)"),
    }
    println!(
        "{:<4} {:>6} {:>7} {:>6} {:>8} {:>8} {:>8} {:>25}  {:<12} unit",
        "", "α°", "β°", "ε°", "θi°", "θo°", "Δφ°", "value ± u (k = 1)", "rests on"
    );
    for c in &values {
        let g = &c.request.geometry;
        let [ti, to, dp] = c.sample_angles_deg;
        let name = match c.request.kind {
            Kind::Ra => "R_A",
            Kind::Rl => "R_L",
        };
        let rests_on = match &c.estimate.basis {
            Some(b) if b.provenance == Provenance::Extrapolated => "EXTRAPOLATED",
            Some(b) if b.provenance == Provenance::NotMeasured => "NOT MEASURED",
            Some(b) => b.provenance.name(),
            None => "",
        };
        if c.estimate.value.is_nan() {
            println!(
                "{name:<4} {:>6.2} {:>7.2} {:>6.1} {ti:>8.3} {to:>8.3} {dp:>8.2} {:>25}  {rests_on:<12} {}",
                g.alpha_deg,
                g.beta_deg(),
                g.epsilon_deg,
                "—",
                c.request.kind.unit()
            );
        } else {
            println!(
                "{name:<4} {:>6.2} {:>7.2} {:>6.1} {ti:>8.3} {to:>8.3} {dp:>8.2} {:>25}  {rests_on:<12} {}",
                g.alpha_deg,
                g.beta_deg(),
                g.epsilon_deg,
                gonio_analysis::rounding::with_uncertainty(c.estimate.value, c.estimate.u),
                c.request.kind.unit()
            );
        }
        if let Some(b) = c.estimate.basis.as_ref().filter(|b| !b.provenance.on_data()) {
            match (c.estimate.model, c.estimate.u_model) {
                (Some(m), Some(um)) => println!(
                    "       {}: carried by {m}; {} models carry it, their spread ±{}",
                    b.why,
                    c.estimate.models.len(),
                    gonio_analysis::rounding::significant(um, 2)
                ),
                _ => println!("       {}", b.why),
            }
            if let Some(m) = b.measure.as_ref().filter(|_| c.estimate.value.is_nan()) {
                println!("       measure it: {m}");
            }
        }
        if let Some(n) = c.estimate.nearest.first() {
            let names: Vec<String> = c
                .estimate
                .nearest
                .iter()
                .map(|n| format!("({:.2}°, {:.2}°, {:.1}°)", n.theta_i_deg, n.theta_o_deg, n.dphi_deg))
                .collect();
            println!(
                "       from the measured geometries {} (the nearest {:.3}° away)",
                names.join(", "),
                n.distance_deg
            );
        }
    }
    Ok(())
}
