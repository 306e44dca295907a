//! `gonio export`: a fit (`gonio fit --out FIT.json`) as a Disney BRDF
//! Explorer `.brdf` file, to look at the model in that tool: a model with
//! its parameters, or a rational function with its coefficients in the
//! shader.

use anyhow::{Context, Result};
use gonio_analysis::fit::file::{read_fitted, FittedBrdf};
use gonio_analysis::formats::brdf_explorer;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A fit written by `gonio fit --out FIT.json`.
    pub fit: PathBuf,
    /// Output `.brdf` file (GLSL `BRDF(L, V, N, X, Y)`; a model's parameters as parameter lines).
    pub output: PathBuf,
    /// Print one JSON object: what was written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// Writes a fit as `.brdf`, naming where it came from in the header.
pub fn write_brdf(fitted: &FittedBrdf, source: &str, out: &Path) -> Result<()> {
    let comments = [format!("from {source}")];
    let text = match fitted {
        FittedBrdf::Model(m) => brdf_explorer::write(m, &comments),
        FittedBrdf::Rational(r) => brdf_explorer::write_rational(r, &comments),
    };
    std::fs::write(out, text).with_context(|| format!("cannot write {}", out.display()))
}

pub fn export_cmd(a: ExportArgs) -> Result<()> {
    let fitted = read_fitted(&a.fit)?;
    write_brdf(&fitted, &a.fit.display().to_string(), &a.output)?;
    match a.json {
        true => println!("{}", serde_json::json!({ "written": a.output, "model": fitted.name() })),
        false => eprintln!("{} written to {}", fitted.name(), a.output.display()),
    }
    Ok(())
}
