//! `run.json`: what was scanned, with what, and how it went. Written once the
//! scan completed, next to `samples.csv`.

use crate::ScanDir;
use anyhow::{Context, Result};
use gonio_brdf::Specimen;
use gonio_shared::{DetectionReport, Identity, LearnReport, ScanSpec, SweepScan};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Debug, Serialize)]
pub struct Versions {
    pub gonio: &'static str,
    pub protocol: u16,
    pub firmware: String,
}

/// Which head the run was taken on.
#[derive(Debug, Serialize)]
pub struct HeadRecord {
    pub board: String,
    pub serial: String,
    pub simulated: bool,
}

#[derive(Debug, Serialize)]
pub struct Grid {
    pub theta_i_deg: Vec<f32>,
    pub theta_o_deg: [f32; 3],
    pub dphi_deg: [f32; 3],
    /// Visit positions: points, or a sweep scan's rows and retro points.
    pub points: u32,
    /// How a sweep scan swept its rows (speed, sample length, the lobe it
    /// slowed down for); absent for a grid scan.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep: Option<SweepScan>,
}

impl From<&ScanSpec> for Grid {
    fn from(s: &ScanSpec) -> Self {
        Grid {
            theta_i_deg: s.theta_i_deg.to_vec(),
            theta_o_deg: [s.theta_o.start_deg, s.theta_o.stop_deg, s.theta_o.step_deg],
            dphi_deg: [s.dphi.start_deg, s.dphi.stop_deg, s.dphi.step_deg],
            points: s.len(),
            sweep: s.sweep,
        }
    }
}

#[derive(Debug, Serialize)]
pub struct Detection {
    pub reference: String,
    pub chop_hz: f32,
    pub samples_per_period: u16,
    pub periods: u16,
    pub integration_s: f32,
    pub enbw_hz: f32,
    pub settle_s: f32,
}

impl From<&DetectionReport> for Detection {
    fn from(r: &DetectionReport) -> Self {
        Detection {
            reference: format!("{:?}", r.settings.reference).to_lowercase(),
            chop_hz: r.chop_hz_actual,
            samples_per_period: r.settings.samples_per_period,
            periods: r.settings.periods,
            integration_s: r.integration_s,
            enbw_hz: r.enbw_hz,
            settle_s: r.settings.settle_s,
        }
    }
}

/// What a completed scan did.
#[derive(Debug, Clone, Serialize)]
pub struct ScanOutcome {
    /// Visit positions: points, or a sweep scan's rows and retro points.
    pub points: u32,
    pub measured: u32,
    /// Samples a sweep scan's rows yielded (0 for a scan of points).
    pub swept_samples: u32,
    pub skipped: u32,
    /// Unreachable points by reason.
    pub skipped_by_reason: BTreeMap<String, u32>,
    /// Samples carrying a quality flag other than `through_splitter`.
    pub flagged: u32,
    /// Events that arrived twice (or late from an earlier run) and were dropped.
    pub duplicates_dropped: u32,
    /// Interruptions recovered, by cause.
    pub recoveries: BTreeMap<String, u32>,
    /// Time the head spent (its clock, s), from its state just before the
    /// scan started to the scan's last event: real time on a real head,
    /// simulated time on the simulator.
    pub head_time_s: f64,
    /// No stop-and-go order of the scan's points (a sweep scan's grid
    /// points) takes less head time than this (s;
    /// `gonio_acquire::scan_order::lower_bound`); absent for a resumed scan,
    /// whose head time covers only its last part, for one with a drift
    /// monitor, whose visits the bound knows nothing of, and for one too
    /// large to bound.
    pub lower_bound_s: Option<f64>,
    pub wall_time_s: f64,
}

impl ScanOutcome {
    /// Head time against the lower bound, in words (`None` without a bound).
    pub fn against_bound(&self) -> Option<String> {
        self.lower_bound_s.map(|bound| {
            format!(
                "{} of head time; no stop-and-go order of the grid's points takes less than {} (× {:.3})",
                hms(self.head_time_s),
                hms(bound),
                self.head_time_s / bound
            )
        })
    }

    /// What the scan of `spec` did, in lines for the operator, ending with
    /// where its samples are.
    pub fn summary(&self, spec: &ScanSpec, samples: &Path) -> String {
        let mut lines = vec![format!(
            "{} {}: {} measured, {} unreachable, {} flagged; {:.0} s of head time in {:.1} s",
            self.points,
            positions(spec),
            self.measured,
            self.skipped,
            self.flagged,
            self.head_time_s,
            self.wall_time_s
        )];
        lines.extend(self.against_bound().map(|b| format!("  {b}")));
        lines.extend(self.skipped_by_reason.iter().map(|(reason, n)| format!("  {n:5} × {reason}")));
        lines.extend(self.recoveries.iter().map(|(why, n)| format!("  recovered {n} × {why}")));
        if self.duplicates_dropped > 0 {
            lines.push(format!("  {} duplicate events dropped", self.duplicates_dropped));
        }
        lines.push(format!("samples: {}", samples.display()));
        lines.join("\n") + "\n"
    }
}

impl ScanOutcome {
    /// What the scan of `spec` measured, in a sentence for a report.
    pub fn measured_text(&self, spec: &ScanSpec) -> String {
        match spec.sweep {
            Some(_) => format!(
                "{} rows of the grid swept, {} retro points and {} pattern points measured at rest: {} of them measured ({} swept samples), {} refused, {} flagged",
                spec.rows(),
                spec.retro_points(),
                spec.pattern_points(),
                self.measured,
                self.swept_samples,
                self.skipped,
                self.flagged
            ),
            None => format!(
                "{} points of the grid: {} measured, {} unreachable, {} flagged",
                self.points, self.measured, self.skipped, self.flagged
            ),
        }
    }
}

/// What a scan's visit positions are called: a grid's points, or a sweep
/// scan's positions (rows and retro points).
pub fn positions(spec: &ScanSpec) -> &'static str {
    match spec.sweep {
        Some(_) => "positions",
        None => "points",
    }
}

/// Seconds as h:mm:ss.
pub fn hms(s: f64) -> String {
    let s = s.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[derive(Debug, Serialize)]
pub struct RunRecord {
    pub versions: Versions,
    pub head: HeadRecord,
    /// The simulated head's material; absent for a real head.
    pub material: Option<Specimen>,
    pub grid: Grid,
    pub detection: Detection,
    /// The reference the detector learned before the scan, if any.
    pub learned: Option<LearnReport>,
    /// The duration estimated before the scan (s); compare `counts.head_time_s`.
    pub estimated_s: Option<f64>,
    pub counts: ScanOutcome,
    pub complete: bool,
}

impl RunRecord {
    pub fn new(
        id: &Identity,
        material: Option<Specimen>,
        spec: &ScanSpec,
        det: &DetectionReport,
        learned: Option<LearnReport>,
        counts: ScanOutcome,
    ) -> Self {
        RunRecord {
            versions: Versions {
                gonio: env!("CARGO_PKG_VERSION"),
                protocol: id.protocol_version,
                firmware: id.firmware_version.to_string(),
            },
            head: HeadRecord {
                board: id.board.to_string(),
                serial: id.serial.to_string(),
                simulated: id.simulated,
            },
            material,
            grid: Grid::from(spec),
            detection: Detection::from(det),
            learned,
            estimated_s: None,
            counts,
            complete: true,
        }
    }

    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = ScanDir::new(dir).run_record();
        let text = serde_json::to_string_pretty(self)?;
        std::fs::write(&path, text + "\n").with_context(|| format!("writing {}", path.display()))
    }
}
