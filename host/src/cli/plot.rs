//! `gonio plot`: the pictures of a data file, with fitted models drawn over it.

use crate::brdf::{Material, ModelId, Param};
use crate::formats;
use crate::plot;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

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
}

/// A material from the JSON of a fit.
pub fn read_fit(path: &Path) -> Result<Material> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let model = ModelId::parse(v["model"].as_str().unwrap_or_default()).with_context(|| format!("{}", path.display()))?;
    let mut params = Vec::new();
    for name in model.param_names() {
        match v["params"][name].as_f64() {
            Some(x) => params.push(x),
            None => bail!("{}: parameter `{name}` missing", path.display()),
        }
    }
    let param = if v["parametrization"] == "back" { Param::Back } else { Param::View };
    Ok(Material { model, params, param })
}

pub fn plot_cmd(a: PlotArgs) -> Result<()> {
    let data = formats::load(&a.file)?;
    let fits: Vec<Material> = a.fit.iter().map(|p| read_fit(p)).collect::<Result<_>>()?;
    let files = plot::render(&data, &fits, &a.out)?;
    eprintln!("{} pictures written to {}", files.len(), a.out.display());
    Ok(())
}
