//! `gonio export`: a fit (`gonio fit --out FIT.json`) as a Disney BRDF
//! Explorer `.brdf` file, to look at the model in that tool: a model with
//! its parameters, or a rational function with its coefficients in the
//! shader.

use anyhow::{Context, Result};
use gonio_analysis::fit::file::{read_fitted, Fitted};
use gonio_analysis::formats::brdf_explorer;
use gonio_analysis::rational;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A fit written by `gonio fit --out FIT.json`.
    pub fit: PathBuf,
    /// Output `.brdf` file (GLSL `BRDF(L, V, N, X, Y)` with parameter lines).
    pub output: PathBuf,
    /// Print one JSON object: what was written (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

/// Writes a fitted material as `.brdf`, naming where it came from in the header.
pub fn write_brdf(m: &gonio_brdf::Material, source: &str, out: &Path) -> Result<()> {
    let text = brdf_explorer::write(m, &[format!("from {source}")]);
    std::fs::write(out, text).with_context(|| format!("cannot write {}", out.display()))
}

pub fn export_cmd(a: ExportArgs) -> Result<()> {
    let source = a.fit.display().to_string();
    let model = match read_fitted(&a.fit)? {
        Fitted::Model(m) => {
            write_brdf(&m, &source, &a.output)?;
            m.model.name()
        }
        Fitted::Rational(r) => {
            let text = brdf_explorer::write_rational(&r, &[format!("from {source}")]);
            std::fs::write(&a.output, text).with_context(|| format!("cannot write {}", a.output.display()))?;
            rational::file::MODEL
        }
    };
    match a.json {
        true => println!("{}", serde_json::json!({ "written": a.output, "model": model })),
        false => eprintln!("{model} written to {}", a.output.display()),
    }
    Ok(())
}
