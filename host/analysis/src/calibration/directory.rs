//! A scan directory calibrated: the reference plate's scale applied to the
//! sample's scan in two passes, `calibrated.csv` and `calibration.json`
//! written beside `samples.csv`.
//!
//! Two passes because the angle component of each value's budget is the
//! stage errors times the BRDF's local slope, and the slope is taken from
//! the calibrated values themselves: a first pass without it, a smooth
//! model fitted to that, a second pass with its slope.

use super::{budget_by_incidence, dataset, write_csv, Budget, CalibratedRow, Calibration, Drift, IncidenceBudget};
use crate::fit::{self, FitSpec};
use crate::uncertainty::HeadUncertainty;
use anyhow::{bail, Context, Result};
use gonio_brdf::{Material, ModelId, Param};
use gonio_scan_dir::samples::{self, Row};
use gonio_scan_dir::ScanDir;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Where the BRDF's slope (the angle component) comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum SlopeSource {
    /// A model fitted to the first pass (only its slope is used).
    Fitted(ModelId),
    /// A fit file's material.
    File(PathBuf),
    /// No angle component.
    None,
}

impl SlopeSource {
    /// From a fit file if given, else a model by id (`none`: no angle component).
    pub fn named(fit: Option<&Path>, model: &str) -> Result<SlopeSource> {
        Ok(match (fit, model) {
            (Some(path), _) => SlopeSource::File(path.to_path_buf()),
            (None, "none") => SlopeSource::None,
            (None, name) => SlopeSource::Fitted(ModelId::parse(name).context("--slope-model")?),
        })
    }
}

/// What a calibration is asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The sample's scan directory.
    pub scan: PathBuf,
    /// The plate's `reference.csv`, or the directory of a plate scan; the
    /// scan directory's own `reference.csv` where `None`.
    pub reference: Option<PathBuf>,
    /// The plate's hemispherical reflectance and its standard uncertainty.
    pub rho_ref: f64,
    pub u_rho_ref: f64,
    /// The splitter's factor, used where the plate run did not measure it.
    pub splitter: Option<f64>,
    pub slope: SlopeSource,
    pub head: HeadUncertainty,
}

impl Request {
    /// The command line's defaults for a scan directory and a plate of
    /// reflectance `rho_ref` ± `u_rho_ref`: the scan's own `reference.csv`,
    /// the splitter as the plate run measured it, retro-phong's slope, the
    /// reference head's uncertainties.
    pub fn for_scan(scan: PathBuf, rho_ref: f64, u_rho_ref: f64) -> Request {
        Request {
            scan,
            reference: None,
            rho_ref,
            u_rho_ref,
            splitter: None,
            slope: SlopeSource::Fitted(ModelId::RetroPhong),
            head: HeadUncertainty::default(),
        }
    }
}

/// The slope model as `calibration.json` names it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlopeModel {
    pub model: &'static str,
    pub params: String,
}

/// `calibration.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    pub calibration: Calibration,
    pub monitor_readings: usize,
    /// The sample run's laser power, lowest and highest, relative to the
    /// plate's; `None` without monitor readings.
    pub laser_power_range: Option<[f64; 2]>,
    pub samples: usize,
    pub usable: usize,
    pub head_uncertainty: HeadUncertainty,
    pub slope_model: Option<SlopeModel>,
    pub budget: Vec<IncidenceBudget>,
    /// `calibrated.csv`.
    pub file: PathBuf,
}

/// A calibrated scan.
pub struct Calibrated {
    pub drift: Drift,
    pub rows: Vec<CalibratedRow>,
    /// The model whose slope gave the angle component, if any.
    pub slope: Option<Material>,
    pub summary: Summary,
}

fn rows(dir: &Path) -> Result<Vec<Row>> {
    let p = ScanDir::new(dir).samples();
    if !p.exists() {
        bail!("{} holds no completed scan (no samples.csv)", dir.display());
    }
    samples::read(&p)
}

/// The plate's samples and its monitor readings: a plate scan's directory
/// splits into both, a `reference.csv` holds samples only.
fn plate(reference: &Path) -> Result<(Vec<Row>, Vec<Row>)> {
    if reference.is_dir() {
        let all = rows(reference).context("reading the reference plate's scan")?;
        return Ok(all.into_iter().partition(|r| r.index.is_some()));
    }
    if !reference.exists() {
        bail!(
            "no reference plate: {} is missing (scan with --reference-plate, or give --reference)",
            reference.display()
        );
    }
    Ok((samples::read(reference)?, Vec::new()))
}

fn slope_model(source: &SlopeSource, first: &[CalibratedRow]) -> Result<Option<Material>> {
    match source {
        SlopeSource::File(path) => fit::file::read_material(path).map(Some),
        SlopeSource::None => Ok(None),
        SlopeSource::Fitted(model) => {
            let spec = FitSpec {
                param: Param::View,
                ..FitSpec::new(*model)
            };
            let f = fit::fit(&dataset(first), &spec).with_context(|| format!("fitting {} for the BRDF's slope", model.name()))?;
            Ok(Some(f.material))
        }
    }
}

/// Calibrates a scan directory: writes `calibrated.csv` and
/// `calibration.json` into it.
pub fn calibrate(r: &Request) -> Result<Calibrated> {
    if !r.scan.is_dir() {
        bail!("{} is not a scan directory (no such directory)", r.scan.display());
    }
    let dir = ScanDir::new(&r.scan);
    let (plate, monitor) = plate(&r.reference.clone().unwrap_or_else(|| dir.reference()))?;
    let cal =
        Calibration::from_plate(&plate, &monitor, r.rho_ref, r.u_rho_ref, r.splitter).context("calibrating on the reference plate")?;
    let sample = rows(&r.scan).context("reading the sample's scan")?;
    let mut budget = Budget { head: r.head, slope: None };
    let (first, _) = cal.apply(&sample, &budget);
    budget.slope = slope_model(&r.slope, &first)?;
    let (calibrated, drift) = cal.apply(&sample, &budget);
    let csv = dir.calibrated();
    write_csv(&csv, &calibrated)?;
    let (lo, hi) = drift.range();
    let summary = Summary {
        calibration: cal,
        monitor_readings: drift.readings(),
        laser_power_range: (drift.readings() > 0).then_some([lo, hi]),
        samples: calibrated.len(),
        usable: calibrated.iter().filter(|r| r.usable).count(),
        head_uncertainty: budget.head,
        slope_model: budget.slope.as_ref().map(|m| SlopeModel {
            model: m.model.name(),
            params: m.params_string(),
        }),
        budget: budget_by_incidence(&calibrated),
        file: csv,
    };
    let path = dir.calibration();
    std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n").with_context(|| format!("writing {}", path.display()))?;
    Ok(Calibrated {
        drift,
        rows: calibrated,
        slope: budget.slope,
        summary,
    })
}
