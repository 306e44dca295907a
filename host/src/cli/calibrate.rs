//! `gonio calibrate`: a sample scan turned into BRDF values with the scale of
//! a reference-plate scan, corrected for laser drift (`crate::calibration`).

use crate::calibration::{self, Calibration};
use crate::samples_csv;
use anyhow::{bail, Context, Result};
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
    /// Beam splitter factor on the retro path, if the plate run did not measure it.
    #[arg(long)]
    pub splitter: Option<f64>,
    #[arg(long)]
    pub json: bool,
}

fn rows(dir: &std::path::Path) -> Result<Vec<samples_csv::Row>> {
    let p = dir.join("samples.csv");
    if !p.exists() {
        bail!("{} holds no completed scan (no samples.csv)", dir.display());
    }
    samples_csv::read(&p)
}

/// A calibrated scan: what `gonio calibrate` wrote and reports.
pub struct Calibrated {
    pub cal: Calibration,
    pub drift: calibration::Drift,
    pub samples: usize,
    pub usable: usize,
    /// `calibration.json`'s content.
    pub summary: serde_json::Value,
    /// `calibrated.csv`.
    pub csv: PathBuf,
}

/// Calibrates a scan directory: writes calibrated.csv and calibration.json.
pub fn calibrate(a: &CalibrateArgs) -> Result<Calibrated> {
    let reference = a.reference.clone().unwrap_or_else(|| a.scan.join(super::reference::FILE));
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
        (samples_csv::read(&reference)?, Vec::new())
    };
    let cal = Calibration::from_plate(&plate, &monitor, a.rho_ref, a.splitter).context("calibrating on the reference plate")?;
    let sample = rows(&a.scan).context("reading the sample's scan")?;
    let (calibrated, drift) = cal.apply(&sample);
    let csv = a.scan.join("calibrated.csv");
    calibration::write_csv(&csv, &calibrated)?;
    let (lo, hi) = drift.range();
    let usable = calibrated.iter().filter(|r| r.usable).count();
    let summary = json!({
        "calibration": cal,
        "monitor_readings": drift.readings(),
        "laser_power_range": if drift.readings() > 0 { json!([lo, hi]) } else { json!(null) },
        "samples": calibrated.len(),
        "usable": usable,
        "file": csv,
    });
    let path = a.scan.join("calibration.json");
    std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n").with_context(|| format!("writing {}", path.display()))?;
    Ok(Calibrated {
        cal,
        drift,
        samples: calibrated.len(),
        usable,
        summary,
        csv,
    })
}

pub fn calibrate_cmd(a: CalibrateArgs) -> Result<()> {
    let Calibrated {
        cal,
        drift,
        samples,
        usable,
        summary,
        csv,
    } = calibrate(&a)?;
    if a.json {
        println!("{summary}");
        return Ok(());
    }
    println!(
        "scale K = {:.6e} A·sr (±{:.2} %), splitter T = {:.4} (±{:.2} %, {}), from {} plate samples",
        cal.scale_a_sr,
        100.0 * cal.scale_rel_sd,
        cal.splitter,
        100.0 * cal.splitter_rel_sd,
        if cal.splitter_measured { "measured" } else { "given" },
        cal.reference_samples
    );
    let (lo, hi) = drift.range();
    match drift.readings() {
        0 => println!("no laser-drift monitor in the sample scan: no drift correction"),
        n => println!(
            "laser power {:.2} %…{:.2} % of the plate's, {n} monitor visits",
            100.0 * lo,
            100.0 * hi
        ),
    }
    println!("{usable} of {samples} samples usable; written to {}", csv.display());
    Ok(())
}
