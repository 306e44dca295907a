//! `gonio fit` and `gonio compare`: models fitted to a data file (ALTA `.dat`
//! or the calibrated sample CSV).

use super::fit_args::{CompareArgs, FitArgs};
use super::fitting::{compare, kept};
use anyhow::{bail, Result};
use gonio_analysis::fit;
use gonio_analysis::fit::comparison::model_fit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::fit::text::{box_notes, ComparisonTable, FitText};
use gonio_brdf::ModelId;

pub fn fit_cmd(a: FitArgs) -> Result<()> {
    if a.rational.given() {
        bail!(
            "--segments, --max-degree and --no-cosine are options of --model rational, not of {}",
            a.model
        );
    }
    let model = ModelId::parse(&a.model)
        .map_err(|e| anyhow::anyhow!("{e}, or `{}` (the rational function)", gonio_analysis::rational::file::MODEL))?;
    let d = a.options.select(&a.file)?;
    let settings = a.options.settings(&a.fix)?;
    let (f, holdout) = model_fit(&d, &settings, model, false)?;
    let v = fit::file::to_json(&f, d.train.units, holdout.as_ref());
    let v = kept(&a, &d, v, &FittedBrdf::Model(f.material.clone()))?;
    if a.options.json {
        println!("{v}");
        return Ok(());
    }
    let fixed: Vec<String> = settings.fixed.iter().map(|(n, _)| n.clone()).collect();
    let holdout = holdout.as_ref().map(|h| (a.options.holdout_theta_i.as_slice(), h));
    print!(
        "{}",
        FitText {
            fit: &f,
            fixed: &fixed,
            holdout
        }
    );
    for n in box_notes(&f) {
        eprintln!("{n}");
    }
    Ok(())
}

pub fn compare_cmd(a: CompareArgs) -> Result<()> {
    if let Some(dir) = a.report.as_ref().filter(|d| d.join("report.html").exists() && !a.force) {
        bail!("{} already holds a report; choose another --report or pass --force", dir.display());
    }
    let rational = a.rational.rational_spec(a.options.param)?;
    let d = a.options.select(&a.file)?;
    let comparison = compare(&d, &a.options, Some(&rational))?;
    if let Some(dir) = &a.report {
        let mut facts = vec![("data".to_string(), a.file.display().to_string())];
        facts.extend(d.train.metadata.iter().map(|m| ("metadata".to_string(), m.clone())));
        let path = comparison.report(dir, format!("Model comparison: {}", a.file.display()), facts, &d, &[])?;
        if !a.options.json {
            eprintln!("report: {}", path.display());
        }
    }
    if a.options.json {
        println!("{}", comparison.into_json());
        return Ok(());
    }
    let table = ComparisonTable {
        comparison: &comparison,
        samples: d.train.observations.len(),
        units: d.train.units,
    };
    print!("{table}");
    for why in &comparison.unfitted {
        eprintln!("note: not fitted: {why}");
    }
    Ok(())
}
