//! Running a scan on a connected head: the request, the event stream with
//! its continuity check, durable storage of every sample, progress.

use crate::client::Head;
use crate::samples_csv::SampleWriter;
use anyhow::{bail, Context, Result};
use gonio_shared::{Fault, Geometry, ScanEvent, ScanSpec};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// Longest silence between two scan events (one move plus one integration).
const EVENT_TIMEOUT: Duration = Duration::from_secs(180);

/// What a completed scan did.
#[derive(Debug, Clone, Serialize)]
pub struct ScanOutcome {
    pub points: u32,
    pub measured: u32,
    pub skipped: u32,
    /// Unreachable points by reason.
    pub skipped_by_reason: BTreeMap<String, u32>,
    /// Samples carrying a quality flag other than `through_splitter`.
    pub flagged: u32,
    /// Time the head spent (its clock, s): real time on a real head, simulated time on the simulator.
    pub head_time_s: f64,
    pub wall_time_s: f64,
}

/// A bar on a terminal, nothing otherwise (or when `quiet`).
pub fn progress_bar(len: u64, quiet: bool, task: &str, items: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} {task} [{{bar:40}}] {{pos}}/{{len}} {items}, {{msg}} ({{eta}} left)"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    pb
}

/// A laser-drift monitor: one geometry of the mounted target, measured
/// before the scan, after every `every` scan positions, and after the scan.
/// Its readings track the laser's power through the scan (`gonio calibrate`
/// interpolates them). The scan is paused for it with an abort between two
/// points and continued from the next position, as a resume would.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct Monitor {
    pub at: Geometry,
    pub every: u32,
}

/// How a stretch of scan ended.
enum Stretch {
    Finished,
    /// Paused for the monitor; continue at this visit position.
    Paused(u32),
}

/// Runs `spec` to the end, appending every sample (and every monitor
/// reading, a row without scan position) to `out`.
pub async fn run(head: &Head, spec: &ScanSpec, out: &mut SampleWriter, pb: &ProgressBar, monitor: Option<&Monitor>) -> Result<ScanOutcome> {
    let t0 = Instant::now();
    let mut outcome = ScanOutcome {
        points: spec.len(),
        measured: 0,
        skipped: 0,
        skipped_by_reason: BTreeMap::new(),
        flagged: 0,
        head_time_s: 0.0,
        wall_time_s: 0.0,
    };
    let mut clock = HeadClock::default();
    let mut first = spec.first_order;
    pb.set_length((outcome.points - first) as u64);
    loop {
        if let Some(m) = monitor {
            read_monitor(head, m, out, &mut clock).await?;
        }
        let stop_at = monitor.map(|m| first.saturating_add(m.every.max(1)));
        let stretch = ScanSpec {
            first_order: first,
            ..spec.clone()
        };
        match run_stretch(head, &stretch, out, pb, &mut outcome, &mut clock, stop_at).await? {
            Stretch::Finished => break,
            Stretch::Paused(next) => first = next,
        }
    }
    if let Some(m) = monitor {
        read_monitor(head, m, out, &mut clock).await?;
    }
    pb.finish_and_clear();
    outcome.head_time_s = clock.span_s();
    outcome.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(outcome)
}

/// Readings per monitor visit: every sample of the scan is referred to them,
/// so their noise is averaged down (`gonio calibrate` merges a visit's readings).
pub const MONITOR_READINGS: usize = 4;

/// One visit to the monitor geometry: a move, then [`MONITOR_READINGS`]
/// measurements in place.
async fn read_monitor(head: &Head, m: &Monitor, out: &mut SampleWriter, clock: &mut HeadClock) -> Result<()> {
    for k in 0..MONITOR_READINGS {
        let at = (k == 0).then_some(m.at);
        let s = head.measure(at).await.context("measuring the laser-drift monitor")?;
        out.push(&s)?;
        clock.saw(s.timestamp_us);
    }
    Ok(())
}

/// First and last timestamp the head reported (µs).
#[derive(Default)]
struct HeadClock {
    first: Option<u64>,
    last: u64,
}

impl HeadClock {
    fn saw(&mut self, t_us: u64) {
        self.first.get_or_insert(t_us);
        self.last = t_us;
    }

    fn span_s(&self) -> f64 {
        self.last.saturating_sub(self.first.unwrap_or(self.last)) as f64 * 1e-6
    }
}

/// Runs the scan from `spec.first_order`, to the end or, with `stop_at`,
/// until that visit position has been reached (then aborts it between points).
async fn run_stretch(
    head: &Head,
    spec: &ScanSpec,
    out: &mut SampleWriter,
    pb: &ProgressBar,
    outcome: &mut ScanOutcome,
    clock: &mut HeadClock,
    stop_at: Option<u32>,
) -> Result<Stretch> {
    let (accepted, mut events) = head.start_scan(spec).await?;
    outcome.points = accepted.points;
    let mut expected = accepted.first_order;
    let (mut measured, mut skipped) = (0, 0);
    let mut pausing = false;
    loop {
        let ev = match tokio::time::timeout(EVENT_TIMEOUT, events.recv()).await {
            Err(_) => bail!(
                "the head went silent during the scan (no event for {} s); resume from position {expected}",
                EVENT_TIMEOUT.as_secs()
            ),
            Ok(None) => bail!("the link to the head closed during the scan; resume from position {expected}"),
            Ok(Some(ev)) => ev,
        };
        let order = match &ev {
            ScanEvent::Sample(s) => s.scan.map(|p| p.order),
            ScanEvent::Skipped { order, .. } => Some(*order),
            ScanEvent::Finished { .. } | ScanEvent::Stopped { .. } => None,
        };
        if let Some(o) = order {
            if o != expected {
                bail!("scan events lost: expected position {expected}, got {o}; resume from position {expected}");
            }
            expected += 1;
            pb.inc(1);
        }
        match ev {
            ScanEvent::Sample(s) => {
                out.push(&s)?;
                measured += 1;
                outcome.measured += 1;
                if s.flags.0 & !gonio_shared::SampleFlags::THROUGH_SPLITTER != 0 {
                    outcome.flagged += 1;
                }
                clock.saw(s.timestamp_us);
            }
            ScanEvent::Skipped { reason, .. } => {
                skipped += 1;
                outcome.skipped += 1;
                *outcome.skipped_by_reason.entry(reason.to_string()).or_default() += 1;
            }
            ScanEvent::Finished {
                measured: head_measured,
                skipped: head_skipped,
            } => {
                if (head_measured, head_skipped) != (measured, skipped) {
                    bail!("the head counted {head_measured} measured and {head_skipped} skipped points, the host {measured} and {skipped}");
                }
                return Ok(Stretch::Finished);
            }
            ScanEvent::Stopped { next_order, reason } => {
                if pausing && reason == Fault::Aborted && next_order == expected {
                    return Ok(Stretch::Paused(next_order));
                }
                bail!("the head stopped the scan: {reason}; resume from position {next_order}")
            }
        }
        pb.set_message(format!("{} measured, {} unreachable", outcome.measured, outcome.skipped));
        if !pausing && stop_at.is_some_and(|p| expected >= p && expected < outcome.points) {
            head.abort().await.context("pausing the scan for the laser-drift monitor")?;
            pausing = true;
        }
    }
}
