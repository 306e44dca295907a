//! `gonio coefficients`: R_A and R_L (CIE 54.2, ASTM E810, EN 1436) from a
//! fit, a model, or measured data, with standard uncertainties.

use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::{self, Apertures, Coefficient, Fitted, Kind, Provenance, Request, Set, Source, Support};
use gonio_analysis::fit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::instrument::Instrument;
use gonio_brdf::{Material, ModelId};
use serde_json::{json, Value};
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
            return Ok(fits_source(&self.fit)?.extrapolating(self.extrapolate));
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

/// The source of `--fit FILE...`: the fits and their data's support, or
/// (one fit of an earlier gonio, which kept no support) the model alone.
fn fits_source(paths: &[PathBuf]) -> Result<Source> {
    let files: Vec<fit::file::FitFile> = paths.iter().map(|p| fit::file::read(p)).collect::<Result<_>>()?;
    if files.iter().all(|f| f.support.is_none()) && files.len() == 1 {
        eprintln!(
            "warning: {} keeps no support of its data (a fit of an earlier gonio): what each value rests on is not known",
            paths[0].display()
        );
        let f = files.into_iter().next().context("one fit")?;
        let FittedBrdf::Model(material) = f.brdf else {
            bail!("{}: a rational fit without its data's support", paths[0].display());
        };
        return Ok(Source::Model {
            material,
            covariance: f.covariance,
        });
    }
    let mut support: Option<Support> = None;
    let mut fits = Vec::new();
    for (f, path) in files.into_iter().zip(paths) {
        // A rational function never carries a value, so it needs no AIC
        // (files of an earlier gonio have none).
        let aic = f.aic.or(matches!(f.brdf, FittedBrdf::Rational(_)).then_some(f64::INFINITY));
        let (Some(s), Some(rmse), Some(aic)) = (f.support, f.rmse, aic) else {
            bail!(
                "{}: a fit without its data's support, RMSE and AIC cannot be weighed against the others",
                path.display()
            );
        };
        match &support {
            Some(first) if first.points.len() != s.points.len() || first.incidences_deg != s.incidences_deg => {
                bail!("{}: fitted to other data than {}", path.display(), paths[0].display())
            }
            Some(_) => {}
            None => support = Some(s),
        }
        fits.push(Fitted {
            brdf: f.brdf,
            covariance: f.covariance,
            rmse,
            aic,
            goodness: f.goodness,
        });
    }
    Source::measured(fits, support.context("no fit")?)
}

/// The coefficients as JSON: `ra` (a list) and `rl` (the last R_L, or
/// null), with the instrument the values rest on (`None`: a model's).
pub fn to_json(values: &[Coefficient], instrument: Option<Instrument>) -> Value {
    let entry = |c: &Coefficient| {
        let g = &c.request.geometry;
        let mut v = json!({
            "alpha_deg": g.alpha_deg, "beta_deg": g.beta_deg(), "epsilon_deg": g.epsilon_deg,
            "value": c.estimate.value, "u": c.estimate.u,
            "theta_i_deg": c.sample_angles_deg[0], "theta_o_deg": c.sample_angles_deg[1], "dphi_deg": c.sample_angles_deg[2],
            "source_aperture_deg": c.request.apertures.source_deg, "receiver_aperture_deg": c.request.apertures.receiver_deg,
        });
        if g.beta2_deg != 0.0 {
            v["beta1_deg"] = json!(g.beta1_deg);
            v["beta2_deg"] = json!(g.beta2_deg);
        }
        if !c.estimate.nearest.is_empty() {
            v["nearest"] = json!(c.estimate.nearest);
        }
        let e = &c.estimate;
        if let Some(b) = &e.basis {
            v["provenance"] = json!(b.provenance);
            v["basis"] = json!(b.why);
            if let Some(m) = &b.measure {
                v["measure_with"] = json!(m);
            }
        }
        for (key, part) in [
            ("u_params", e.u_params),
            ("u_model", e.u_model),
            ("u_aperture", e.u_aperture),
            ("u_arm_zero", e.u_arm_zero),
        ] {
            if let Some(x) = part {
                v[key] = json!(x);
            }
        }
        if let Some(m) = e.model {
            v["model"] = json!(m);
            v["models"] = json!(e.models);
        }
        v
    };
    let ra: Vec<Value> = values.iter().filter(|c| c.request.kind == Kind::Ra).map(entry).collect();
    let rl = values.iter().rev().find(|c| c.request.kind == Kind::Rl).map(|c| {
        let mut v = entry(c);
        if let Some(o) = v.as_object_mut() {
            o.remove("epsilon_deg");
        }
        v
    });
    json!({
        "ra": ra, "rl": rl,
        "units": {"ra": Kind::Ra.unit(), "rl": Kind::Rl.unit()},
        "wavelength_nm": instrument.and_then(|i| i.wavelength_nm()),
        "instrument": instrument.map(|i| i.to_json()),
        "note": format!("spectral values at {}, not photometric; u is the standard uncertainty (k = 1); \
                 provenance: measured (a sample at the geometry), interpolated (between samples on every side within the \
                 standard's aperture), extrapolated (within the data's spacing, an adequate model carries it: u holds the \
                 adequate models' spread, u_model) or not measured (value null: the basis says why, measure_with the scan \
                 that would measure it)", instrument.map_or("no instrument's wavelength (a model)".into(), |i| i.wavelength_text())),
    })
}

pub fn coefficients_cmd(a: CoefficientsArgs) -> Result<()> {
    let source = a.source()?;
    let requests = a.requests()?;
    let values = coefficients::compute(&source, &requests)?;
    let instrument = source.instrument();
    if a.json {
        println!("{}", to_json(&values, instrument));
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
