//! A scan into a scan directory, new or resumed: connect, check what the
//! head is asked to reach, set the detector up, record the scan
//! (`scan.json`), measure the plate if asked, run it, and write its
//! `run.json`. Files are written only once the head answers and the scan is
//! known to be possible; Ctrl-C stops the head and says how to resume.

use super::drive;
use super::live::Live;
use super::progress::Progress;
use crate::operator::Operator;
use crate::plate;
use crate::scan_order::{dwell_s, lower_bound, time_left_s, visit_order};
use crate::session::{Session, Setup};
use crate::target::Target;
use anyhow::{bail, Context, Result};
use gonio_firmware::config::HeadConfig;
use gonio_firmware::footprint;
use gonio_firmware::kinematics;
use gonio_firmware::motion::PARK;
use gonio_scan_dir::record::ScanRecord;
use gonio_scan_dir::run::{hms, positions};
use gonio_scan_dir::run::{RunRecord, ScanOutcome};
use gonio_scan_dir::samples::{self, drop_last_position, stored_rows, SampleWriter};
use gonio_scan_dir::ScanDir;
use gonio_shared::icd::AbortEndpoint;
use gonio_shared::{DetectionReport, ScanSpec};
use std::collections::BTreeSet;
use std::future::Future;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Length of the detector's reference learning (s).
const LEARNING_S: f32 = 1.0;

/// Where a scan goes and how it starts.
pub struct Destination<'a> {
    pub dir: &'a Path,
    /// The first visit position to measure, for a resumed scan
    /// ([`resume_from`]); `None` for a new one.
    pub resume: Option<u32>,
    /// Overwrite a completed scan in `dir`.
    pub force: bool,
}

/// Runs `record` on the head at `target` into `to`, shown and steered on
/// `live`; `stop` resolving (the operator's Ctrl-C) or an abort asked on
/// `live` stops the head and ends the scan with [`Interrupted`]. Returns
/// the counts and the samples file.
pub async fn scan_into(
    record: &ScanRecord,
    target: Arc<dyn Target>,
    to: Destination<'_>,
    operator: Operator,
    live: &Live,
    stop: impl Future<Output = ()>,
) -> Result<(ScanOutcome, PathBuf)> {
    let (dir, resume) = (to.dir, to.resume);
    if resume.is_none() {
        refuse_finished(dir, to.force)?;
    }
    let spec = &ScanSpec {
        first_order: resume.unwrap_or(0),
        ..record.spec.clone()
    };
    let mut session = connect(record, target.clone(), operator).await?;
    if resume.is_none() {
        prepare_dir(dir, to.force)?;
        record.write(dir)?;
    }
    let _announced = live.announce(dir)?;
    session.start().await?;
    let reconnected_before_scan = session.reconnections;
    let detection = session.detection.context("the head's detection settings")?;
    if record.reference_plate && resume.is_none() {
        plate::measure_plate(session.head(), target.as_ref(), dir, operator).await?;
    }
    let config = *session.head().config();
    // The lower bound needs only the grid, and takes about a second for a
    // default scan (quadratic in its positions): worked out while the head
    // scans.
    let bound = (resume.is_none() && record.monitor.is_none()).then(|| {
        let spec = spec.clone();
        tokio::task::spawn_blocking(move || lower_bound_s(&config, &spec, &detection))
    });
    let order: Vec<u32> = visit_order(&config, spec, PARK).collect();
    let rest = order.iter().copied().skip(spec.first_order as usize);
    let progress = Progress::new(
        operator,
        time_left_s(&config, spec, rest, PARK, &detection),
        spec.first_order,
        positions(spec),
        live.clone(),
    );
    let estimate = progress.estimate_s();
    operator.notice(estimate_text(spec, estimate, &detection));
    let mut writer = writer(dir, resume, spec, operator)?;
    let ended = {
        let scanning = drive(&mut session, spec, order, &mut writer, &progress, record.monitor.as_ref());
        tokio::pin!(scanning);
        tokio::select! {
            r = &mut scanning => Some(r),
            () = stop => None,
            () = live.aborted() => None,
        }
    };
    let Some(ended) = ended else {
        return Err(interrupted(session, &progress, live, dir, record).await);
    };
    let mut outcome = ended.with_context(|| {
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
    match (resume, bound) {
        (None, Some(bound)) => outcome.lower_bound_s = bound.await.context("working out the scan's lower bound")?,
        (None, None) => {}
        (Some(_), _) => whole_scan_counts(&mut outcome, &samples)?,
    }
    let id = session.head().identity().clone();
    let mut run_record = RunRecord::new(&id, record.material(), spec, &detection, session.learned, outcome.clone());
    run_record.estimated_s = Some(estimate);
    run_record.write(dir)?;
    session.close().await;
    Ok((outcome, samples))
}

/// A session with the head `record` names, checked able to reach its
/// grid, and named to the operator.
async fn connect(record: &ScanRecord, target: Arc<dyn Target>, operator: Operator) -> Result<Session> {
    let settings = record.detector.settings();
    let setup = Setup {
        settings,
        learn_at: record.detector.learn_at,
        learning_periods: settings.periods_for(LEARNING_S),
    };
    let session = Session::connect(target, setup, operator).await?;
    reachable(session.head().config(), record)?;
    let id = session.head().identity();
    operator.notice(format_args!(
        "head: {} (serial {}, firmware {}, protocol v{}{})",
        id.board,
        id.serial,
        id.firmware_version,
        id.protocol_version,
        if id.simulated { ", simulated" } else { "" }
    ));
    Ok(session)
}

/// What the scan will measure and how long it should take, in words.
fn estimate_text(spec: &ScanSpec, estimate_s: f64, detection: &DetectionReport) -> String {
    let settle_ms = detection.settings.settle_s * 1e3;
    match spec.sweep {
        Some(_) => format!(
            "{} rows to sweep, {} retro points and {} pattern points to measure at rest; estimated duration {} (moves to their starts, {settle_ms:.0} ms settle, the sweeps)",
            spec.rows(),
            spec.retro_points(),
            spec.pattern_points(),
            hms(estimate_s),
        ),
        None => format!(
            "{} points; estimated duration {} (moves, {settle_ms:.0} ms settle and {:.0} ms integration per point)",
            spec.len(),
            hms(estimate_s),
            detection.integration_s * 1e3
        ),
    }
}

/// The samples file of a new scan, or the one a resumed scan appends to
/// (its last row swept again: [`resume_from`]).
fn writer(dir: &Path, resume: Option<u32>, spec: &ScanSpec, operator: Operator) -> Result<SampleWriter> {
    let Some(first) = resume else {
        return SampleWriter::create(dir);
    };
    operator.notice(format_args!("resuming at position {first} of {}", spec.len()));
    if spec.sweep.is_some() {
        drop_last_position(dir)?;
    }
    SampleWriter::append(dir)
}

/// The operator stopped the scan: the head made safe, and where to resume.
async fn interrupted(session: Session, progress: &Progress, live: &Live, dir: &Path, record: &ScanRecord) -> anyhow::Error {
    progress.finish();
    live.state("interrupted: stopped by the operator");
    // The scan is dropped between two events: every row on disk is whole.
    let safe = session.head().request::<AbortEndpoint>(&()).await.is_ok();
    session.close().await;
    match resume_from(dir, &record.spec) {
        Ok(at) => Interrupted {
            at,
            of: record.spec.len(),
            dir: dir.to_path_buf(),
            head_safe: safe,
        }
        .into(),
        Err(e) => e,
    }
}

/// A resumed scan's counts over the whole scan, not only this session's.
fn whole_scan_counts(outcome: &mut ScanOutcome, samples: &Path) -> Result<()> {
    let rows = samples::read(samples)?;
    outcome.measured = rows.iter().filter_map(|r| r.order).collect::<BTreeSet<_>>().len() as u32;
    outcome.swept_samples = rows.iter().filter(|r| r.extent_deg.is_some()).count() as u32;
    outcome.skipped = outcome.points - outcome.measured;
    // Why the earlier sessions skipped theirs is not on disk: said so, so
    // that the reasons add up to the count.
    let known: u32 = outcome.skipped_by_reason.values().sum();
    if outcome.skipped > known {
        *outcome
            .skipped_by_reason
            .entry("skipped before the resume (reason not recorded)".into())
            .or_default() += outcome.skipped - known;
    }
    Ok(())
}

/// The first visit position an interrupted scan of `spec` in `dir` has not
/// stored. A sweep scan's last stored row may have been cut short while it
/// was written: it is swept again (and its stored samples dropped once the
/// head is found, [`scan_into`]).
pub fn resume_from(dir: &Path, spec: &ScanSpec) -> Result<u32> {
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

/// Refuses to mix a new scan into a directory that holds one, before
/// anything is asked of the head.
fn refuse_finished(dir: &Path, force: bool) -> Result<()> {
    if let Some(p) = ScanDir::new(dir).finished_files().iter().find(|p| p.exists()) {
        if !force {
            let f = p.file_name().unwrap_or_default().to_string_lossy();
            bail!("{} already holds a scan ({f}); choose another --out or pass --force", dir.display());
        }
    }
    Ok(())
}

/// Makes `dir` ready for a new scan: created, a completed scan's files
/// removed (`--force`, checked by [`refuse_finished`]).
fn prepare_dir(dir: &Path, force: bool) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for p in ScanDir::new(dir).finished_files() {
        if p.exists() {
            refuse_finished(dir, force)?;
            std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
        }
    }
    Ok(())
}

/// Refuses a scan whose drift monitor or learning geometry this head
/// cannot reach (its mechanics, as it reported them), or whose beam
/// footprint would overfill the declared sample at one of its incidences,
/// before it moves.
fn reachable(cfg: &HeadConfig, record: &ScanRecord) -> Result<()> {
    if let Some(side) = record.sample_size_mm {
        let beam = cfg.optics.beam_diameter_mm as f64;
        // f32 as the scan holds them, and as the user wrote them.
        let lit = record.spec.theta_i_deg.iter().copied();
        let monitor = record.monitor.map(|m| m.at.theta_i_deg);
        let learning = record.detector.learn_at.map(|g| g.theta_i_deg);
        for t in lit.chain(monitor).chain(learning) {
            let lost = 1.0 - footprint::on_sample(t as f64, beam, side);
            if lost > footprint::LOST_MAX {
                bail!(
                    "θi {t}°: the {beam} mm beam's footprint, {:.0} mm long at this incidence, overfills the {side} mm sample \
                     ({:.1} % of the light would miss it); declare the sample's real size with --sample-size-mm, or keep \
                     to incidences up to {:.1}° on this one",
                    beam / (t as f64).to_radians().cos(),
                    100.0 * lost,
                    footprint::largest_incidence_deg(beam, side)
                );
            }
        }
    }
    let asked = [
        ("--monitor", record.monitor.map(|m| m.at)),
        ("--learn-at", record.detector.learn_at),
    ];
    for (option, at) in asked {
        let Some(g) = at else { continue };
        if let Err(f) = kinematics::inverse(cfg, &g) {
            bail!(
                "{option} {},{},{}: {f} on this head; choose a geometry it reaches",
                g.theta_i_deg,
                g.theta_o_deg,
                g.dphi_deg
            );
        }
    }
    Ok(())
}

/// A scan stopped by the operator (Ctrl-C): where, and whether the head
/// confirmed it is safe. The command line exits with 130 for it.
#[derive(Debug)]
pub struct Interrupted {
    /// The first visit position not stored.
    pub at: u32,
    pub of: u32,
    pub dir: PathBuf,
    /// The head answered the abort: laser off, drivers off.
    pub head_safe: bool,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let head = match self.head_safe {
            true => "the head is safe (laser off, drivers off)",
            false => "the head did not confirm the stop: check it is safe (its host watch stops it once the host is silent)",
        };
        write!(
            f,
            "interrupted at position {} of {}; {head}; every sample so far is on disk: resume with `gonio scan --resume {}`",
            self.at,
            self.of,
            self.dir.display()
        )
    }
}

impl std::error::Error for Interrupted {}

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
