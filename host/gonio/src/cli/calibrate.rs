//! `gonio calibrate`: a sample scan turned into BRDF values with the scale of
//! a reference-plate scan, corrected for laser drift (`gonio_analysis::calibration`),
//! each value with its uncertainty budget (`gonio_analysis::uncertainty`).

use anyhow::{bail, Context, Result};
use gonio_analysis::calibration::{self, Budget, CalibratedRow, Calibration};
use gonio_analysis::fit::{self, FitSpec};
use gonio_analysis::rounding::{significant, with_uncertainty};
use gonio_analysis::uncertainty::HeadUncertainty;
use gonio_brdf::{Material, ModelId, Param};
use gonio_scan_dir::samples;
use gonio_scan_dir::ScanDir;
use serde_json::json;
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

fn rows(dir: &std::path::Path) -> Result<Vec<samples::Row>> {
    let p = ScanDir::new(dir).samples();
    if !p.exists() {
        bail!("{} holds no completed scan (no samples.csv)", dir.display());
    }
    samples::read(&p)
}

/// A calibrated scan: what `gonio calibrate` wrote and reports.
pub struct Calibrated {
    pub cal: Calibration,
    pub drift: calibration::Drift,
    pub rows: Vec<CalibratedRow>,
    pub usable: usize,
    /// The model whose slope gave the angle component, if any.
    pub slope: Option<Material>,
    /// `calibration.json`'s content.
    pub summary: serde_json::Value,
    /// `calibrated.csv`.
    pub csv: PathBuf,
}

/// The model whose slope gives the angle component.
fn slope_model(a: &CalibrateArgs, first: &[CalibratedRow]) -> Result<Option<Material>> {
    if let Some(path) = &a.slope_fit {
        return fit::file::read_material(path).map(Some);
    }
    if a.slope_model == "none" {
        return Ok(None);
    }
    let model = ModelId::parse(&a.slope_model).context("--slope-model")?;
    let spec = FitSpec {
        param: Param::View,
        ..FitSpec::new(model)
    };
    let f = fit::fit(&calibration::dataset(first), &spec).with_context(|| format!("fitting {} for the BRDF's slope", model.name()))?;
    Ok(Some(f.material))
}

/// Calibrates a scan directory: writes calibrated.csv and calibration.json.
pub fn calibrate(a: &CalibrateArgs) -> Result<Calibrated> {
    if !a.scan.is_dir() {
        bail!("{} is not a scan directory (no such directory)", a.scan.display());
    }
    let reference = a.reference.clone().unwrap_or_else(|| ScanDir::new(&a.scan).reference());
    let (plate, monitor) = if reference.is_dir() {
        let all = rows(&reference).context("reading the reference plate's scan")?;
        all.into_iter().partition(|r| r.index.is_some())
    } else {
        if !reference.exists() {
            bail!(
                "no reference plate: {} is missing (scan with --reference-plate, or give --reference)",
                reference.display()
            );
        }
        (samples::read(&reference)?, Vec::new())
    };
    let cal =
        Calibration::from_plate(&plate, &monitor, a.rho_ref, a.u_rho_ref, a.splitter).context("calibrating on the reference plate")?;
    let sample = rows(&a.scan).context("reading the sample's scan")?;
    let mut budget = Budget {
        head: a.head.stated()?,
        slope: None,
    };
    // The slope comes from the calibrated values themselves: a first pass
    // without the angle component, a smooth model fitted to it, a second pass.
    let (first, _) = cal.apply(&sample, &budget);
    budget.slope = slope_model(a, &first)?;
    let (calibrated, drift) = cal.apply(&sample, &budget);
    let csv = ScanDir::new(&a.scan).calibrated();
    calibration::write_csv(&csv, &calibrated)?;
    let (lo, hi) = drift.range();
    let usable = calibrated.iter().filter(|r| r.usable).count();
    let summary = json!({
        "calibration": cal,
        "monitor_readings": drift.readings(),
        "laser_power_range": if drift.readings() > 0 { json!([lo, hi]) } else { json!(null) },
        "samples": calibrated.len(),
        "usable": usable,
        "head_uncertainty": budget.head,
        "slope_model": budget.slope.as_ref().map(|m| json!({"model": m.model.name(), "params": m.params_string()})),
        "budget": calibration::budget_by_incidence(&calibrated),
        "file": csv,
    });
    let path = ScanDir::new(&a.scan).calibration();
    std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n").with_context(|| format!("writing {}", path.display()))?;
    Ok(Calibrated {
        cal,
        drift,
        rows: calibrated,
        usable,
        slope: budget.slope,
        summary,
        csv,
    })
}

pub fn calibrate_cmd(a: CalibrateArgs) -> Result<()> {
    let c = calibrate(&a)?;
    if a.json {
        println!("{}", c.summary);
        return Ok(());
    }
    let cal = &c.cal;
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
    for b in calibration::budget_by_incidence(&c.rows) {
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
    println!("{} of {} samples usable; written to {}", c.usable, c.rows.len(), c.csv.display());
    Ok(())
}
