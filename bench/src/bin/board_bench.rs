//! board-bench: the unmodified release image scans on the virtual STM32F405
//! board (`tests/chip/board/`), driven by `gonio scan --port` over the
//! board's USB host and pseudo-terminal, with the simulated head's world
//! behind its pins (`board-plant`). Prints one JSON object:
//!
//! - `points_stored` against `points_planned`: the samples the board's scan
//!   stored, and those the in-process simulated head's scan of the same
//!   grid stores (the blind zone's points are skipped by both);
//! - `fits_agree`: retro-phong fitted to each scan, calibrated with the
//!   simulated head's plate scan (the plant is the simulated head's world:
//!   same laser, photodiode and gains), every parameter within 2 combined
//!   standard errors;
//! - `step_edge_jitter_ticks_max` (bar ≤ 2): the longest a STEP edge rose
//!   after its planned time (the tick the step timer's compare was set
//!   for, matched or already passed when written), in ticks of its 1 MHz
//!   clock, from the board's pin log;
//! - `step_isr_latency_cycles_max`: the longest the step timer's interrupt
//!   waited from pending to its handler (USB, DMA and the time driver's
//!   interrupts, and critical sections, in the way);
//! - `cpu_load_scan`: instructions over cycles for the whole run (one cycle
//!   per instruction; the core's waits are idle), and `interrupt_runs`,
//!   each handler's count and cycles (the guard's, TIM7, among them);
//! - `stack_high_water_bytes` (bar ≤ 48 KiB);
//! - `thread_turn_longest_laser_on_us` (bar: the guard's allowance, 750
//!   µs): the longest the thread ran without a turn of its loop while the
//!   laser was on, which the guard would take for a stuck thread;
//! - `faults_survived` of `faults_tried` and `laser_off_us_max` (bar ≤
//!   1 000): the fault trials (`gonio_bench::fault_trials`), each a board of
//!   its own;
//! - `faulted_scans_complete` of `faulted_scans_tried`: scans a fault
//!   strikes in the middle of, each ending with every position stored once
//!   (`gonio_bench::board_scans`);
//! - `emulated_s`, `wall_s` (of the scan; the trials' are in theirs).
//!
//! The board runs at most `PACE` times faster than the wall clock: the
//! host's heartbeat (every 5 s) must reach the head's 20 s watch. The
//! stages power up a degree from their home switches, so that homing takes
//! seconds, not the minutes of a full travel.

use anyhow::{bail, Context, Result};
use gonio_bench::board_scans::{self, gonio, stored};
use gonio_bench::chip_costs;
use gonio_bench::fault_trials;
use gonio_bench::virtual_board::{board_plant, head_image, Board};
use gonio_firmware::config::{CPU_HZ, REFERENCE};
use gonio_firmware::guard::{STUCK_TICKS, TICK_US};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A subset of the Belcour grid over its three incidences: 351 points.
const GRID: [&str; 7] = [
    "--theta-i",
    "15,30,60",
    "--theta-o",
    "0:80:10",
    "--dphi",
    "-180:180:30",
    "--no-patterns",
];
const MATERIAL: [&str; 4] = ["--material", "retro-phong", "--seed", "1"];
const PACE: &str = "3";
const STACK_BAR_BYTES: u64 = 48 * 1024;
const JITTER_BAR_TICKS: f64 = 2.0;
const LASER_OFF_BAR_US: f64 = 1_000.0;
/// The step timer's tick (cycles of the 168 MHz core).
const TICK_CYCLES: f64 = CPU_HZ / 1e6;

fn cargo(root: &Path, args: &[&str]) -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut c = Command::new(cargo);
    c.args(args).current_dir(root);
    if !cfg!(debug_assertions) {
        c.arg("--release");
    }
    if !c.status().with_context(|| format!("cargo {args:?}"))?.success() {
        bail!("cargo {args:?} failed");
    }
    Ok(())
}

/// Calibrates the scan in `dir` with the plate scan `reference` and fits
/// retro-phong to it: (parameters, standard errors).
fn fit(bin: &Path, dir: &Path, reference: &Path) -> Result<Value> {
    let d = dir.to_str().context("a UTF-8 path")?;
    gonio(
        bin,
        &["calibrate", d, "--reference", reference.to_str().context("a UTF-8 path")?, "--json"],
    )?;
    gonio(bin, &["fit", &format!("{d}/calibrated.csv"), "--model", "retro-phong", "--json"])
}

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let image = head_image(&root)?;
    cargo(&root, &["build", "--locked", "-p", "gonio", "--bin", "gonio"])?;
    let plant = board_plant(&root)?;
    let gonio_bin = plant.with_file_name("gonio");
    let work = tempfile::tempdir()?;
    let (sim_dir, board_dir) = (work.path().join("sim"), work.path().join("board"));

    // The in-process simulated head: the plan and the fit to agree with.
    let mut args = vec![
        "scan",
        "--sim",
        "--reference-plate",
        "--json",
        "--out",
        sim_dir.to_str().context("path")?,
    ];
    args.extend(GRID);
    args.extend(MATERIAL);
    gonio(&gonio_bin, &args)?;
    let planned = stored(&sim_dir)?;
    let reference = sim_dir.join("reference.csv");
    let sim_fit = fit(&gonio_bin, &sim_dir, &reference)?;

    // The board, its stages a degree above their home switches.
    let power_up = REFERENCE.axes.map(|a| format!("{}", a.home_deg + 1.0)).join(",");
    let plant_cmd = format!("{} {} --power-up={power_up}", plant.display(), MATERIAL.join(" "));
    let started = std::time::Instant::now();
    let board = Board::start(
        &root,
        &image,
        &[
            "--pace".as_ref(),
            PACE.as_ref(),
            "--seconds".as_ref(),
            "7200".as_ref(),
            "--plant".as_ref(),
            plant_cmd.as_ref(),
        ],
    )?;
    let mut args = vec!["scan", "--port", &board.pty, "--json", "--out", board_dir.to_str().context("path")?];
    args.extend(GRID);
    let scan = gonio(&gonio_bin, &args);
    let report = board.stop()?;
    let wall_s = started.elapsed().as_secs_f64();
    // An interrupted scan, or one that had to recover its link, is reported
    // too, with what the board saw: its whole report (USB log, sessions,
    // pins, interrupts) is kept beside the build.
    let scan = scan.map_err(|e| format!("{e:#}"));
    let recovered = scan
        .as_ref()
        .is_ok_and(|s| s["recoveries"].as_object().is_some_and(|r| !r.is_empty()));
    let kept_report = if scan.is_err() || recovered {
        let path = chip_costs::target_dir().join("board-bench-report.json");
        std::fs::write(&path, report.to_string()).with_context(|| format!("{}", path.display()))?;
        Some(path.display().to_string())
    } else {
        None
    };
    let points = stored(&board_dir)?;
    let board_fit = match &scan {
        Ok(_) => fit(&gonio_bin, &board_dir, &reference)?,
        Err(_) => Value::Null,
    };

    let mut agree = serde_json::Map::new();
    let mut fits_agree = scan.is_ok();
    for (name, a) in sim_fit["params"].as_object().context("the simulated scan's fit")? {
        let (a, b) = (
            a.as_f64().unwrap_or(f64::NAN),
            board_fit["params"][name].as_f64().unwrap_or(f64::NAN),
        );
        let (sa, sb) = (
            sim_fit["stderr"][name].as_f64().unwrap_or(f64::NAN),
            board_fit["stderr"][name].as_f64().unwrap_or(f64::NAN),
        );
        let z = (a - b).abs() / (sa * sa + sb * sb).sqrt();
        fits_agree &= z <= 2.0;
        agree.insert(name.clone(), json!({"simulated": a, "board": b, "combined_sigmas": z}));
    }
    let jitter_ticks = report["step_edge_lateness_cycles"]["max"].as_f64().map(|c| c / TICK_CYCLES);
    let turn_us = report["thread_turn_longest_laser_on_us"].as_f64();
    let turn_bar_us = (STUCK_TICKS * TICK_US) as f64;

    let faults = fault_trials::run(&root, &image, &plant)?;
    let laser_off_us = faults["laser_off_us_max"].as_f64();
    let faults_all = faults["faults_survived"] == faults["faults_tried"];
    let scans = board_scans::run(&root, &image, &gonio_bin, &plant_cmd, &MATERIAL, work.path())?;
    let scans_all = scans["scans_complete"] == scans["scans_tried"];
    let stack = report["stack_bytes_max"].as_u64().context("the board's stack")?;
    let emulated_s = report["virtual_seconds"].as_f64().context("the board's time")?;
    let instructions = report["instructions"].as_f64().context("the board's instructions")?;
    let figures = json!({
        "grid": GRID.join(" "),
        "material": MATERIAL.join(" "),
        "points_planned": planned,
        "points_stored": points,
        "scan": scan.as_ref().ok(),
        "scan_error": scan.as_ref().err(),
        "board_report": kept_report,
        "fits": agree,
        "fits_agree": fits_agree,
        "step_edges": report["step_edges"],
        "step_edge_jitter_ticks_max": jitter_ticks,
        "step_edge_lateness_cycles": report["step_edge_lateness_cycles"],
        "step_isr_latency_cycles_max": report["interrupt_worst_wait"]["TIM5"]["cycles"],
        "interrupt_worst_wait": report["interrupt_worst_wait"],
        "interrupts": report["interrupts"],
        "interrupt_runs": report["interrupt_runs"],
        "cpu_load_scan": instructions / (emulated_s * CPU_HZ),
        "stack_high_water_bytes": stack,
        "thread_turn_longest_laser_on_us": turn_us,
        "faults_tried": faults["faults_tried"],
        "faults_survived": faults["faults_survived"],
        "laser_off_us_max": laser_off_us,
        "faults": faults["faults"],
        "faulted_scans_tried": scans["scans_tried"],
        "faulted_scans_complete": scans["scans_complete"],
        "faulted_scans": scans,
        "board_stopped": report["stopped"],
        "unsafe_at_end": !report["safe_at_end"].as_bool().unwrap_or(false),
        "emulated_s": emulated_s,
        "wall_s": wall_s,
        "bars": {
            "points_stored": planned,
            "step_edge_jitter_ticks_max": JITTER_BAR_TICKS,
            "stack_high_water_bytes": STACK_BAR_BYTES,
            "thread_turn_longest_laser_on_us": turn_bar_us,
            "faults_survived": faults["faults_tried"],
            "laser_off_us_max": LASER_OFF_BAR_US,
            "faulted_scans_complete": scans["scans_tried"],
        },
        "bars_met": {
            "points_stored": points == planned,
            "fits_agree": fits_agree,
            "step_edge_jitter_ticks_max": jitter_ticks.is_some_and(|t| t <= JITTER_BAR_TICKS),
            "stack_high_water_bytes": stack <= STACK_BAR_BYTES,
            "thread_turn_longest_laser_on_us": turn_us.is_some_and(|t| t <= turn_bar_us),
            "faults_survived": faults_all,
            "laser_off_us_max": laser_off_us.is_some_and(|t| t <= LASER_OFF_BAR_US),
            "faulted_scans_complete": scans_all,
        },
    });
    println!("{figures}");
    if let Err(e) = scan {
        bail!("the scan on the board did not complete: {e}");
    }
    Ok(())
}
