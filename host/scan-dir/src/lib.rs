//! The files of one scan directory and their formats, in one crate: what
//! acquisition (`gonio-acquire`) writes, what `gonio scan --resume` reads
//! back and what analysis (`gonio-analysis`) takes (`docs/samples-csv.md`
//! gives their columns). Links no tokio, serial port or simulator thread.
//!
//! | file | module |
//! |---|---|
//! | `scan.json` | [`record`] |
//! | `reference.csv`, `samples.csv.part`, `samples.csv` | [`samples`] (swept samples' geometry: [`swept`]) |
//! | `run.json` | [`run`] |
//! | `calibrated.csv` | [`calibrated`] |
//! | `calibration.json` | named here; its typed summary is `gonio_analysis::calibration::directory::Summary`, whose fields are the analysis's own types |

pub mod calibrated;
pub mod record;
pub mod run;
pub mod samples;
pub mod swept;

use std::path::{Path, PathBuf};

/// A scan directory.
#[derive(Debug, Clone, Copy)]
pub struct ScanDir<'a> {
    root: &'a Path,
}

impl<'a> ScanDir<'a> {
    pub fn new(root: &'a Path) -> Self {
        ScanDir { root }
    }

    pub fn root(&self) -> &'a Path {
        self.root
    }

    /// `scan.json`: what the scan was asked to do, written before its first
    /// sample (`--resume` repeats it).
    pub fn record(&self) -> PathBuf {
        self.root.join("scan.json")
    }

    /// `samples.csv.part`: the samples while the scan runs, one durable row
    /// per point; an interrupted scan resumes after its last whole row.
    pub fn samples_part(&self) -> PathBuf {
        self.root.join("samples.csv.part")
    }

    /// `samples.csv`: the samples of a completed scan.
    pub fn samples(&self) -> PathBuf {
        self.root.join("samples.csv")
    }

    /// `reference.csv`: the reference plate's samples, taken before the scan.
    pub fn reference(&self) -> PathBuf {
        self.root.join("reference.csv")
    }

    /// `run.json`: versions, head, grid, detection and counts of the run.
    pub fn run_record(&self) -> PathBuf {
        self.root.join("run.json")
    }

    /// `calibrated.csv`: the samples in BRDF units, written by `gonio calibrate`.
    pub fn calibrated(&self) -> PathBuf {
        self.root.join("calibrated.csv")
    }

    /// `calibration.json`: the plate's scale, splitter factor and drift that
    /// `gonio calibrate` found (its fields are the calibration's own).
    pub fn calibration(&self) -> PathBuf {
        self.root.join("calibration.json")
    }

    /// What a new scan must not overwrite: a completed scan's samples and record.
    /// Where a running scan's live view listens (`{"url", "pid"}`), for
    /// `gonio pause|continue|abort DIR`; there only while the scan runs.
    pub fn live(&self) -> PathBuf {
        self.root.join("live.json")
    }

    pub fn finished_files(&self) -> [PathBuf; 2] {
        [self.samples(), self.run_record()]
    }
}
