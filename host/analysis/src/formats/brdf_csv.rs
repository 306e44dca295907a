//! The project's calibrated sample CSV (`docs/samples-csv.md`): columns found
//! by name, `theta_i_deg, theta_o_deg, dphi_deg` and either `brdf_sr` (`f_r`)
//! or `brdf_cos_sr` (`f_r·cosθo`), optionally `brdf_sigma_sr` /
//! `brdf_cos_sigma_sr`, and the shifts of the inputs every sample shares
//! (`shift_NAME_sr`, `uncertainty::SHARED`), which a fit's covariance takes
//! in. Other columns (the raw values) are ignored. Rows
//! flagged as rejected (`flags` with the saturated or weak-signal bits) are
//! left out when a `usable` column says `false`. A file with this head's
//! raw columns is this head's; any other, of an instrument not known.

use super::guard::{self, MAX_ROWS};
use crate::fit::data::check_angles;
use crate::fit::{Dataset, Observation, Units};
use crate::instrument::Instrument;
use crate::uncertainty::SHARED;
use anyhow::{anyhow, bail, Result};
use std::io::Read;

/// Parses the CSV held in memory.
pub fn parse(text: &str) -> Result<Dataset> {
    read(text.as_bytes())
}

/// What the CSV reader met, with the line it met it on.
fn csv_error(e: csv::Error) -> anyhow::Error {
    let line = e.position().map_or(1, |p| p.line() as usize);
    match e.into_kind() {
        csv::ErrorKind::Io(e) => guard::line_error(e, line),
        csv::ErrorKind::Utf8 { .. } => anyhow!("line {line}: not UTF-8 text"),
        csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
            anyhow!("line {line}: {len} fields where the header has {expected_len}")
        }
        _ => anyhow!("line {line}: malformed CSV"),
    }
}

/// Reads the CSV as it streams.
pub fn read(input: impl Read) -> Result<Dataset> {
    let mut reader = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(input);
    let header = reader.headers().map_err(csv_error)?.clone();
    if header.iter().all(str::is_empty) {
        bail!("line 1: the file is empty");
    }
    let col = |name: &str| header.iter().position(|h| h == name);
    let need = |name: &str| col(name).ok_or_else(|| anyhow!("line 1: missing column `{name}`"));
    let (ti, to, dp) = (need("theta_i_deg")?, need("theta_o_deg")?, need("dphi_deg")?);
    let (units, value, sigma) = match (col("brdf_sr"), col("brdf_cos_sr")) {
        (Some(v), _) => (Units::Fr, v, col("brdf_sigma_sr")),
        (None, Some(v)) => (Units::FrCos, v, col("brdf_cos_sigma_sr")),
        (None, None) => bail!("line 1: no value column: expected `brdf_sr` (f_r) or `brdf_cos_sr` (f_r·cosθo)"),
    };
    let usable = col("usable");
    let shared = SHARED.map(|n| col(&format!("shift_{n}_sr")));
    let mut observations = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_error)?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        let num = |i: usize| -> Result<f64> {
            let f = record.get(i).unwrap_or("");
            let v: f64 = f
                .parse()
                .map_err(|_| anyhow!("line {line}: column `{}`: `{f}` is not a number", &header[i]))?;
            if v.is_finite() {
                Ok(v)
            } else {
                bail!("line {line}: column `{}`: `{f}` is not a finite number", &header[i])
            }
        };
        if usable.and_then(|u| record.get(u)) == Some("false") {
            continue;
        }
        let (theta_i, theta_o, dphi) = (num(ti)?.to_radians(), num(to)?.to_radians(), num(dp)?.to_radians());
        let (theta_i, theta_o, dphi) = check_angles(theta_i, theta_o, dphi).map_err(|e| anyhow!("line {line}: {e}"))?;
        if observations.len() == MAX_ROWS {
            return Err(guard::too_many_rows());
        }
        observations.push(Observation {
            theta_i,
            theta_o,
            dphi,
            value: num(value)?,
            sigma: match sigma {
                Some(s) if !record.get(s).unwrap_or("").is_empty() => Some(num(s)?),
                _ => None,
            },
            shared: {
                let mut v = [0.0; SHARED.len()];
                for (x, c) in v.iter_mut().zip(shared) {
                    if let Some(c) = c {
                        *x = num(c)?;
                    }
                }
                v
            },
        });
    }
    if observations.is_empty() {
        bail!("line 2: no data rows");
    }
    // This head's calibrated.csv keeps the raw columns beside the
    // calibrated ones: the gain it measured at and the shift of the arm's
    // zero are in no other tool's file.
    let instrument = match col("gain_index").and(col("shift_zero_psi_sr")) {
        Some(_) => Instrument::ThisHead,
        None => Instrument::Unknown,
    };
    Ok(Dataset {
        units,
        observations,
        metadata: Vec::new(),
        units_stated: true,
        warnings: Vec::new(),
        instrument,
    })
}
