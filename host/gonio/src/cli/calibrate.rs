//! `gonio calibrate`: its arguments as a calibration request
//! (`gonio_analysis::calibration::directory`), and what it did, as text or
//! JSON.

use anyhow::{bail, Context, Result};
use gonio_analysis::calibration::directory::{calibrate, Request, SlopeSource};
use gonio_analysis::rounding::{significant, with_uncertainty};
use gonio_analysis::uncertainty::HeadUncertainty;
use gonio_brdf::ModelId;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// Directory of the sample's completed scan (samples.csv).
    pub scan: PathBuf,
    /// The reference plate's samples: a reference.csv (default: the one
    /// `gonio scan --reference-plate` wrote into the scan's directory) or the
    /// directory of a plate scan taken just before, on the same head clock.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Hemispherical reflectance of the Lambertian reference plate.
    #[arg(long, default_value_t = 0.99)]
    pub rho_ref: f64,
    /// Standard uncertainty of --rho-ref (the plate's certificate).
    #[arg(long, default_value_t = 0.005)]
    pub u_rho_ref: f64,
    /// Beam splitter factor on the retro path, if the plate run did not measure it.
    #[arg(long)]
    pub splitter: Option<f64>,
    /// Model whose local slope turns stage-angle errors into BRDF errors: it
    /// is fitted to the calibrated data (only its slope is used), or `none`
    /// for no angle component.
    #[arg(long, default_value = "retro-phong")]
    pub slope_model: String,
    /// Take the slope from this fit (FIT.json) instead of fitting one.
    #[arg(long, value_name = "FIT.json")]
    pub slope_fit: Option<PathBuf>,
    #[command(flatten)]
    pub head: HeadUncertaintyArgs,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// The head's stated uncertainties; each left out is the reference head's
/// (`HeadUncertainty::default`: 0.02° zeros, 0.01° backlash, 0.2 % gains,
/// 2 pA stray light).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct HeadUncertaintyArgs {
    /// Standard uncertainty of each stage's zero (degrees): one value for
    /// every axis, or three (ω, τ, ψ).
    #[arg(long, value_delimiter = ',')]
    pub u_zero_deg: Option<Vec<f64>>,
    /// Backlash of each stage (degrees): one value or three.
    #[arg(long, value_delimiter = ',')]
    pub backlash_deg: Option<Vec<f64>>,
    /// Relative standard uncertainty of each gain range.
    #[arg(long)]
    pub u_gain: Option<f64>,
    /// Largest chopped stray-light photocurrent (A).
    #[arg(long)]
    pub stray_a: Option<f64>,
}

impl HeadUncertaintyArgs {
    pub fn stated(&self) -> Result<HeadUncertainty> {
        let reference = HeadUncertainty::default();
        let valid = |x: f64| x.is_finite() && x >= 0.0;
        let three = |v: &Option<Vec<f64>>, default: [f64; 3], name: &str| -> Result<[f64; 3]> {
            match v.as_deref() {
                None => Ok(default),
                Some(v) if v.iter().any(|x| !valid(*x)) => bail!("--{name} must be finite and ≥ 0"),
                Some([x]) => Ok([*x; 3]),
                Some([a, b, c]) => Ok([*a, *b, *c]),
                Some(v) => bail!("--{name} takes one value or three (ω, τ, ψ), found {}", v.len()),
            }
        };
        let one = |v: Option<f64>, default: f64, name: &str| -> Result<f64> {
            match v {
                None => Ok(default),
                Some(x) if valid(x) => Ok(x),
                Some(_) => bail!("--{name} must be finite and ≥ 0"),
            }
        };
        Ok(HeadUncertainty {
            zero_deg: three(&self.u_zero_deg, reference.zero_deg, "u-zero-deg")?,
            backlash_deg: three(&self.backlash_deg, reference.backlash_deg, "backlash-deg")?,
            gain_rel: one(self.u_gain, reference.gain_rel, "u-gain")?,
            stray_a: one(self.stray_a, reference.stray_a, "stray-a")?,
        })
    }
}

impl CalibrateArgs {
    /// The command line's defaults for a scan directory (the simulated
    /// head's plate and certificate).
    pub fn for_scan(scan: PathBuf, json: bool) -> Self {
        CalibrateArgs {
            scan,
            reference: None,
            rho_ref: gonio_sim::PLATE_RHO,
            u_rho_ref: gonio_sim::PLATE_RHO_U,
            splitter: None,
            slope_model: "retro-phong".into(),
            slope_fit: None,
            head: HeadUncertaintyArgs::default(),
            json,
        }
    }
}

impl CalibrateArgs {
    /// The calibration these arguments ask for.
    pub fn request(&self) -> Result<Request> {
        let slope = match (&self.slope_fit, self.slope_model.as_str()) {
            (Some(path), _) => SlopeSource::File(path.clone()),
            (None, "none") => SlopeSource::None,
            (None, name) => SlopeSource::Fitted(ModelId::parse(name).context("--slope-model")?),
        };
        Ok(Request {
            scan: self.scan.clone(),
            reference: self.reference.clone(),
            rho_ref: self.rho_ref,
            u_rho_ref: self.u_rho_ref,
            splitter: self.splitter,
            slope,
            head: self.head.stated()?,
        })
    }
}

pub fn calibrate_cmd(a: CalibrateArgs) -> Result<()> {
    let c = calibrate(&a.request()?)?;
    if a.json {
        println!("{}", serde_json::to_value(&c.summary)?);
        return Ok(());
    }
    let cal = &c.summary.calibration;
    println!(
        "scale K = {} A·sr, splitter T = {} ({}), from {} plate samples (± k = 1)",
        with_uncertainty(cal.scale_a_sr, cal.scale_a_sr * cal.scale_rel_sd),
        with_uncertainty(cal.splitter, cal.splitter * cal.splitter_rel_sd),
        if cal.splitter_measured { "measured" } else { "given" },
        cal.reference_samples
    );
    let (lo, hi) = c.drift.range();
    match c.drift.readings() {
        0 => println!("no laser-drift monitor in the sample scan: no drift correction"),
        n => println!(
            "laser power {:.2} %…{:.2} % of the plate's, {n} monitor visits",
            100.0 * lo,
            100.0 * hi
        ),
    }
    match &c.slope {
        Some(m) => {
            let params: Vec<String> = m
                .model
                .param_names()
                .iter()
                .zip(&m.params)
                .map(|(n, v)| format!("{n} = {}", significant(*v, 4)))
                .collect();
            println!("angle component from the slope of {} ({})", m.model.name(), params.join(", "))
        }
        None => println!("no angle component (--slope-model none)"),
    }
    for b in &c.summary.budget {
        let top: Vec<String> = b
            .components
            .iter()
            .take(3)
            .map(|(n, u)| format!("{n} {:.2} %", 100.0 * u))
            .collect();
        println!(
            "θi = {:>5.1}°: median u = {:.2} % (k = 1); largest: {}",
            b.theta_i_deg,
            100.0 * b.combined,
            top.join(", ")
        );
    }
    println!(
        "{} of {} samples usable; written to {}",
        c.summary.usable,
        c.rows.len(),
        c.summary.file.display()
    );
    Ok(())
}
