//! Scans on the virtual board (`tests/chip/board/`) that a fault strikes in
//! the middle of, driven by `gonio scan --port` as a user drives a head:
//! whatever the fault, the scan directory must end with every planned
//! position stored once, none twice, none left out. Run by `board-bench`.
//!
//! - `dma-freeze`: the conversion chain stops in a measurement; the head
//!   refuses it (E500), and `gonio scan` recovers by itself (a transient
//!   fault: the head is asked to go on from the position not stored);
//! - `estop-pulse`: the E-STOP opens for 200 µs; the head stops the scan
//!   and `gonio scan` fails, saying so; the user re-arms the head (`gonio
//!   rearm`) and finishes the scan (`gonio scan --resume`);
//! - `usb-replug`: the cable is pulled for 100 ms and plugged back; the
//!   head holds the scan when the link goes, and `gonio scan` takes it up
//!   again once the port answers.

use crate::virtual_board::Board;
use anyhow::{bail, Context, Result};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

/// A small grid of the three incidences' middle one: 12 positions, two of
/// them in the splitter's blind zone.
pub const GRID: [&str; 7] = ["--theta-i", "30", "--theta-o", "0:60:20", "--dphi", "-90:90:90", "--no-patterns"];

/// When the fault strikes: 50 ms into the fourth measurement (DMA2 stream
/// 0's fourth enable; in a scan the laser stays on between positions, the
/// conversions do not).
const STRIKE: &str = "dma4+0.05";

/// A fault struck in a scan, and whether the user must re-arm and resume
/// (`gonio scan` ends with an error first).
struct FaultedScan {
    kind: &'static str,
    resume: bool,
}

const FAULTED_SCANS: [FaultedScan; 3] = [
    FaultedScan {
        kind: "dma-freeze",
        resume: false,
    },
    FaultedScan {
        kind: "estop-pulse",
        resume: true,
    },
    FaultedScan {
        kind: "usb-replug",
        resume: false,
    },
];

/// Runs `gonio ARGS` and reads the JSON object it prints: `Err` with that
/// object (or what it printed) and the notices it gave on the way (the
/// recoveries before the error) when it fails.
pub fn gonio(bin: &Path, args: &[&str]) -> Result<Value> {
    let out = Command::new(bin).args(args).output().with_context(|| format!("gonio {args:?}"))?;
    let notices = String::from_utf8_lossy(&out.stderr);
    let v: Value = serde_json::from_slice(&out.stdout).with_context(|| format!("gonio {args:?} printed no JSON: {notices}"))?;
    if !out.status.success() {
        bail!("gonio {args:?}: {v}; its notices: {:?}", notices.lines().collect::<Vec<_>>());
    }
    Ok(v)
}

/// The samples file of the scan in `dir`: the complete one, or the one an
/// interrupted scan left.
fn samples_file(dir: &Path) -> std::path::PathBuf {
    let whole = dir.join("samples.csv");
    if whole.exists() {
        whole
    } else {
        dir.join("samples.csv.part")
    }
}

/// How many times each grid index is stored in the scan in `dir`.
pub fn stored_indices(dir: &Path) -> Result<BTreeMap<u32, u32>> {
    let file = samples_file(dir);
    let text = std::fs::read_to_string(&file).with_context(|| format!("{}", file.display()))?;
    let mut lines = text.lines();
    let header = lines.next().context("an empty samples file")?;
    let column = header
        .split(',')
        .position(|c| c == "index")
        .context("no index column in the samples file")?;
    let mut seen = BTreeMap::new();
    for line in lines {
        let index: u32 = line
            .split(',')
            .nth(column)
            .and_then(|v| v.parse().ok())
            .with_context(|| format!("a row without an index: {line}"))?;
        *seen.entry(index).or_insert(0) += 1;
    }
    Ok(seen)
}

/// Samples stored in `dir`.
pub fn stored(dir: &Path) -> Result<usize> {
    Ok(stored_indices(dir)?.values().map(|&n| n as usize).sum())
}

fn faulted_scan(
    root: &Path,
    image: &Path,
    gonio_bin: &Path,
    plant_cmd: &str,
    planned: &BTreeMap<u32, u32>,
    dir: &Path,
    f: &FaultedScan,
) -> Result<Value> {
    let fault = format!("{}@{STRIKE}", f.kind);
    let args: [&OsStr; 8] = [
        "--pace".as_ref(),
        "3".as_ref(),
        "--seconds".as_ref(),
        "3600".as_ref(),
        "--plant".as_ref(),
        plant_cmd.as_ref(),
        "--fault".as_ref(),
        fault.as_ref(),
    ];
    let board = Board::start(root, image, &args)?;
    let d = dir.to_str().context("a UTF-8 path")?;
    let mut scan_args = vec!["scan", "--port", &board.pty, "--json", "--out", d];
    scan_args.extend(GRID);
    let first = gonio(gonio_bin, &scan_args).map_err(|e| format!("{e:#}"));
    let mut steps = vec![json!({"step": "scan", "ok": first.as_ref().ok(), "error": first.as_ref().err()})];
    if f.resume && first.is_err() {
        let rearm = gonio(gonio_bin, &["rearm", "--port", &board.pty, "--json"]).map_err(|e| format!("{e:#}"));
        steps.push(json!({"step": "rearm", "ok": rearm.as_ref().ok(), "error": rearm.as_ref().err()}));
        let resumed = gonio(gonio_bin, &["scan", "--port", &board.pty, "--json", "--resume", d]).map_err(|e| format!("{e:#}"));
        steps.push(json!({"step": "resume", "ok": resumed.as_ref().ok(), "error": resumed.as_ref().err()}));
    }
    let report = board.stop()?;
    let seen = stored_indices(dir).unwrap_or_default();
    let twice: Vec<u32> = seen.iter().filter(|(_, &n)| n > 1).map(|(&i, _)| i).collect();
    let left_out: Vec<u32> = planned.keys().filter(|i| !seen.contains_key(i)).copied().collect();
    let unplanned: Vec<u32> = seen.keys().filter(|i| !planned.contains_key(i)).copied().collect();
    let mut problems = Vec::new();
    if report["fault"]["struck"] != json!(true) {
        problems.push("the fault never struck".to_string());
    }
    if f.resume == first.is_ok() {
        problems.push(format!(
            "the first scan {} (expected {})",
            if first.is_ok() { "completed" } else { "failed" },
            if f.resume { "a failure to resume from" } else { "it to complete" }
        ));
    }
    if !dir.join("samples.csv").exists() {
        problems.push("the scan did not complete (no samples.csv)".into());
    }
    if !(twice.is_empty() && left_out.is_empty() && unplanned.is_empty()) {
        problems.push(format!("stored twice {twice:?}, left out {left_out:?}, not planned {unplanned:?}"));
    }
    Ok(json!({
        "fault": f.kind,
        "struck_s": report["fault"]["struck_s"],
        "laser_off_us": report["fault"]["laser_off_after_s"].as_f64().map(|s| (s * 1e7).round() / 10.0),
        "steps": steps,
        "stored": seen.values().sum::<u32>(),
        "planned": planned.len(),
        "stored_twice": twice,
        "left_out": left_out,
        "board_stopped": report["stopped"],
        "emulated_s": report["virtual_seconds"],
        "wall_s": report["host_seconds"],
        "complete": problems.is_empty(),
        "problems": problems,
    }))
}

/// The faulted scans of [`GRID`], each on a board of its own with the
/// plant `plant_cmd`, against the positions the in-process simulated
/// head stores for the same grid: a JSON object with each scan's figures
/// and `scans_complete` of `scans_tried`.
pub fn run(root: &Path, image: &Path, gonio_bin: &Path, plant_cmd: &str, material: &[&str], work: &Path) -> Result<Value> {
    let sim = work.join("faulted-sim");
    let s = sim.to_str().context("a UTF-8 path")?;
    let mut args = vec!["scan", "--sim", "--json", "--out", s];
    args.extend(GRID);
    args.extend(material);
    gonio(gonio_bin, &args)?;
    let planned = stored_indices(&sim)?;
    let mut scans = Vec::new();
    for f in &FAULTED_SCANS {
        eprintln!("board scans: {}", f.kind);
        let dir = work.join(format!("faulted-{}", f.kind));
        scans.push(faulted_scan(root, image, gonio_bin, plant_cmd, &planned, &dir, f).with_context(|| f.kind)?);
    }
    let complete = scans.iter().filter(|s| s["complete"] == json!(true)).count();
    Ok(json!({
        "grid": GRID.join(" "),
        "strike": STRIKE,
        "scans": scans,
        "scans_tried": FAULTED_SCANS.len(),
        "scans_complete": complete,
    }))
}
