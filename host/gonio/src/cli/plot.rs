//! `gonio plot`: the pictures of a data file, with fitted models drawn over it.

use anyhow::Result;
use gonio_analysis::fit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::plot;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct PlotArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Output directory of the pictures (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// A fit written by `gonio fit --out FIT.json` to draw over the data (repeatable): a model's, or a rational function's.
    #[arg(long)]
    pub fit: Vec<PathBuf>,
    /// How the hemisphere maps colour f_r.
    #[arg(long, value_enum, default_value = "log")]
    pub scale: plot::Scale,
    /// The maps' colour range of f_r, LO:HI in sr⁻¹ (default: the data's 1st
    /// to 99th percentile, so that a mirror lobe does not set it).
    #[arg(long, value_name = "LO:HI", value_parser = plot::colour_range)]
    pub range: Option<(f64, f64)>,
    /// Print one JSON object: the files written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
}

pub fn plot_cmd(a: PlotArgs) -> Result<()> {
    let data = super::load_data(&a.file, None, &a.instrument)?;
    let fits: Vec<FittedBrdf> = a.fit.iter().map(|p| fit::file::read_fitted(p)).collect::<Result<_>>()?;
    let options = plot::Options {
        scale: a.scale,
        range: a.range,
    };
    let files = plot::render(&data, &fits, &a.out, &options)?;
    match a.json {
        true => println!("{}", serde_json::json!({ "written": files })),
        false => eprintln!("{} pictures written to {}", files.len(), a.out.display()),
    }
    Ok(())
}
