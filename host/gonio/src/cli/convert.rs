//! `gonio convert`: a BRDF data file (ALTA `.dat` or calibrated sample CSV)
//! written as ALTA text, in the units asked for.

use anyhow::{Context, Result};
use gonio_analysis::fit::Units;
use gonio_analysis::formats::alta;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// Input: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub input: PathBuf,
    /// Output ALTA file (ISOTROPIC_TL_TV_PROJ_DPHI; #VS 2 with k = 2 intervals when every value has an uncertainty, else #VS 0).
    pub output: PathBuf,
    /// Output units (default: the input's); for a file that does not say what
    /// its values are (ALTA without #PARAM_OUT), what they are.
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Print one JSON object: what was written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
}

pub fn convert_cmd(a: ConvertArgs) -> Result<()> {
    let mut data = super::load_data(&a.input, a.units, &a.instrument)?;
    if let Some(u) = a.units {
        data = data.in_units(u)?;
    }
    data.metadata.push(format!(
        "converted by gonio {} from {}",
        env!("CARGO_PKG_VERSION"),
        a.input.display()
    ));
    std::fs::write(&a.output, alta::write(&data)).with_context(|| format!("cannot write {}", a.output.display()))?;
    match a.json {
        true => println!("{}", serde_json::json!({ "written": a.output, "samples": data.observations.len() })),
        false => eprintln!("{} samples written to {}", data.observations.len(), a.output.display()),
    }
    Ok(())
}
