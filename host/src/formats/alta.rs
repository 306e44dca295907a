//! ALTA's text data format (`models.md` §1): a header of `#DIM in out`,
//! `#PARAM_IN`, `#PARAM_OUT`, `#VS`, other `#` lines (kept as metadata), then
//! one sample per line. Input forms read: `ISOTROPIC_TL_TV_PROJ_DPHI`
//! (`θL, θV·cosΔφ, θV·sinΔφ`, the form written), `ISOTROPIC_TV_TL_DPHI`
//! (`θV, θL, Δφ`) and `SPHERICAL_TL_PL_TV_PV` (`θL, φL, θV, φV`), radians.
//! Outputs: `INV_STERADIAN` (`f_r`) and `INV_STERADIAN_COSINE_FACTOR`
//! (`f_r·cosθo`). Confidence columns: `#VS 0` (none), `#VS 1` (one more
//! number per value: its standard uncertainty) and `#VS 2` (two more: the
//! lower and upper ends of its k = 2 interval); the writer uses `#VS 2` for
//! values that carry an uncertainty.

use crate::fit::{Dataset, Observation, Units};
use crate::uncertainty::K_COVERAGE;
use anyhow::{anyhow, bail, Result};
use std::fmt::Write;

#[derive(Debug, Clone, Copy, PartialEq)]
enum ParamIn {
    TlTvProjDphi,
    TvTlDphi,
    SphericalTlPlTvPv,
}

impl ParamIn {
    fn parse(s: &str) -> Option<Self> {
        match s {
            "ISOTROPIC_TL_TV_PROJ_DPHI" => Some(Self::TlTvProjDphi),
            "ISOTROPIC_TV_TL_DPHI" => Some(Self::TvTlDphi),
            "SPHERICAL_TL_PL_TV_PV" => Some(Self::SphericalTlPlTvPv),
            _ => None,
        }
    }

    fn dim(self) -> usize {
        match self {
            Self::SphericalTlPlTvPv => 4,
            _ => 3,
        }
    }

    /// `(θi, θo, Δφ)` from one row's inputs.
    fn angles(self, x: &[f64]) -> (f64, f64, f64) {
        match self {
            Self::TlTvProjDphi => (x[0], x[1].hypot(x[2]), x[2].atan2(x[1])),
            Self::TvTlDphi => (x[1], x[0], x[2]),
            Self::SphericalTlPlTvPv => (x[0], x[2], x[3] - x[1]),
        }
    }
}

fn units(s: &str) -> Option<Units> {
    match s {
        "INV_STERADIAN" => Some(Units::Fr),
        "INV_STERADIAN_COSINE_FACTOR" => Some(Units::FrCos),
        _ => None,
    }
}

fn unit_name(u: Units) -> &'static str {
    match u {
        Units::Fr => "INV_STERADIAN",
        Units::FrCos => "INV_STERADIAN_COSINE_FACTOR",
    }
}

/// Parses an ALTA text file; errors name the line (1-based).
pub fn parse(text: &str) -> Result<Dataset> {
    let (mut dim, mut param_in, mut out_units) = (None, None, None);
    let mut vs = 0usize;
    let mut metadata = Vec::new();
    let mut observations = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let n = i + 1;
        let line = raw.trim();
        let err = |msg: String| anyhow!("line {n}: {msg}");
        if line.is_empty() {
            continue;
        }
        if let Some(rest) = line.strip_prefix('#') {
            let mut words = rest.split_whitespace();
            match words.next() {
                Some("DIM") => {
                    let v: Vec<&str> = words.collect();
                    let parsed: Option<Vec<usize>> = v.iter().map(|w| w.parse().ok()).collect();
                    match parsed.as_deref() {
                        Some([i, 1]) => dim = Some(*i),
                        _ => return Err(err(format!("#DIM must be `#DIM <inputs> 1`, found `{line}`"))),
                    }
                }
                Some("PARAM_IN") => {
                    let w = words.next().unwrap_or("");
                    param_in = Some(ParamIn::parse(w).ok_or_else(|| {
                        err(format!(
                            "unsupported #PARAM_IN `{w}`; supported: ISOTROPIC_TL_TV_PROJ_DPHI, ISOTROPIC_TV_TL_DPHI, SPHERICAL_TL_PL_TV_PV"
                        ))
                    })?);
                }
                Some("PARAM_OUT") => {
                    let w = words.next().unwrap_or("");
                    out_units = Some(units(w).ok_or_else(|| {
                        err(format!(
                            "unsupported #PARAM_OUT `{w}`; supported: INV_STERADIAN, INV_STERADIAN_COSINE_FACTOR"
                        ))
                    })?);
                }
                Some("VS") => {
                    vs = match words.next() {
                        Some("0") => 0,
                        Some("1") => 1,
                        Some("2") => 2,
                        _ => return Err(err(format!("#VS must be 0, 1 or 2 (confidence columns per value), found `{line}`"))),
                    };
                }
                _ => metadata.push(rest.trim().to_string()),
            }
            continue;
        }
        let (Some(d), Some(p), Some(_)) = (dim, param_in, out_units) else {
            return Err(err("data before the header: #DIM, #PARAM_IN and #PARAM_OUT must come first".into()));
        };
        if d != p.dim() {
            return Err(err(format!("#DIM says {d} inputs but #PARAM_IN has {}", p.dim())));
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.len() != d + 1 + vs {
            return Err(err(format!(
                "expected {} numbers ({} inputs, 1 output, {vs} confidence), found {}",
                d + 1 + vs,
                d,
                fields.len()
            )));
        }
        let mut x = Vec::with_capacity(d + 1 + vs);
        for f in fields {
            let v: f64 = f.parse().map_err(|_| err(format!("`{f}` is not a number")))?;
            if !v.is_finite() {
                return Err(err(format!("`{f}` is not a finite number")));
            }
            x.push(v);
        }
        let (theta_i, theta_o, dphi) = p.angles(&x);
        let sigma = match vs {
            1 => Some(x[d + 1]),
            2 => Some((x[d + 2] - x[d + 1]) / (2.0 * K_COVERAGE)),
            _ => None,
        };
        if sigma.is_some_and(|s| s < 0.0) {
            return Err(err("the confidence interval is negative".into()));
        }
        observations.push(Observation {
            theta_i,
            theta_o,
            dphi,
            value: x[d],
            sigma,
            shared: Default::default(),
        });
    }
    let Some(units) = out_units else {
        bail!("missing header: no #PARAM_OUT line (an ALTA file starts with #DIM, #PARAM_IN, #PARAM_OUT)");
    };
    if dim.is_none() || param_in.is_none() {
        bail!("missing header: #DIM and #PARAM_IN are required");
    }
    if observations.is_empty() {
        bail!("no data lines: the file holds a header only");
    }
    Ok(Dataset {
        units,
        observations,
        metadata,
    })
}

/// Writes a data set as ALTA text in `ISOTROPIC_TL_TV_PROJ_DPHI`, in its own
/// units; metadata become `#` comment lines. Numbers are written in Rust's
/// shortest round-trip form, so reading back gives the same `f64`s. When
/// every value has an uncertainty, `#VS 2` with its k = 2 interval.
pub fn write(data: &Dataset) -> String {
    let intervals = !data.observations.is_empty() && data.observations.iter().all(|o| o.sigma.is_some());
    let mut s = String::new();
    let _ = writeln!(s, "#DIM 3 1");
    let _ = writeln!(s, "#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI");
    let _ = writeln!(s, "#PARAM_OUT {}", unit_name(data.units));
    let _ = writeln!(s, "#VS {}", if intervals { 2 } else { 0 });
    if intervals {
        let _ = writeln!(s, "# confidence: the value's k = {K_COVERAGE} interval [lower upper]");
    }
    for m in &data.metadata {
        let _ = writeln!(s, "# {m}");
    }
    for o in &data.observations {
        let _ = write!(
            s,
            "{:e} {:e} {:e} {:e}",
            o.theta_i,
            o.theta_o * o.dphi.cos(),
            o.theta_o * o.dphi.sin(),
            o.value
        );
        match o.sigma {
            Some(u) if intervals => {
                let _ = writeln!(s, " {:e} {:e}", o.value - K_COVERAGE * u, o.value + K_COVERAGE * u);
            }
            _ => s.push('\n'),
        }
    }
    s
}
