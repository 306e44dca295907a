//! A calibration as text for a terminal, as `gonio calibrate` prints it:
//! the plate's scale and splitter, the laser drift, the slope model, and
//! each incidence's budget with its largest components.

use super::directory::Calibrated;
use super::Calibration;
use crate::rounding::{significant, with_uncertainty};
use std::fmt;

impl fmt::Display for Calibrated {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let cal = &self.summary.calibration;
        writeln!(
            f,
            "scale K = {} A·sr, splitter T = {} ({}), from {} plate samples (± k = 1)",
            with_uncertainty(cal.scale_a_sr, cal.scale_a_sr * cal.scale_rel_sd),
            with_uncertainty(cal.splitter, cal.splitter * cal.splitter_rel_sd),
            if cal.splitter_measured { "measured" } else { "given" },
            cal.reference_samples
        )?;
        let (lo, hi) = self.drift.range();
        match self.drift.readings() {
            0 => writeln!(f, "no laser-drift monitor in the sample scan: no drift correction")?,
            n => writeln!(
                f,
                "laser power {:.2} %…{:.2} % of the plate's, {n} monitor visits",
                100.0 * lo,
                100.0 * hi
            )?,
        }
        match &self.slope {
            Some(m) => {
                let params: Vec<String> = m
                    .model
                    .param_names()
                    .iter()
                    .zip(&m.params)
                    .map(|(n, v)| format!("{n} = {}", significant(*v, 4)))
                    .collect();
                writeln!(f, "angle component from the slope of {} ({})", m.model.name(), params.join(", "))?
            }
            None => writeln!(f, "no angle component (--slope-model none)")?,
        }
        for b in &self.summary.budget {
            let top: Vec<String> = b
                .components
                .iter()
                .take(3)
                .map(|(n, u)| format!("{n} {:.2} %", 100.0 * u))
                .collect();
            writeln!(
                f,
                "θi = {:>5.1}°: median u = {:.2} % (k = 1); largest: {}",
                b.theta_i_deg,
                100.0 * b.combined,
                top.join(", ")
            )?;
        }
        writeln!(
            f,
            "{} of {} samples usable; written to {}",
            self.summary.usable,
            self.rows.len(),
            self.summary.file.display()
        )
    }
}

impl Calibration {
    /// The plate's scale and splitter in a line for a report, the plate's
    /// reflectance `rho`.
    pub fn plate_text(&self, rho: f64) -> String {
        format!(
            "reference plate ρ = {rho}: K = {} A·sr, splitter {} (± k = 1)",
            with_uncertainty(self.scale_a_sr, self.scale_a_sr * self.scale_rel_sd),
            with_uncertainty(self.splitter, self.splitter * self.splitter_rel_sd)
        )
    }
}
