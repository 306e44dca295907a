//! `gonio demo` and `gonio scan`: connect, home, scan, store, summarise.

use super::calibrate;
use super::detector::DetectorArgs;
use super::fit::{self, FitOptions};
use super::grid::{GridArgs, LobeArgs};
use super::material::SimHeadArgs;
use super::plan::{PlanTarget, ScanPlan};
use super::reference;
use crate::operator::Operator;
use crate::run_record::RunRecord;
use crate::samples_csv::{drop_last_position, stored_rows, SampleWriter};
use crate::scan::{self, Monitor, ScanOutcome};
use crate::scan_dir::ScanDir;
use crate::scan_order::{dwell_s, lower_bound, scan_time, sweep_time, visit_order};
use crate::session::{Session, Setup};
use anyhow::{bail, Context, Result};
use gonio_firmware::config::HeadConfig;
use gonio_firmware::motion::PARK;
use gonio_shared::{DetectionReport, ScanSpec, SweepRequest, SweepScan};
use gonio_sim::SimConfig;

/// Length of the detector calibration (s).
const CALIBRATION_S: f32 = 1.0;
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
}

/// How results are written.
#[derive(Debug, clap::Args)]
pub struct OutputArgs {
    /// Overwrite a scan already in the output directory.
    #[arg(long)]
    pub force: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("head").args(["sim", "port"])))]
#[command(group(clap::ArgGroup::new("dest").required(true).args(["out", "resume"])))]
pub struct ScanArgs {
    /// Scan the simulated head (in this process).
    #[arg(long)]
    pub sim: bool,
    /// Serial port of a head (its USB port, or a `gonio sim` pseudo-terminal).
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Output directory of a new scan.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Finish the interrupted scan in this directory (same grid, head and
    /// detector settings; no point measured twice, none left out).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["sim", "out", "force"])]
    pub resume: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Laser-drift monitor geometry θi,θo,Δφ (degrees), measured before, during
    /// and after the scan; `gonio calibrate` corrects the drift with it.
    #[arg(long, value_name = "TI,TO,DPHI")]
    pub monitor: Option<String>,
    /// Scan positions between two monitor readings (each pause has the head
    /// replay its plan to continue, so not too few).
    #[arg(long, default_value_t = 500, requires = "monitor")]
    pub monitor_every: u32,
    /// Measure the Lambertian reference plate first (written to
    /// reference.csv), then the sample: the operator is asked to swap them
    /// (the simulated head swaps them itself). For `gonio calibrate`.
    #[arg(long)]
    pub reference_plate: bool,
    #[command(flatten)]
    pub detector: DetectorArgs,
    #[command(flatten)]
    pub sim_head: SimHeadArgs,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The whole chain on the simulated head: the reference plate and the
/// Belcour grid in one session, calibration, every model fitted, and
/// `report.html` with the comparison table and the pictures.
pub async fn demo(a: DemoArgs) -> Result<()> {
    let sim = SimConfig {
        seed: a.seed,
        ..SimConfig::default()
    };
    let truth = sim.material.clone();
    let belcour = ScanSpec::belcour_with_patterns();
    let sweep = match a.sweep {
        true => Some(SweepScan {
            lobe: a.lobe.lobe(&belcour.theta_i_deg)?,
            ..DEMO_SWEEP
        }),
        false => None,
    };
    let spec = ScanSpec { sweep, ..belcour };
    let (outcome, samples) = demo_scan(sim, &spec, &a.out, &a.output).await?;
    let retro = spec.retro_points();
    let json = a.output.json;
    if !json {
        summarise(&spec, &outcome, &samples, false)?;
    }
    let calibrated = calibrate::calibrate(&calibrate::CalibrateArgs::for_scan(a.out.clone(), json))?;
    let options = FitOptions {
        json,
        ..FitOptions::default()
    };
    let domain = fit::domain(&calibrated.csv, &options)?;
    let rows = fit::compare(&domain, &options)?;
    let mut facts = vec![
        ("head".to_string(), "simulated (gonio demo)".to_string()),
        ("virtual material".to_string(), truth.describe()),
        (
            "scan".to_string(),
            if a.sweep {
                format!(
                    "{} rows of the Belcour grid swept, {} retro points and {} pattern points measured at rest: {} of them measured ({} swept samples), {} refused, {} flagged",
                    spec.rows(),
                    retro,
                    spec.pattern_points(),
                    outcome.measured,
                    outcome.swept_samples,
                    outcome.skipped,
                    outcome.flagged
                )
            } else {
                format!(
                    "{} points of the Belcour grid: {} measured, {} unreachable, {} flagged",
                    outcome.points, outcome.measured, outcome.skipped, outcome.flagged
                )
            },
        ),
        (
            "calibration".to_string(),
            format!(
                "reference plate ρ = {}: K = {:.5e} A·sr (±{:.3} %), splitter {:.4}",
                gonio_sim::PLATE_RHO,
                calibrated.cal.scale_a_sr,
                100.0 * calibrated.cal.scale_rel_sd,
                calibrated.cal.splitter
            ),
        ),
        ("data".to_string(), calibrated.csv.display().to_string()),
    ];
    if let Some(bound) = outcome.lower_bound_s {
        facts.push(("scan time".to_string(), against_bound(outcome.head_time_s, bound)));
    }
    let budget = crate::calibration::budget_by_incidence(&calibrated.rows);
    let report = fit::report(&a.out, format!("gonio demo: {}", truth.describe()), facts, &domain, &rows, &budget)?;
    let best = rows
        .iter()
        .min_by(|x, y| x.fit.metrics.rmse.total_cmp(&y.fit.metrics.rmse))
        .context("no model fitted")?;
    if json {
        let mut v = serde_json::to_value(&outcome)?;
        v["calibration"] = calibrated.summary;
        v["models"] = rows.iter().map(|r| r.json.clone()).collect();
        v["material"] = truth.describe().into();
        v["best_model"] = best.fit.material.model.name().into();
        v["report"] = report.display().to_string().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("material: {}", truth.describe());
        println!(
            "calibrated: {} of {} samples usable; best model {} (RMSE {:.3e} sr⁻¹, NCC {:.4})",
            calibrated.usable,
            calibrated.rows.len(),
            best.fit.material.model.name(),
            best.fit.metrics.rmse,
            best.fit.metrics.ncc
        );
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
pub async fn demo_scan(sim: SimConfig, spec: &ScanSpec, dir: &Path, output: &OutputArgs) -> Result<(ScanOutcome, PathBuf)> {
    let mut plan = ScanPlan::simulated(&sim, spec, &DetectorArgs::demo().checked()?);
    plan.reference_plate = true;
    scan_to_dir(&plan, dir, output, None).await
}

pub async fn scan(a: ScanArgs) -> Result<()> {
    if let Some(dir) = &a.resume {
        let mut plan = ScanPlan::read(dir)?;
        if let Some(p) = &a.port {
            // The head may come back on another port.
            plan.target = PlanTarget::Port { path: p.clone() };
        }
        let first = resume_from(dir, &plan.spec)?;
        let (outcome, samples) = scan_to_dir(&plan, dir, &a.output, Some(first)).await?;
        return summarise(&plan.spec, &outcome, &samples, a.output.json);
    }
    let (spec, det) = (a.grid.spec()?, &a.detector.checked()?);
    let mut plan = match (&a.port, a.sim) {
        (Some(_), _) if a.sim_head.inject.is_some() => bail!("--inject acts on the simulated head only (--sim), not on a head at a port"),
        (Some(p), _) => ScanPlan::at_port(p, &spec, det),
        (None, true) => ScanPlan::simulated(&a.sim_head.config()?, &spec, det),
        (None, false) => bail!("one of --sim or --port is required"),
    };
    if let Some(m) = &a.monitor {
        if a.monitor_every == 0 {
            bail!("--monitor-every must be at least 1");
        }
        plan.monitor = Some(Monitor {
            at: super::detector::parse_geometry(m).context("--monitor")?,
            every: a.monitor_every,
        });
    }
    plan.reference_plate = a.reference_plate;
    let out = a.out.context("--out is required")?;
    let (outcome, samples) = scan_to_dir(&plan, &out, &a.output, None).await?;
    summarise(&spec, &outcome, &samples, a.output.json)
}

/// The first visit position an interrupted scan of `spec` has not stored.
/// A sweep scan's last stored row may have been cut short while it was
/// written: it is swept again (and its stored samples dropped once the head
/// is found, [`scan_to_dir`]).
fn resume_from(dir: &Path, spec: &ScanSpec) -> Result<u32> {
    if ScanDir::new(dir).samples().exists() {
        bail!("{} holds a complete scan; nothing to resume", dir.display());
    }
    let last = stored_rows(dir)?.iter().filter_map(|r| r.order).max();
    Ok(match (last, spec.sweep) {
        (Some(o), Some(_)) => o,
        (Some(o), None) => o + 1,
        (None, _) => 0,
    })
}

/// Refuses to mix a new scan into a directory that holds one.
fn prepare_dir(dir: &Path, force: bool) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for p in ScanDir::new(dir).finished_files() {
        if p.exists() {
            if !force {
                let f = p.file_name().unwrap_or_default().to_string_lossy();
                bail!("{} already holds a scan ({f}); choose another --out or pass --force", dir.display());
            }
            std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
        }
    }
    Ok(())
}

/// Runs a plan into `dir`: a new scan, or the rest of one from visit position
/// `resume`. Connects first, so a head that cannot be reached leaves no files
/// behind. Returns the counts and the samples file.
async fn scan_to_dir(plan: &ScanPlan, dir: &Path, output: &OutputArgs, resume: Option<u32>) -> Result<(ScanOutcome, PathBuf)> {
    let json = output.json;
    let (target, det) = (plan.target(), &plan.detector);
    let spec = &ScanSpec {
        first_order: resume.unwrap_or(0),
        ..plan.spec.clone()
    };
    let (settings, calibrate_at) = (det.settings(), det.calibrate_at);
    let setup = Setup {
        settings,
        calibrate_at,
        calibration_periods: settings.periods_for(CALIBRATION_S),
    };
    let mut session = Session::connect(target.clone(), setup, Operator::for_json(json)).await?;
    let id = session.head().identity().clone();
    if !json {
        eprintln!(
            "head: {} (serial {}, firmware {}, protocol v{}{})",
            id.board,
            id.serial,
            id.firmware_version,
            id.protocol_version,
            if id.simulated { ", simulated" } else { "" }
        );
    }
    if resume.is_none() {
        prepare_dir(dir, output.force)?;
        plan.write(dir)?;
    }
    session.start().await?;
    let reconnected_before_scan = session.reconnections;
    let detection = session.detection.context("the head's detection settings")?;
    if plan.reference_plate && resume.is_none() {
        reference::measure_plate(session.head(), target.as_ref(), dir, Operator::for_json(json)).await?;
    }
    let config = *session.head().config();
    let estimate = estimate_s(&config, spec, &detection);
    if !json {
        if spec.sweep.is_some() {
            eprintln!(
                "{} rows to sweep, {} retro points and {} pattern points to measure at rest; estimated duration {} (moves to their starts, {:.0} ms settle, the sweeps)",
                spec.rows(),
                spec.retro_points(),
                spec.pattern_points(),
                hms(estimate),
                detection.settings.settle_s * 1e3,
            );
        } else {
            eprintln!(
                "{} points; estimated duration {} (moves, {:.0} ms settle and {:.0} ms integration per point)",
                spec.len(),
                hms(estimate),
                detection.settings.settle_s * 1e3,
                detection.integration_s * 1e3
            );
        }
    }
    let mut writer = match resume {
        Some(first) => {
            if !json {
                eprintln!("resuming at position {first} of {}", spec.len());
            }
            if spec.sweep.is_some() {
                // The row resuming sweeps again (`resume_from`).
                drop_last_position(dir)?;
            }
            SampleWriter::append(dir)?
        }
        None => SampleWriter::create(dir)?,
    };
    let pb = Operator::for_json(json).bar(spec.len() as u64, "scanning", positions(spec));
    let mut outcome = scan::run(&mut session, spec, &mut writer, &pb, plan.monitor.as_ref())
        .await
        .with_context(|| {
            format!(
                "scan interrupted; every sample so far is on disk: finish it with `gonio scan --resume {}`",
                dir.display()
            )
        })?;
    if reconnected_before_scan > 0 {
        outcome
            .recoveries
            .insert("link lost while preparing the head".into(), reconnected_before_scan);
    }
    let samples = writer.finish()?;
    if resume.is_none() && plan.monitor.is_none() {
        outcome.lower_bound_s = lower_bound_s(&config, spec, &detection);
    }
    if resume.is_some() {
        // Counts of the whole scan, not only of this session.
        let rows = crate::samples_csv::read(&samples)?;
        outcome.measured = rows.iter().filter_map(|r| r.order).collect::<std::collections::BTreeSet<_>>().len() as u32;
        outcome.swept_samples = rows.iter().filter(|r| r.extent_deg.is_some()).count() as u32;
        outcome.skipped = outcome.points - outcome.measured;
    }
    let mut record = RunRecord::new(&id, plan.material(), spec, &detection, session.calibration, outcome.clone());
    record.estimated_s = Some(estimate);
    record.write(dir)?;
    session.close().await;
    Ok((outcome, samples))
}

/// The plan replayed from the park position under the head's reported axis
/// limits, from the scan's first position on: moves, settle and acquisition,
/// or a sweep scan's moves, settling, ranging and sweeps (s).
fn estimate_s(cfg: &HeadConfig, spec: &ScanSpec, det: &DetectionReport) -> f64 {
    let (settle, acquire) = dwell_s(det);
    let rest = visit_order(cfg, spec, PARK).skip(spec.first_order as usize);
    if spec.sweep.is_some() {
        let ranging = acquire - det.integration_s as f64;
        return sweep_time(cfg, spec, rest, PARK, (settle, acquire, ranging), det.settings.chop_hz).total_s();
    }
    scan_time(cfg, spec, rest, PARK, settle, acquire).total_s()
}

/// The least head time any stop-and-go order of the whole scan could take
/// (s), for a sweep scan of its grid's points; `None` for a scan too large
/// to bound.
fn lower_bound_s(cfg: &HeadConfig, spec: &ScanSpec, det: &DetectionReport) -> Option<f64> {
    let (settle, acquire) = dwell_s(det);
    let grid = ScanSpec {
        sweep: None,
        ..spec.clone()
    };
    lower_bound(cfg, &grid, settle, acquire).map(|(t, _)| t.total_s())
}

/// Head time against the lower bound, in words.
fn against_bound(head_time_s: f64, bound_s: f64) -> String {
    format!(
        "{} of head time; no stop-and-go order of the grid's points takes less than {} (× {:.3})",
        hms(head_time_s),
        hms(bound_s),
        head_time_s / bound_s
    )
}

fn hms(s: f64) -> String {
    let s = s.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// What a scan's visit positions are called: a grid's points, or a sweep
/// scan's positions (rows and retro points).
fn positions(spec: &ScanSpec) -> &'static str {
    match spec.sweep {
        Some(_) => "positions",
        None => "points",
    }
}

fn summarise(spec: &ScanSpec, o: &ScanOutcome, samples: &Path, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(o)?);
        return Ok(());
    }
    println!(
        "{} {}: {} measured, {} unreachable, {} flagged; {:.0} s of head time in {:.1} s",
        o.points,
        positions(spec),
        o.measured,
        o.skipped,
        o.flagged,
        o.head_time_s,
        o.wall_time_s
    );
    if let Some(bound) = o.lower_bound_s {
        println!("  {}", against_bound(o.head_time_s, bound));
    }
    for (reason, n) in &o.skipped_by_reason {
        println!("  {n:5} × {reason}");
    }
    for (why, n) in &o.recoveries {
        println!("  recovered {n} × {why}");
    }
    if o.duplicates_dropped > 0 {
        println!("  {} duplicate events dropped", o.duplicates_dropped);
    }
    println!("samples: {}", samples.display());
    Ok(())
}
