//! `gonio scan`: connect, home, scan, store, summarise.

use super::detector::DetectorArgs;
use super::grid::GridArgs;
use super::in_process;
use super::material::SimHeadArgs;
use super::output::{summarise, LiveArgs, OutputArgs};
use anyhow::{bail, Context, Result};
use gonio_acquire::interrupt;
use gonio_acquire::operator::Operator;
use gonio_acquire::scan::directory::{resume_from, scan_into, Destination};
use gonio_acquire::scan::page;
use gonio_scan_dir::record::{parse_geometry, Monitor, RecordedHead, ScanRecord, SAMPLE_MM};
use gonio_sim::faults::Faults;
use gonio_sim::SimConfig;
use std::path::PathBuf;

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
    let (spec, det) = (a.grid.scan_spec()?, &a.detector.checked()?);
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
    let target = in_process::target(&record.head, faults, a.sim_head.pace);
    let live = page::start(a.live.live_addr, a.live.live, operator).await?;
    let (outcome, samples) = scan_into(record, target, to, operator, &live, interrupt::requested()).await?;
    summarise(&record.spec, &outcome, &samples, a.output.json)
}

/// A sample size: positive and finite.
fn positive_mm(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a positive size in mm")),
    }
}
