//! Fit files: a fit as one JSON object (model,
//! parametrization, params, stderr, metrics), and a material read back from
//! one, for `gonio plot --fit` and `gonio export`.

use super::goodness::Goodness;
use super::{Fit, Metrics, Units};
use crate::coefficients::Support;
use anyhow::{bail, Context, Result};
use gonio_brdf::{Material, ModelId, Param};
use serde_json::{json, Map, Value};
use std::path::Path;

/// The JSON object of a fit, with the metrics of held-out samples if any.
pub fn to_json(f: &Fit, units: Units, holdout: Option<&Metrics>) -> Value {
    let m = &f.material;
    let names = m.model.param_names();
    let params: Map<String, Value> = names.iter().zip(&m.params).map(|(n, v)| (n.to_string(), json!(v))).collect();
    let stderr: Map<String, Value> = names.iter().zip(&f.stderr).map(|(n, v)| (n.to_string(), json!(v))).collect();
    let parametrization = if m.model.has_retro_cosine() { json!(m.param) } else { Value::Null };
    let mut v = json!({
        "model": m.model.name(), "parametrization": parametrization, "params": params, "stderr": stderr,
        "rmse": f.metrics.rmse, "nrmse": f.metrics.nrmse, "ncc": f.metrics.ncc, "l2": f.metrics.l2,
        "samples": f.samples, "seconds": f.seconds, "units": units,
        "aic": f.aic, "bic": f.bic, "at_bound": f.at_bound,
    });
    if let Some(c) = &f.covariance {
        let rows: Vec<Vec<f64>> = (0..c.nrows()).map(|i| c.row(i).iter().copied().collect()).collect();
        v["covariance"] = json!(rows);
    }
    if !f.undetermined.is_empty() {
        let why: Map<String, Value> = f.undetermined.iter().map(|(n, w)| (n.to_string(), json!(w))).collect();
        v["no_uncertainty"] = Value::Object(why);
    }
    if let Some(c) = &f.correlation {
        let rows: Vec<Vec<f64>> = (0..c.rho.nrows()).map(|i| c.rho.row(i).iter().copied().collect()).collect();
        v["correlation"] = json!({ "params": c.names, "matrix": rows });
    }
    if !f.widened.is_empty() {
        let w: Map<String, Value> = f.widened.iter().map(|(n, b)| (n.to_string(), json!([b.lo, b.hi]))).collect();
        v["widened"] = Value::Object(w);
    }
    if let Some(g) = &f.goodness {
        v["goodness"] = json!(g);
    }
    if let Some(h) = holdout {
        v["holdout"] = json!(h);
    }
    v
}

/// A fit read back: the model or rational function, and what its
/// uncertainty needs.
#[derive(Debug, Clone)]
pub struct FitFile {
    pub brdf: FittedBrdf,
    /// Covariance of a model's parameters, `models.md` order (`None` if the
    /// file has none, and for a rational function).
    pub covariance: Option<nalgebra::DMatrix<f64>>,
    pub rmse: Option<f64>,
    pub aic: Option<f64>,
    /// χ² against the data's σ (`None` where they had none, or in a file
    /// of an earlier gonio).
    pub goodness: Option<Goodness>,
    /// The measured samples about the retro direction the fit saw (`None`
    /// in a file of an earlier gonio): what its coefficients may rest on.
    pub support: Option<Support>,
}

/// Writes a fit's JSON with the support of the data it was fitted to
/// (`coefficients::Support`: the samples within 12° of the retro direction
/// and the incidences), so that `gonio coefficients --fit` can say what
/// each value rests on.
pub fn write_with_support(path: &Path, v: &Value, support: &Support) -> Result<()> {
    let mut v = v.clone();
    v["support"] = support.to_json();
    write(path, &v)
}

/// Reads a fit file whole.
pub fn read(path: &Path) -> Result<FitFile> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: Value = serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let brdf = if v["model"] == crate::rational::file::MODEL {
        FittedBrdf::Rational(crate::rational::file::function_of(&v).with_context(|| format!("{}", path.display()))?)
    } else {
        FittedBrdf::Model(material_of(&v).with_context(|| format!("{}", path.display()))?)
    };
    let covariance = match (&brdf, &v["covariance"]) {
        (FittedBrdf::Rational(_), _) | (_, Value::Null) => None,
        (FittedBrdf::Model(m), c) => {
            let n = m.params.len();
            // JSON has no NaN: serde_json writes one as null, as an earlier
            // gonio did for a covariance it could not compute. Such a
            // matrix states nothing, as an absent one.
            let rows: Vec<Vec<Option<f64>>> = serde_json::from_value(c.clone())
                .with_context(|| format!("{}: `covariance` is not a matrix of numbers", path.display()))?;
            if rows.len() != n || rows.iter().any(|r| r.len() != n) {
                bail!("{}: `covariance` must be {n} × {n}", path.display());
            }
            rows.iter()
                .flatten()
                .all(Option::is_some)
                .then(|| nalgebra::DMatrix::from_fn(n, n, |i, k| rows[i][k].unwrap_or(f64::NAN)))
        }
    };
    let support = match &v["support"] {
        Value::Null => None,
        s => Some(Support::from_json(s).with_context(|| format!("{}", path.display()))?),
    };
    Ok(FitFile {
        brdf,
        covariance,
        rmse: v["rmse"].as_f64(),
        aic: v["aic"].as_f64(),
        // A χ² an earlier gonio could not write (null) is not known.
        goodness: serde_json::from_value(v["goodness"].clone()).ok(),
        support,
    })
}

/// Writes a fit's JSON (pretty, one object).
pub fn write(path: &Path, v: &Value) -> Result<()> {
    std::fs::write(path, serde_json::to_string_pretty(v)? + "\n").with_context(|| format!("cannot write {}", path.display()))
}

/// The material of a fit file: a model's only.
pub fn read_material(path: &Path) -> Result<Material> {
    match read(path)?.brdf {
        FittedBrdf::Model(m) => Ok(m),
        FittedBrdf::Rational(_) => bail!(
            "{}: a rational fit: here only a parametric model's fit is taken (eval, dhr, export, plot and coefficients take a rational one)",
            path.display()
        ),
    }
}

/// What a fit file holds: a model with its parameters, or a rational
/// function (`gonio fit --model rational`).
#[derive(Debug, Clone, PartialEq)]
pub enum FittedBrdf {
    Model(Material),
    Rational(crate::rational::Rational),
}

impl FittedBrdf {
    /// `f_r` (sr⁻¹) at `d`; a rational function's is NaN at a pole.
    pub fn eval(&self, d: &gonio_brdf::Directions) -> f64 {
        match self {
            FittedBrdf::Model(m) => m.eval(d),
            FittedBrdf::Rational(r) => r.eval(d),
        }
    }

    /// The model's id, `rational` for a rational function.
    pub fn name(&self) -> &'static str {
        match self {
            FittedBrdf::Model(m) => m.model.name(),
            FittedBrdf::Rational(_) => crate::rational::file::MODEL,
        }
    }
}

/// Reads either kind of fit file.
pub fn read_fitted(path: &Path) -> Result<FittedBrdf> {
    read(path).map(|f| f.brdf)
}

fn material_of(v: &Value) -> Result<Material> {
    let model = ModelId::parse(v["model"].as_str().unwrap_or_default())?;
    let mut params = Vec::new();
    for name in model.param_names() {
        match v["params"][name].as_f64() {
            Some(x) => params.push(x),
            None => bail!("parameter `{name}` missing"),
        }
    }
    let param = if v["parametrization"] == "back" { Param::Back } else { Param::View };
    Ok(Material { model, params, param })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{fit, FitSpec, Weighting};
    use gonio_brdf::{Directions, ModelId};

    /// What `gonio fit --out` writes is read back whole: its χ², and a
    /// covariance an earlier gonio could not compute and wrote as nulls.
    #[test]
    fn a_fit_file_reads_back_with_its_goodness_and_undefined_covariances() {
        let truth = Material::parse(ModelId::Lambert, "kd=0.4").unwrap();
        let observations = (0..30)
            .map(|k| {
                let (ti, to, dphi) = ((10.0 + k as f64).to_radians(), (2.0 * k as f64).to_radians(), 0.3 * k as f64);
                let d = Directions::from_angles(ti, to, dphi);
                crate::fit::Observation {
                    theta_i: ti,
                    theta_o: to,
                    dphi,
                    value: truth.eval(&d) * (1.0 + 0.01 * ((k * 7 % 5) as f64 - 2.0)),
                    sigma: Some(0.002),
                    shared: Default::default(),
                }
            })
            .collect();
        let data = crate::fit::Dataset::new(Units::Fr, observations);
        let spec = FitSpec {
            weighting: Weighting::Sigma,
            ..FitSpec::new(ModelId::Lambert)
        };
        let f = fit(&data, &spec).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fit.json");
        let mut v = to_json(&f, Units::Fr, None);
        write(&path, &v).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.goodness, f.goodness);
        assert!(back.goodness.is_some() && back.covariance.is_some());
        // NaN is null in JSON: a covariance of nulls states nothing, and
        // the file is read all the same.
        v["covariance"] = serde_json::json!([[f64::NAN]]);
        assert_eq!(v["covariance"], serde_json::json!([[null]]));
        write(&path, &v).unwrap();
        let back = read(&path).unwrap();
        assert!(back.covariance.is_none());
        assert_eq!(read_material(&path).unwrap(), f.material);

        // retro-phong with its mirror lobe's height k3 held at 0: its
        // growth k4 moves nothing, has no standard error, and says why.
        let spec = FitSpec {
            weighting: Weighting::Sigma,
            fixed: vec![(4, 0.0)],
            ..FitSpec::new(ModelId::RetroPhong)
        };
        let f = fit(&data, &spec).unwrap();
        assert_eq!(f.stderr[5], None);
        assert!(f.stderr[0].is_some(), "{:?}", f.stderr);
        assert_eq!(f.undetermined.iter().map(|u| u.0).collect::<Vec<_>>(), ["k4"]);
        let v = to_json(&f, Units::Fr, None);
        assert!(v["no_uncertainty"]["k4"].as_str().unwrap().contains("do not depend on it"), "{v}");
        write(&path, &v).unwrap();
        let back = read(&path).unwrap();
        assert!(back.covariance.is_some_and(|c| c[(5, 5)] == 0.0 && c[(0, 0)] > 0.0));
    }
}
