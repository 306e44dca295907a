//! BRDF data files: ALTA text `.dat` (read and write) and the project's
//! calibrated sample CSV (read); [`load`] picks the reader by extension.
//! Fitted models are written for Disney's BRDF Explorer.

pub mod alta;
pub mod brdf_csv;
pub mod brdf_explorer;
pub mod export;
pub mod guard;
pub mod merl;
pub mod rgl;

use crate::fit::{Dataset, Units};
use anyhow::{Context, Result};
use std::io::{BufReader, Read};
use std::path::Path;

/// Reads a data set: `.dat` as ALTA, anything else as the sample CSV. The
/// file streams through [`guard`], so a binary or huge file is refused
/// early and in bounded memory. Where the file does not say what its
/// values are (ALTA's `UNKNOWN_OUTPUT`), `units` says it, or they are read
/// as `f_r` with a warning. Then the set is made fit to use: rows too
/// grazing for their units dropped, repeated geometries merged
/// (`Dataset::settle`), each said in a warning.
pub fn load(path: &Path, units: Option<Units>) -> Result<Dataset> {
    let context = || format!("{}", path.display());
    let unreadable = || format!("cannot read {}", path.display());
    let mut file = std::fs::File::open(path).with_context(unreadable)?;
    let mut head = Vec::with_capacity(guard::SNIFF_BYTES);
    (&mut file)
        .take(guard::SNIFF_BYTES as u64)
        .read_to_end(&mut head)
        .with_context(unreadable)?;
    guard::sniff(&head).with_context(context)?;
    let input = BufReader::new(guard::Guarded::new(std::io::Cursor::new(head).chain(file)));
    let mut data = match path.extension().and_then(|e| e.to_str()) {
        Some("dat") | Some("alta") => alta::read(input),
        _ => brdf_csv::read(input),
    }
    .with_context(context)?;
    if !data.units_stated {
        match units {
            Some(u) => data.units = u,
            None => data.warnings.push(
                "the file does not say what its values are (no #PARAM_OUT): read as f_r (sr⁻¹); give --units fr-cos if they are f_r·cosθo"
                    .into(),
            ),
        }
        data.units_stated = true;
    }
    data.settle();
    Ok(data)
}

/// [`load`], with the instrument the user stated (`None`: the file's own),
/// and the data's doubts (`Dataset::doubts`) added to the reader's warnings,
/// for a command to show.
pub fn load_stated(path: &Path, units: Option<Units>, instrument: Option<crate::instrument::Instrument>) -> Result<Dataset> {
    let mut data = load(path, units)?;
    if let Some(i) = instrument {
        data.instrument = i;
    }
    data.warnings.extend(data.doubts());
    Ok(data)
}
