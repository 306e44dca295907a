//! `gonio demo`: the whole chain on the simulated head, composed of the
//! libraries' steps: the reference plate and the Belcour grid scanned in
//! one session, the scan directory calibrated, every model and the
//! rational function compared, R_A and R_L, and `report.html`.

use super::detector::DetectorArgs;
use super::fit_args::{FitOptions, RationalArgs};
use super::fitting::compare;
use super::grid::LobeArgs;
use super::in_process;
use super::output::{summarise, LiveArgs, OutputArgs};
use anyhow::{Context, Result};
use gonio_acquire::interrupt;
use gonio_acquire::operator::Operator;
use gonio_acquire::scan::directory::{scan_into, Destination};
use gonio_acquire::scan::live::Live;
use gonio_analysis::calibration::directory::{calibrate, Request};
use gonio_analysis::coefficients::Set;
use gonio_analysis::rounding::{figure, significant};
use gonio_scan_dir::record::ScanRecord;
use gonio_scan_dir::run::ScanOutcome;
use gonio_shared::{ScanSpec, SweepRequest, SweepScan};
use gonio_sim::SimConfig;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "gonio-demo")]
    pub out: PathBuf,
    /// Seed of the simulated head's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sweep the Belcour grid's rows, measuring while moving (as fast as the
    /// axes allow, 8 chop periods per sample), instead of stopping at every
    /// point.
    #[arg(long)]
    pub sweep: bool,
    #[command(flatten)]
    pub lobe: LobeArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub live: LiveArgs,
}

/// The whole chain on the simulated head: the reference plate and the
/// Belcour grid in one session, calibration, every model fitted, and
/// `report.html` with the comparison table and the pictures.
pub async fn demo(a: DemoArgs) -> Result<()> {
    let sim = SimConfig {
        seed: a.seed,
        sample_mm: Some(gonio_scan_dir::record::SAMPLE_MM),
        ..SimConfig::default()
    };
    let truth = sim.material.clone();
    let mut belcour = ScanSpec::belcour_with_patterns();
    gonio_analysis::coefficients::scan::measure_for(&mut belcour, &[Set::AstmE810, Set::En1436])?;
    let sweep = match a.sweep {
        true => Some(SweepScan {
            lobe: a.lobe.lobe(&belcour.theta_i_deg)?,
            ..DEMO_SWEEP
        }),
        false => None,
    };
    let spec = ScanSpec { sweep, ..belcour };
    let live = gonio_acquire::scan::page::start(a.live.live_addr, a.live.live, Operator::for_json(a.output.json)).await?;
    let (outcome, samples) = demo_scan(sim, &spec, &a.out, &a.output, &live).await?;
    let json = a.output.json;
    if !json {
        summarise(&spec, &outcome, &samples, false)?;
    }
    let calibrated = calibrate(&Request::for_scan(a.out.clone(), gonio_sim::PLATE_RHO, gonio_sim::PLATE_RHO_U))?;
    let cal = &calibrated.summary.calibration;
    let options = FitOptions {
        json,
        ..FitOptions::default()
    };
    let domain = options.select(&calibrated.summary.file)?;
    let rational = RationalArgs::default().rational_spec(options.param)?;
    let comparison = compare(&domain, &options, Some(&rational))?;
    let mut facts = vec![
        ("head".to_string(), "simulated (gonio demo)".to_string()),
        ("virtual material".to_string(), truth.describe()),
        ("scan".to_string(), outcome.measured_text(&spec)),
        ("calibration".to_string(), cal.plate_text(gonio_sim::PLATE_RHO)),
        ("data".to_string(), calibrated.summary.file.display().to_string()),
    ];
    facts.extend(outcome.against_bound().map(|b| ("scan time".to_string(), b)));
    let report = comparison.report(
        &a.out,
        format!("gonio demo: {}", truth.describe()),
        facts,
        &domain,
        &calibrated.summary.budget,
    )?;
    let best = comparison.best().context("no model fitted")?;
    if json {
        let mut v = serde_json::to_value(&outcome)?;
        v["calibration"] = serde_json::to_value(&calibrated.summary)?;
        v["models"] = comparison.rows.iter().map(|r| r.json.clone()).collect();
        v["material"] = truth.describe().into();
        v["unfitted"] = serde_json::json!(comparison.unfitted);
        v["best_model"] = best.fit.name().into();
        v["coefficients"] = gonio_analysis::coefficients::json::to_json(
            &comparison.coefficients(&domain)?,
            Some(gonio_analysis::instrument::Instrument::ThisHead),
        );
        v["report"] = report.display().to_string().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("material: {}", truth.describe());
        println!(
            "calibrated: {} of {} samples usable; best model {} (RMSE {} sr⁻¹, NCC {})",
            calibrated.summary.usable,
            calibrated.rows.len(),
            best.fit.name(),
            significant(best.fit.metrics().rmse, 4),
            figure(best.fit.metrics().ncc, 4)
        );
        for why in &comparison.unfitted {
            println!("not fitted: {why}");
        }
        println!("report: {}", report.display());
    }
    Ok(())
}

/// How `gonio demo --sweep` sweeps: as fast as the axes allow (the arm's
/// 30 deg/s on the reference head), 8 chop periods per sample.
pub const DEMO_SWEEP: SweepScan = SweepScan {
    speed_dps: 30.0,
    periods_per_sample: SweepRequest::PERIODS_MAX,
    lobe: None,
};

/// The demo's scan of a simulated head into `dir`: the reference plate,
/// then `spec` (quiet with `output.json`). Returns the outcome and the
/// samples file.
pub async fn demo_scan(sim: SimConfig, spec: &ScanSpec, dir: &Path, output: &OutputArgs, live: &Live) -> Result<(ScanOutcome, PathBuf)> {
    let mut record = ScanRecord::simulated(&sim, spec, &DetectorArgs::demo().checked()?);
    record.reference_plate = true;
    record.sample_size_mm = sim.sample_mm;
    let to = Destination {
        dir,
        resume: None,
        force: output.force,
    };
    scan_into(
        &record,
        in_process::target(&record.head, sim.faults, sim.pace),
        to,
        Operator::for_json(output.json),
        live,
        interrupt::requested(),
    )
    .await
}
