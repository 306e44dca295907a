//! `gonio demo` and `gonio scan`: connect, home, scan, store, summarise.

use super::calibrate;
use super::detector::DetectorArgs;
use super::fit;
use super::fitting::{self, FitOptions};
use super::grid::{GridArgs, LobeArgs};
use super::live::LiveArgs;
use super::material::SimHeadArgs;
use super::{interrupt, simulated};
use anyhow::{bail, Context, Result};
use gonio_acquire::operator::Operator;
use gonio_acquire::scan::directory::{positions, resume_from, scan_into, Destination};
use gonio_acquire::scan::live::Live;
use gonio_acquire::scan::progress::hms;
use gonio_analysis::coefficients::Set;
use gonio_analysis::rounding::{figure, significant, with_uncertainty};
use gonio_scan_dir::record::{parse_geometry, Monitor, RecordedHead, ScanRecord};
use gonio_scan_dir::run::ScanOutcome;
use gonio_shared::{ScanSpec, SweepRequest, SweepScan};
use gonio_sim::faults::Faults;
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

/// How results are written.
#[derive(Debug, clap::Args)]
pub struct OutputArgs {
    /// Overwrite a scan already in the output directory.
    #[arg(long)]
    pub force: bool,
    /// Print the summary as one JSON object (errors too: `{"error", "kind"}`).
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
    /// detector settings, as its scan.json records them: options that would
    /// change them are refused; no point measured twice, none left out).
    #[arg(
        long,
        value_name = "DIR",
        conflicts_with_all = [
            "sim", "out", "force", "DetectorArgs", "SimHeadArgs", "monitor", "monitor_every", "reference_plate",
            // The grid's (a group of its own would not hold its flattened parts).
            "theta_i", "theta_o", "dphi", "sweep", "sweep_speed", "sweep_periods", "sweep_lobe", "sweep_lobe_from",
            "sweep_extent", "retro_rings", "retro_azimuths", "mirror_rings", "mirror_azimuths", "no_patterns",
            "for_sets", "sample_size_mm",
        ]
    )]
    pub resume: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Laser-drift monitor geometry θi,θo,Δφ (degrees), measured before, during
    /// and after the scan; `gonio calibrate` corrects the drift with it.
    #[arg(long, value_name = "TI,TO,DPHI")]
    pub monitor: Option<String>,
    /// Scan positions between two monitor readings (each visit costs a move
    /// to the monitor and back and four readings, so not too few).
    #[arg(long, default_value_t = 500, requires = "monitor")]
    pub monitor_every: u32,
    /// Side of the square sample (mm): at grazing incidence the beam's
    /// footprint is 1/cosθi as long (46× at 88.76°), and an incidence whose
    /// footprint would overfill the sample is refused before anything
    /// moves. The simulated head's sample is this size.
    #[arg(long, value_name = "MM", default_value_t = SAMPLE_MM, value_parser = positive_mm)]
    pub sample_size_mm: f64,
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
    #[command(flatten)]
    pub live: LiveArgs,
}

/// The whole chain on the simulated head: the reference plate and the
/// Belcour grid in one session, calibration, every model fitted, and
/// `report.html` with the comparison table and the pictures.
pub async fn demo(a: DemoArgs) -> Result<()> {
    let sim = SimConfig {
        seed: a.seed,
        sample_mm: Some(SAMPLE_MM),
        ..SimConfig::default()
    };
    let truth = sim.material.clone();
    let mut belcour = ScanSpec::belcour_with_patterns();
    super::grid::measure_for(&mut belcour, &[Set::AstmE810, Set::En1436])?;
    let sweep = match a.sweep {
        true => Some(SweepScan {
            lobe: a.lobe.lobe(&belcour.theta_i_deg)?,
            ..DEMO_SWEEP
        }),
        false => None,
    };
    let spec = ScanSpec { sweep, ..belcour };
    let live = super::live::start(&a.live, Operator::for_json(a.output.json)).await?;
    let (outcome, samples) = demo_scan(sim, &spec, &a.out, &a.output, &live).await?;
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
    let domain = fitting::domain(&calibrated.csv, &options)?;
    let rational = fitting::RationalArgs::default().spec(options.param)?;
    let comparison = fit::compare(&domain, &options, Some(&rational))?;
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
                "reference plate ρ = {}: K = {} A·sr, splitter {} (± k = 1)",
                gonio_sim::PLATE_RHO,
                with_uncertainty(calibrated.cal.scale_a_sr, calibrated.cal.scale_a_sr * calibrated.cal.scale_rel_sd),
                with_uncertainty(calibrated.cal.splitter, calibrated.cal.splitter * calibrated.cal.splitter_rel_sd)
            ),
        ),
        ("data".to_string(), calibrated.csv.display().to_string()),
    ];
    if let Some(bound) = outcome.lower_bound_s {
        facts.push(("scan time".to_string(), against_bound(outcome.head_time_s, bound)));
    }
    let budget = gonio_analysis::calibration::budget_by_incidence(&calibrated.rows);
    let report = fit::report(
        &a.out,
        format!("gonio demo: {}", truth.describe()),
        facts,
        &domain,
        &comparison,
        &budget,
    )?;
    let rows = &comparison.rows;
    let best = rows
        .iter()
        .min_by(|x, y| x.fit.metrics().rmse.total_cmp(&y.fit.metrics().rmse))
        .context("no model fitted")?;
    if json {
        let mut v = serde_json::to_value(&outcome)?;
        v["calibration"] = calibrated.summary;
        v["models"] = rows.iter().map(|r| r.json.clone()).collect();
        v["material"] = truth.describe().into();
        v["unfitted"] = serde_json::json!(comparison.unfitted);
        v["best_model"] = best.fit.name().into();
        v["coefficients"] = super::coefficients::to_json(
            &fit::coefficients(&domain, rows)?,
            Some(gonio_analysis::instrument::Instrument::ThisHead),
        );
        v["report"] = report.display().to_string().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("material: {}", truth.describe());
        println!(
            "calibrated: {} of {} samples usable; best model {} (RMSE {} sr⁻¹, NCC {})",
            calibrated.usable,
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
        simulated::target(&record.head, sim.faults, sim.pace),
        to,
        Operator::for_json(output.json),
        live,
        interrupt::requested(),
    )
    .await
}

pub async fn scan(a: ScanArgs) -> Result<()> {
    if let Some(dir) = &a.resume {
        let mut record = ScanRecord::read(dir)?;
        if let Some(p) = &a.port {
            // The head may come back on another port.
            record.head = RecordedHead::Port { path: p.clone() };
        }
        let to = Destination {
            dir,
            resume: Some(resume_from(dir, &record.spec)?),
            force: false,
        };
        // A resume runs on the repaired head: no faults.
        return scan_and_summarise(&record, Faults::default(), to, &a).await;
    }
    let (spec, det) = (a.grid.spec()?, &a.detector.checked()?);
    let (mut record, faults) = match (&a.port, a.sim) {
        (Some(_), _) if a.sim_head.inject.is_some() => bail!("--inject acts on the simulated head only (--sim), not on a head at a port"),
        (Some(p), _) => (ScanRecord::at_port(p, &spec, det), Faults::default()),
        (None, true) => {
            let c = SimConfig {
                sample_mm: Some(a.sample_size_mm),
                ..a.sim_head.config()?
            };
            (ScanRecord::simulated(&c, &spec, det), c.faults)
        }
        (None, false) => bail!("one of --sim or --port is required"),
    };
    if let Some(m) = &a.monitor {
        if a.monitor_every == 0 {
            bail!("--monitor-every must be at least 1");
        }
        record.monitor = Some(Monitor {
            at: parse_geometry(m).context("--monitor")?,
            every: a.monitor_every,
        });
    }
    record.reference_plate = a.reference_plate;
    record.sample_size_mm = Some(a.sample_size_mm);
    let out = a.out.clone().context("--out is required")?;
    let to = Destination {
        dir: &out,
        resume: None,
        force: a.output.force,
    };
    scan_and_summarise(&record, faults, to, &a).await
}

/// Runs `record` (its head with `faults` if simulated) into `to`, its live
/// view served, stoppable with Ctrl-C, and prints the summary.
async fn scan_and_summarise(record: &ScanRecord, faults: Faults, to: Destination<'_>, a: &ScanArgs) -> Result<()> {
    let operator = Operator::for_json(a.output.json);
    let target = simulated::target(&record.head, faults, a.sim_head.pace);
    let live = super::live::start(&a.live, operator).await?;
    let (outcome, samples) = scan_into(record, target, to, operator, &live, interrupt::requested()).await?;
    summarise(&record.spec, &outcome, &samples, a.output.json)
}

/// The sample a scan assumes unless told (mm): a 100 mm square holds the
/// 1 mm beam's footprint at EN 1436's 88.76° (46 mm long at 1/e²) with
/// all but 0.1 % of its light.
pub const SAMPLE_MM: f64 = 100.0;

/// A sample size: positive and finite.
fn positive_mm(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a positive size in mm")),
    }
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
