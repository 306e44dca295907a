//! Fit files (`gonio fit --out`, a report's `fits/*.json`) as the source
//! of coefficients: each fit with its RMSE and AIC, all of one data set,
//! whose support they keep.

use super::{Fitted, Source, Support};
use crate::fit::file::{self, FittedBrdf};
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

/// The source of fit files: the fits and their data's support, or (one
/// fit of an earlier gonio, which kept no support) the model alone, with a
/// warning that says so.
pub fn source(paths: &[PathBuf]) -> Result<(Source, Option<String>)> {
    let files: Vec<file::FitFile> = paths.iter().map(|p| file::read(p)).collect::<Result<_>>()?;
    if files.iter().all(|f| f.support.is_none()) && files.len() == 1 {
        let warning = format!(
            "{} keeps no support of its data (a fit of an earlier gonio): what each value rests on is not known",
            paths[0].display()
        );
        let f = files.into_iter().next().context("one fit")?;
        let FittedBrdf::Model(material) = f.brdf else {
            bail!("{}: a rational fit without its data's support", paths[0].display());
        };
        let source = Source::Model {
            material,
            covariance: f.covariance,
        };
        return Ok((source, Some(warning)));
    }
    let mut support: Option<Support> = None;
    let mut fits = Vec::new();
    for (f, path) in files.into_iter().zip(paths) {
        // A rational function never carries a value, so it needs no AIC
        // (files of an earlier gonio have none).
        let aic = f.aic.or(matches!(f.brdf, FittedBrdf::Rational(_)).then_some(f64::INFINITY));
        let (Some(s), Some(rmse), Some(aic)) = (f.support, f.rmse, aic) else {
            bail!(
                "{}: a fit without its data's support, RMSE and AIC cannot be weighed against the others",
                path.display()
            );
        };
        match &support {
            Some(first) if first.points.len() != s.points.len() || first.incidences_deg != s.incidences_deg => {
                bail!("{}: fitted to other data than {}", path.display(), paths[0].display())
            }
            Some(_) => {}
            None => support = Some(s),
        }
        fits.push(Fitted {
            brdf: f.brdf,
            covariance: f.covariance,
            rmse,
            aic,
            goodness: f.goodness,
        });
    }
    Ok((Source::measured(fits, support.context("no fit")?)?, None))
}
