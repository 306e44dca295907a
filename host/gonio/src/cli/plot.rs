//! `gonio plot`: the pictures of a data file, with fitted models drawn over it.

use anyhow::Result;
use gonio_analysis::fit;
use gonio_analysis::plot;
use gonio_brdf::Material;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct PlotArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Output directory of the pictures (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// A fit written by `gonio fit --out FIT.json` to draw over the data (repeatable).
    #[arg(long)]
    pub fit: Vec<PathBuf>,
    /// Print one JSON object: the files written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

pub fn plot_cmd(a: PlotArgs) -> Result<()> {
    let data = super::load_data(&a.file, None)?;
    let fits: Vec<Material> = a.fit.iter().map(|p| fit::file::read_material(p)).collect::<Result<_>>()?;
    let files = plot::render(&data, &fits, &a.out)?;
    match a.json {
        true => println!("{}", serde_json::json!({ "written": files })),
        false => eprintln!("{} pictures written to {}", files.len(), a.out.display()),
    }
    Ok(())
}
