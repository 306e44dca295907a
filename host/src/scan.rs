//! Running a scan on a connected head: the request, the event stream with
//! its continuity check, durable storage of every sample, progress.

use crate::client::Head;
use crate::samples_csv::SampleWriter;
use anyhow::{bail, Result};
use gonio_shared::{ScanEvent, ScanSpec};
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

/// Runs `spec` to the end, appending every sample to `out`.
pub async fn run(head: &Head, spec: &ScanSpec, out: &mut SampleWriter, pb: &ProgressBar) -> Result<ScanOutcome> {
    let t0 = Instant::now();
    let (accepted, mut events) = head.start_scan(spec).await?;
    pb.set_length((accepted.points - accepted.first_order) as u64);
    let mut outcome = ScanOutcome {
        points: accepted.points,
        measured: 0,
        skipped: 0,
        skipped_by_reason: BTreeMap::new(),
        flagged: 0,
        head_time_s: 0.0,
        wall_time_s: 0.0,
    };
    let mut expected = accepted.first_order;
    let (mut first_ts, mut last_ts) = (None, 0u64);
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
                outcome.measured += 1;
                if s.flags.0 & !gonio_shared::SampleFlags::THROUGH_SPLITTER != 0 {
                    outcome.flagged += 1;
                }
                first_ts.get_or_insert(s.timestamp_us);
                last_ts = s.timestamp_us;
            }
            ScanEvent::Skipped { reason, .. } => {
                outcome.skipped += 1;
                *outcome.skipped_by_reason.entry(reason.to_string()).or_default() += 1;
            }
            ScanEvent::Finished { measured, skipped } => {
                if (measured, skipped) != (outcome.measured, outcome.skipped) {
                    bail!(
                        "the head counted {measured} measured and {skipped} skipped points, the host {} and {}",
                        outcome.measured,
                        outcome.skipped
                    );
                }
                break;
            }
            ScanEvent::Stopped { next_order, reason } => {
                bail!("the head stopped the scan: {reason}; resume from position {next_order}")
            }
        }
        pb.set_message(format!("{} measured, {} unreachable", outcome.measured, outcome.skipped));
    }
    pb.finish_and_clear();
    outcome.head_time_s = last_ts.saturating_sub(first_ts.unwrap_or(last_ts)) as f64 * 1e-6;
    outcome.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(outcome)
}
