//! `gonio calibrate`: its arguments as a calibration request
//! (`gonio_analysis::calibration::directory`), and what it did, as text or
//! JSON.

use anyhow::Result;
use gonio_analysis::calibration::directory::{calibrate, Request, SlopeSource};
use gonio_analysis::uncertainty::HeadUncertainty;
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
        HeadUncertainty::stated(self.u_zero_deg.as_deref(), self.backlash_deg.as_deref(), self.u_gain, self.stray_a)
    }
}

impl CalibrateArgs {
    /// The calibration these arguments ask for.
    pub fn request(&self) -> Result<Request> {
        Ok(Request {
            scan: self.scan.clone(),
            reference: self.reference.clone(),
            rho_ref: self.rho_ref,
            u_rho_ref: self.u_rho_ref,
            splitter: self.splitter,
            slope: SlopeSource::named(self.slope_fit.as_deref(), &self.slope_model)?,
            head: self.head.stated()?,
        })
    }
}

pub fn calibrate_cmd(a: CalibrateArgs) -> Result<()> {
    let c = calibrate(&a.request()?)?;
    match a.json {
        true => println!("{}", serde_json::to_value(&c.summary)?),
        false => print!("{c}"),
    }
    Ok(())
}
