//! ALTA's text data format, read as ALTA reads it (`belcour/alta`,
//! `data_storage.cpp` `load_data_from_text` and `args.h` `parse_header`) and
//! a little more tolerantly: a header of `#KEY value` lines (`#DIM in out`,
//! `#PARAM_IN`, `#PARAM_OUT`, `#VS`; `# ...` and unknown keys are comments,
//! kept as metadata), then one sample per line: the inputs, the outputs, and
//! `#VS` confidence numbers for the first output. Where ALTA assumes, so do
//! we, and say so: a missing `#PARAM_OUT` is ALTA's `UNKNOWN_OUTPUT`, read as
//! `f_r` unless the user says otherwise (`Dataset::units_stated` false; the
//! commands' `--units`); a missing `#DIM` is taken from `#PARAM_IN` with one
//! output, with a warning.
//! Accepted beyond ALTA: CRLF line ends and trailing blanks (ALTA reads them
//! into the parametrization's name and no longer recognises it), blank
//! lines in the header, comment lines anywhere. Refused, naming the line and
//! what was expected: unknown input parametrizations, rows with the wrong
//! count of numbers, non-finite numbers, header keys after the data.
//!
//! Input parametrizations (radians; ALTA's `params.cpp`; the view comes
//! first in ALTA's 6-vectors): `ISOTROPIC_TL_TV_PROJ_DPHI` (θL, θV·cosΔφ,
//! θV·sinΔφ; the form written), `ISOTROPIC_TV_TL_DPHI` (θV, θL, Δφ),
//! `ISOTROPIC_TV_PROJ_DPHI` (θV·cosΔφ, θV·sinΔφ; light along the normal),
//! `SPHERICAL_TL_PL_TV_PV` (θL, φL, θV, φV), `RUSIN_TH_TD_PD` (θh, θd, φd),
//! `RUSIN_TH_PH_TD_PD` (θh, φh, θd, φd), `RUSIN_TH_TD` (θh, θd; φd = π/2),
//! `CARTESIAN` (Vx, Vy, Vz, Lx, Ly, Lz). Outputs: `INV_STERADIAN` (`f_r`),
//! `INV_STERADIAN_COSINE_FACTOR` (`f_r·cosθo`); others (`ENERGY`,
//! `RGB_COLOR`, `XYZ_COLOR`, `UNKNOWN_OUTPUT`) are read as `f_r` with a
//! warning, the first channel of several. Confidence: `#VS 1` one more
//! number, the half-width of the first value's interval; `#VS 2` two, how
//! far its interval reaches below and above the value (ALTA reads them as
//! `[y − a, y + b]`, `read_confidence_interval`, since its 2017 fix of
//! that reader); both taken as k = 2 intervals, an asymmetric one as its
//! half-width (σ = (a + b)/4). Files gonio wrote before it
//! followed ALTA there held the interval's ends themselves: they carry
//! [`ENDS_NOTE`], and are read as they were written. The writer uses `#VS 2`
//! when every value has an uncertainty.

use super::guard::{self, MAX_ROWS};
use crate::fit::data::check_angles;
use crate::fit::{Dataset, Observation, Units};
use crate::instrument::Instrument;
use crate::uncertainty::K_COVERAGE;
use anyhow::{anyhow, bail, Context, Result};
use gonio_brdf::frame::dot;
use gonio_brdf::Directions;
use std::fmt::Write;
use std::io::BufRead;

/// The note gonio's writer put in files whose `#VS 2` columns are the
/// interval's lower and upper ends, not ALTA's distances to them.
pub const ENDS_NOTE: &str = "confidence: the value's k = 2 interval [lower upper]";
/// The note of `#VS 2` columns as ALTA reads them.
const OFFSETS_NOTE: &str = "confidence: how far the value's k = 2 interval reaches [below above]";

#[derive(Debug, Clone, Copy, PartialEq)]
enum ParamIn {
    TlTvProjDphi,
    TvTlDphi,
    TvProjDphi,
    SphericalTlPlTvPv,
    RusinThTdPd,
    RusinThPhTdPd,
    RusinThTd,
    Cartesian,
}

const SUPPORTED: &str = "ISOTROPIC_TL_TV_PROJ_DPHI, ISOTROPIC_TV_TL_DPHI, ISOTROPIC_TV_PROJ_DPHI, SPHERICAL_TL_PL_TV_PV, \
                         RUSIN_TH_TD_PD, RUSIN_TH_PH_TD_PD, RUSIN_TH_TD, CARTESIAN";

type Vec3 = [f64; 3];

fn sph(theta: f64, phi: f64) -> Vec3 {
    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
}

/// The view of a projected `(θ·cosφ, θ·sinφ)` pair (ALTA: `(0,0,1)` at θ = 0).
fn projected(x: f64, y: f64) -> Vec3 {
    let theta = x.hypot(y);
    if theta == 0.0 {
        [0.0, 0.0, 1.0]
    } else {
        [x / theta * theta.sin(), y / theta * theta.sin(), theta.cos()]
    }
}

/// ALTA's `half_to_cartesian`: `V = Rz(φh)·Ry(θh)·d`, `L = 2(V·h)h − V`.
fn rusin(th: f64, ph: f64, td: f64, pd: f64) -> (Vec3, Vec3) {
    let h = sph(th, ph);
    let d = sph(td, pd);
    let (c, s) = (th.cos(), th.sin());
    let r = [c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]];
    let (c, s) = (ph.cos(), ph.sin());
    let v = [c * r[0] - s * r[1], s * r[0] + c * r[1], r[2]];
    let vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
    let l = [0, 1, 2].map(|i| 2.0 * vh * h[i] - v[i]);
    (l, v)
}

impl ParamIn {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "ISOTROPIC_TL_TV_PROJ_DPHI" => Self::TlTvProjDphi,
            "ISOTROPIC_TV_TL_DPHI" => Self::TvTlDphi,
            "ISOTROPIC_TV_PROJ_DPHI" => Self::TvProjDphi,
            "SPHERICAL_TL_PL_TV_PV" => Self::SphericalTlPlTvPv,
            "RUSIN_TH_TD_PD" => Self::RusinThTdPd,
            "RUSIN_TH_PH_TD_PD" => Self::RusinThPhTdPd,
            "RUSIN_TH_TD" => Self::RusinThTd,
            "CARTESIAN" => Self::Cartesian,
            _ => return None,
        })
    }

    fn dim(self) -> usize {
        match self {
            Self::TvProjDphi | Self::RusinThTd => 2,
            Self::TlTvProjDphi | Self::TvTlDphi | Self::RusinThTdPd => 3,
            Self::SphericalTlPlTvPv | Self::RusinThPhTdPd => 4,
            Self::Cartesian => 6,
        }
    }

    /// Light and view (unit vectors, sample frame) of one row's inputs.
    fn directions(self, x: &[f64]) -> (Vec3, Vec3) {
        match self {
            Self::TlTvProjDphi => (sph(x[0], 0.0), projected(x[1], x[2])),
            Self::TvTlDphi => (sph(x[1], 0.0), sph(x[0], x[2])),
            Self::TvProjDphi => ([0.0, 0.0, 1.0], projected(x[0], x[1])),
            Self::SphericalTlPlTvPv => (sph(x[0], x[1]), sph(x[2], x[3])),
            Self::RusinThTdPd => rusin(x[0], 0.0, x[1], x[2]),
            Self::RusinThPhTdPd => rusin(x[0], x[1], x[2], x[3]),
            Self::RusinThTd => rusin(x[0], 0.0, x[1], std::f64::consts::FRAC_PI_2),
            Self::Cartesian => ([x[3], x[4], x[5]], [x[0], x[1], x[2]]),
        }
    }
}

/// `(θi, θo, Δφ)` (radians) of a light and a view; `None` for a zero vector.
fn angles(l: Vec3, v: Vec3) -> Option<(f64, f64, f64)> {
    (dot(l, l) > 0.0 && dot(v, v) > 0.0).then(|| Directions { l, v }.angles())
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

/// What the header said so far.
#[derive(Default)]
struct Header {
    dim: Option<(usize, usize)>,
    param_in: Option<ParamIn>,
    /// `Some(None)`: a `#PARAM_OUT` we do not know the units of.
    param_out: Option<Option<Units>>,
    vs: usize,
}

/// How the data lines read, settled at the first of them.
#[derive(Clone, Copy)]
struct Layout {
    param_in: ParamIn,
    outputs: usize,
    units: Option<Units>,
    /// Confidence numbers per row (`#VS`).
    vs: usize,
    /// `#VS 2` holds the interval's ends, as gonio's older files (`ENDS_NOTE`).
    ends: bool,
}

/// A header line's keyword, or `None` for a comment (kept as metadata).
fn keyword(rest: &str) -> Option<(&str, &str)> {
    let key = rest.split_whitespace().next().unwrap_or("");
    let value = rest.trim_start().strip_prefix(key).unwrap_or("").trim();
    (!rest.starts_with(char::is_whitespace) && matches!(key, "DIM" | "PARAM_IN" | "PARAM_OUT" | "VS")).then_some((key, value))
}

impl Header {
    /// Takes `#KEY value` of `line`; what it doubts goes to `warnings`.
    fn take(&mut self, key: &str, value: &str, line: &str, warnings: &mut Vec<String>, n: usize) -> Result<(), String> {
        match key {
            "DIM" => {
                let parsed: Option<Vec<usize>> = value.split_whitespace().map(|w| w.parse().ok()).collect();
                match parsed.as_deref() {
                    Some([i, o]) if *i > 0 && *o > 0 => self.dim = Some((*i, *o)),
                    _ => return Err(format!("expected `#DIM <inputs> <outputs>`, found `{line}`")),
                }
            }
            "PARAM_IN" => {
                self.param_in =
                    Some(ParamIn::parse(value).ok_or_else(|| format!("unsupported #PARAM_IN `{value}`; supported: {SUPPORTED}"))?);
            }
            "PARAM_OUT" => {
                let u = units(value);
                if u.is_none() {
                    warnings.push(format!(
                        "line {n}: #PARAM_OUT {value} is not a unit of the BRDF (ALTA's UNKNOWN_OUTPUT)"
                    ));
                }
                self.param_out = Some(u);
            }
            _ => {
                self.vs = match value {
                    "0" => 0,
                    "1" => 1,
                    "2" => 2,
                    _ => {
                        return Err(format!(
                            "expected `#VS 0`, `#VS 1` or `#VS 2` (confidence numbers per row), found `{line}`"
                        ))
                    }
                };
            }
        }
        Ok(())
    }

    /// The layout of the data lines, once the header is over.
    fn layout(&self, metadata: &[String], warnings: &mut Vec<String>) -> Result<Layout, String> {
        let p = self
            .param_in
            .ok_or_else(|| format!("data before any #PARAM_IN: which parametrization are the inputs in? ({SUPPORTED})"))?;
        let (d_in, outputs) = match self.dim {
            Some(d) => d,
            None => {
                warnings.push(format!("no #DIM line: assumed `#DIM {} 1` from #PARAM_IN", p.dim()));
                (p.dim(), 1)
            }
        };
        if d_in != p.dim() {
            return Err(format!("#DIM says {d_in} inputs but #PARAM_IN has {}", p.dim()));
        }
        if outputs > 1 {
            warnings.push(format!("{outputs} outputs per sample: the first is used"));
        }
        Ok(Layout {
            param_in: p,
            outputs,
            // No #PARAM_OUT: ALTA's UNKNOWN_OUTPUT (`units_stated` false).
            units: self.param_out.flatten(),
            vs: self.vs,
            ends: metadata.iter().any(|m| m == ENDS_NOTE),
        })
    }
}

impl Layout {
    /// One data line as a sample: its geometry, its value (the first
    /// output), and its σ from the confidence numbers.
    fn row(&self, line: &str) -> Result<Observation, String> {
        let (d, outputs) = (self.param_in.dim(), self.outputs);
        let fields: Vec<&str> = line.split_whitespace().collect();
        let want = d + outputs + self.vs;
        if fields.len() != want {
            return Err(format!(
                "expected {want} numbers ({d} inputs, {outputs} output{}, {} confidence), found {}",
                if outputs == 1 { "" } else { "s" },
                self.vs,
                fields.len()
            ));
        }
        let mut x = Vec::with_capacity(want);
        for f in fields {
            let v: f64 = f.parse().map_err(|_| format!("`{f}` is not a number"))?;
            if !v.is_finite() {
                return Err(format!("`{f}` is not a finite number"));
            }
            x.push(v);
        }
        let (l, v) = self.param_in.directions(&x);
        let (theta_i, theta_o, dphi) = angles(l, v).ok_or_else(|| "a direction of length zero".to_string())?;
        let (theta_i, theta_o, dphi) = check_angles(theta_i, theta_o, dphi)?;
        Ok(Observation {
            theta_i,
            theta_o,
            dphi,
            value: x[d],
            sigma: self.sigma(&x[d + outputs..])?,
            shared: Default::default(),
        })
    }

    /// σ of a row's confidence numbers (`#VS 1`: the k = 2 half-width; `#VS
    /// 2`: how far below and above, or the ends in gonio's older files).
    fn sigma(&self, conf: &[f64]) -> Result<Option<f64>, String> {
        let sigma = match self.vs {
            1 if conf[0] < 0.0 => return Err("the confidence half-width is negative".into()),
            1 => Some(conf[0] / K_COVERAGE),
            2 if self.ends && conf[1] < conf[0] => {
                return Err("the confidence interval is negative (#VS 2 of gonio's older files: lower end, then upper end)".into())
            }
            2 if self.ends => Some((conf[1] - conf[0]) / (2.0 * K_COVERAGE)),
            2 if conf[0] < 0.0 || conf[1] < 0.0 => {
                return Err("a confidence offset is negative (#VS 2: how far the interval reaches below, then above the value)".into())
            }
            2 => Some((conf[0] + conf[1]) / (2.0 * K_COVERAGE)),
            _ => None,
        };
        // The writer puts k·σ below and above; their sum must be a number too.
        if sigma.is_some_and(|s| !(2.0 * K_COVERAGE * s).is_finite()) {
            return Err("the confidence interval is wider than a number holds".into());
        }
        Ok(sigma)
    }
}

/// Parses ALTA text held in memory.
pub fn parse(text: &str) -> Result<Dataset> {
    read(text.as_bytes())
}

/// Reads an ALTA text file as it streams; errors name the line (1-based)
/// and what was expected; what was assumed is in the data set's warnings.
pub fn read(input: impl BufRead) -> Result<Dataset> {
    let mut h = Header::default();
    let (mut metadata, mut warnings, mut observations) = (Vec::new(), Vec::new(), Vec::new());
    let mut layout: Option<Layout> = None;
    for (i, raw) in input.lines().enumerate() {
        let n = i + 1;
        let raw = raw.map_err(|e| guard::line_error(e, n))?;
        let line = raw.trim();
        let err = |msg: String| anyhow!("line {n}: {msg}");
        if line.is_empty() {
            continue;
        }
        if let Some(rest) = line.strip_prefix('#') {
            match keyword(rest) {
                None if !rest.trim().is_empty() => metadata.push(rest.trim().to_string()),
                None => {}
                Some((key, _)) if layout.is_some() => {
                    return Err(err(format!(
                        "#{key} after the data: header lines must come before the first sample"
                    )))
                }
                Some((key, value)) => h.take(key, value, line, &mut warnings, n).map_err(err)?,
            }
            continue;
        }
        let l = match layout {
            Some(l) => l,
            None => *layout.insert(h.layout(&metadata, &mut warnings).map_err(err)?),
        };
        if observations.len() == MAX_ROWS {
            return Err(guard::too_many_rows());
        }
        observations.push(l.row(line).map_err(err)?);
    }
    let Some(Layout { units, .. }) = layout else {
        bail!("no data lines: the file holds no sample (a header at most)");
    };
    // A file says what measured it in a comment line of its own
    // (`instrument::HEADER`), as `gonio convert` writes; else nobody knows.
    let mut instrument = Instrument::Unknown;
    for m in &metadata {
        if let Some(stated) = Instrument::from_header(m) {
            instrument = stated.with_context(|| format!("the header's `# {m}`"))?;
        }
    }
    Ok(Dataset {
        units: units.unwrap_or(Units::Fr),
        units_stated: units.is_some(),
        observations,
        metadata,
        warnings,
        instrument,
    })
}

/// Writes a data set as ALTA text in `ISOTROPIC_TL_TV_PROJ_DPHI`, in its own
/// units; metadata become `#` comment lines. Numbers are written in Rust's
/// shortest round-trip form, so reading back gives the same `f64`s. When
/// every value has an uncertainty, `#VS 2` with its k = 2 interval, as far
/// below and above the value as ALTA reads it.
pub fn write(data: &Dataset) -> String {
    let intervals = !data.observations.is_empty() && data.observations.iter().all(|o| o.sigma.is_some());
    let mut s = String::new();
    let _ = writeln!(s, "#DIM 3 1");
    let _ = writeln!(s, "#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI");
    let _ = writeln!(s, "#PARAM_OUT {}", unit_name(data.units));
    let _ = writeln!(s, "#VS {}", if intervals { 2 } else { 0 });
    if intervals {
        let _ = writeln!(s, "# {OFFSETS_NOTE}");
    }
    // A note of the columns read back is the writer's to write, above, for
    // the columns it writes: not kept twice, and an older file's never.
    if let Some(line) = data.instrument.header_text() {
        let _ = writeln!(s, "# {line}");
    }
    for m in data
        .metadata
        .iter()
        .filter(|m| *m != OFFSETS_NOTE && *m != ENDS_NOTE && Instrument::from_header(m).is_none())
    {
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
                let _ = writeln!(s, " {:e} {:e}", K_COVERAGE * u, K_COVERAGE * u);
            }
            _ => s.push('\n'),
        }
    }
    s
}
