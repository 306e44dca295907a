//! `gonio repeatability DIR1 DIR2 …`: repeated scans of one sample compared
//! geometry by geometry against the budget's prediction.

use anyhow::{Context, Result};
use gonio_analysis::repeatability::{self, Repeatability, REPEATING};
use gonio_analysis::rounding::{figure, significant};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct RepeatabilityArgs {
    /// Calibrated scans of the same sample and grid (scan directories after
    /// `gonio calibrate`, or their calibrated.csv), two or more.
    #[arg(required = true, num_args = 2..)]
    pub scans: Vec<PathBuf>,
    /// Write every geometry's n, mean, s and predicted σ to this CSV.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Draw s against the prediction into this directory (PNG and SVG).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print one JSON object: the summary and every geometry (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn repeatability_cmd(a: RepeatabilityArgs) -> Result<()> {
    let r = repeatability::compare(&a.scans)?;
    if let Some(path) = &a.csv {
        write_csv(&r, path)?;
    }
    let pictures = match &a.plot {
        Some(dir) => gonio_analysis::plot::repeatability::render(&r, dir)?,
        None => Vec::new(),
    };
    if a.json {
        let mut v = serde_json::to_value(&r)?;
        v["predicted_from"] = serde_json::json!(REPEATING);
        v["pictures"] = serde_json::json!(pictures);
        println!("{v}");
        return Ok(());
    }
    println!(
        "{} scans, {} geometries in common; the prediction: {} in quadrature",
        r.scans.len(),
        r.geometries.len(),
        REPEATING.join(", ")
    );
    println!(
        "s / predicted σ: median {}, pooled {}, at the peaks (the top {} % of values) {}; relative repeatability s / mean: median {} %",
        figure(r.median_ratio, 2),
        figure(r.pooled_ratio, 2),
        figure(100.0 * gonio_analysis::repeatability::PEAK_SHARE, 0),
        figure(r.peak_median_ratio, 2),
        significant(100.0 * r.median_relative_s, 2)
    );
    let mut incidences: Vec<f64> = r.geometries.iter().map(|g| g.theta_i_deg).collect();
    incidences.sort_by(f64::total_cmp);
    incidences.dedup();
    for ti in incidences {
        let mut ratios: Vec<f64> = r.geometries.iter().filter(|g| g.theta_i_deg == ti).map(|g| g.ratio()).collect();
        ratios.sort_by(f64::total_cmp);
        println!(
            "  θi = {ti:>5}°: {:>5} geometries, s / σ median {}",
            ratios.len(),
            figure(ratios[ratios.len() / 2], 2)
        );
    }
    Ok(())
}

fn write_csv(r: &Repeatability, path: &PathBuf) -> Result<()> {
    let mut w = csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))?;
    w.write_record(["theta_i_deg", "theta_o_deg", "dphi_deg", "n", "mean_sr", "s_sr", "u_predicted_sr"])?;
    for g in &r.geometries {
        w.write_record([
            g.theta_i_deg.to_string(),
            g.theta_o_deg.to_string(),
            g.dphi_deg.to_string(),
            g.n.to_string(),
            g.mean_sr.to_string(),
            g.s_sr.to_string(),
            g.u_predicted_sr.to_string(),
        ])?;
    }
    w.flush().with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
