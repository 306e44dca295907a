//! `calibrated.csv`: every raw column of `samples.csv`, then the calibrated
//! value with its k = 2 interval, each uncertainty component and each
//! shared input's shift, under names the calibration gives.

use crate::samples::Row;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;

/// The calibrated columns of one row.
#[derive(Debug, Clone, Copy)]
pub struct Values<'a> {
    /// Laser power relative to the plate's.
    pub laser_power: f64,
    pub usable: bool,
    pub brdf_sr: f64,
    pub brdf_sigma_sr: f64,
    pub brdf_cos_sr: f64,
    /// The k = 2 interval.
    pub brdf_lo_sr: f64,
    pub brdf_hi_sr: f64,
    /// One value per name of [`Writer::create`]'s `components`, then one per `shifts`.
    pub components: &'a [f64],
}

/// Writes `calibrated.csv` row by row.
pub struct Writer {
    out: std::io::BufWriter<std::fs::File>,
    path: std::path::PathBuf,
    header: bool,
    /// Column names after the fixed ones: `u_NAME_sr` then `shift_NAME_sr`.
    extra: Vec<String>,
}

impl Writer {
    /// `components` are the budget's component names (`u_NAME_sr`),
    /// `shifts` the shared inputs' names (`shift_NAME_sr`).
    pub fn create(path: &Path, components: &[&str], shifts: &[&str]) -> Result<Writer> {
        let out = std::io::BufWriter::new(std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?);
        let extra = components
            .iter()
            .map(|n| format!("u_{n}_sr"))
            .chain(shifts.iter().map(|n| format!("shift_{n}_sr")))
            .collect();
        Ok(Writer {
            out,
            path: path.to_path_buf(),
            header: true,
            extra,
        })
    }

    pub fn push(&mut self, raw: &Row, v: &Values) -> Result<()> {
        if v.components.len() != self.extra.len() {
            anyhow::bail!("{} component values for {} columns", v.components.len(), self.extra.len());
        }
        // The raw part is serialised by the same code as samples.csv, so
        // the columns cannot drift apart.
        let mut w = csv::WriterBuilder::new().has_headers(self.header).from_writer(Vec::new());
        w.serialize(raw)?;
        let text = String::from_utf8(w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?)?;
        let mut lines = text.lines();
        if self.header {
            let header = lines.next().unwrap_or_default();
            writeln!(
                self.out,
                "{header},laser_power,usable,brdf_sr,brdf_sigma_sr,brdf_cos_sr,brdf_lo_sr,brdf_hi_sr,{}",
                self.extra.join(",")
            )?;
            self.header = false;
        }
        let u: Vec<String> = v.components.iter().map(f64::to_string).collect();
        writeln!(
            self.out,
            "{},{},{},{},{},{},{},{},{}",
            lines.next().unwrap_or_default(),
            v.laser_power,
            v.usable,
            v.brdf_sr,
            v.brdf_sigma_sr,
            v.brdf_cos_sr,
            v.brdf_lo_sr,
            v.brdf_hi_sr,
            u.join(",")
        )?;
        Ok(())
    }

    pub fn finish(mut self) -> Result<()> {
        self.out.flush().with_context(|| format!("writing {}", self.path.display()))
    }
}
