//! `gonio repeatability DIR1 DIR2 …`: repeated scans of one sample compared
//! geometry by geometry against the budget's prediction.

use anyhow::Result;
use gonio_analysis::repeatability::{self, REPEATING};
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
        r.write_csv(path)?;
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
    print!("{r}");
    Ok(())
}
