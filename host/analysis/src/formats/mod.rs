//! BRDF data files: ALTA text `.dat` (read and write) and the project's
//! calibrated sample CSV (read); [`load`] picks the reader by extension.
//! Fitted models are written for Disney's BRDF Explorer.

pub mod alta;
pub mod brdf_csv;
pub mod brdf_explorer;
pub mod merl;
pub mod rgl;

use crate::fit::Dataset;
use anyhow::{Context, Result};
use std::path::Path;

/// Reads a data set: `.dat` as ALTA, anything else as the sample CSV.
pub fn load(path: &Path) -> Result<Dataset> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let parsed = match path.extension().and_then(|e| e.to_str()) {
        Some("dat") | Some("alta") => alta::parse(&text),
        _ => brdf_csv::parse(&text),
    };
    parsed.with_context(|| format!("{}", path.display()))
}
