//! Repeated scans compared, as `gonio repeatability` prints them (the
//! ratios of the scatter to the prediction, per incidence) and writes them
//! (a CSV of every geometry).

use super::{Repeatability, PEAK_SHARE, REPEATING};
use crate::rounding::{figure, significant};
use anyhow::{Context, Result};
use std::fmt;
use std::path::Path;

impl fmt::Display for Repeatability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} scans, {} geometries in common; the prediction: {} in quadrature",
            self.scans.len(),
            self.geometries.len(),
            REPEATING.join(", ")
        )?;
        writeln!(
            f,
            "s / predicted σ: median {}, pooled {}, at the peaks (the top {} % of values) {}; relative repeatability s / mean: median {} %",
            figure(self.median_ratio, 2),
            figure(self.pooled_ratio, 2),
            figure(100.0 * PEAK_SHARE, 0),
            figure(self.peak_median_ratio, 2),
            significant(100.0 * self.median_relative_s, 2)
        )?;
        let mut incidences: Vec<f64> = self.geometries.iter().map(|g| g.theta_i_deg).collect();
        incidences.sort_by(f64::total_cmp);
        incidences.dedup();
        for ti in incidences {
            let mut ratios: Vec<f64> = self.geometries.iter().filter(|g| g.theta_i_deg == ti).map(|g| g.ratio()).collect();
            ratios.sort_by(f64::total_cmp);
            writeln!(
                f,
                "  θi = {ti:>5}°: {:>5} geometries, s / σ median {}",
                ratios.len(),
                figure(ratios[ratios.len() / 2], 2)
            )?;
        }
        Ok(())
    }
}

impl Repeatability {
    /// Every geometry's n, mean, s and predicted σ, as CSV.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let mut w = csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))?;
        w.write_record(["theta_i_deg", "theta_o_deg", "dphi_deg", "n", "mean_sr", "s_sr", "u_predicted_sr"])?;
        for g in &self.geometries {
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
        w.flush().with_context(|| format!("cannot write {}", path.display()))
    }
}
