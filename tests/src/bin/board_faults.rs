//! `cargo run --release -p tests --bin board-faults`: the unmodified
//! release image on the virtual STM32F405 board (`tests/chip/board/`),
//! faulted in the middle of a measurement, and what the pins and the host
//! then see. Prints one JSON object and fails when a fault is not survived.
//!
//! Each trial boots the image, opens its port with the host crate's client
//! (as `gonio --port` does) and asks for a measurement; `STRIKE_S` after the
//! laser enable rises, the board injects the fault (`board.py --fault`):
//!
//! - `hardfault`: a bus error at whatever instruction runs;
//! - `stack-overflow`: the stack runs out (SP moved to the bottom of the
//!   CCM RAM), so the next push or exception entry falls outside memory;
//! - `estop-pulse`: the E-STOP opens for 200 µs, shorter than a turn of the
//!   serve loop.
//!
//! Survived means: the laser enable low within `LASER_OFF_BAR_S` of the
//! fault (`laser_off_us`, from the board's pin log, in emulated time), and
//! the drivers' enables high within the fault's own bound; after a fault
//! of the firmware (the first two) the independent watchdog resets the
//! chip within its timeout, every pin safe; after the E-STOP the
//! measurement is refused as an E-STOP (no sample), the head re-arms on a
//! continue once the input has stayed closed, and measures again.

use anyhow::{bail, Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_shared::icd::{ContinueEndpoint, MeasureEndpoint, MeasureRequest, StatusEndpoint};
use gonio_shared::{Fault, HeadState};
use gonio_tests::virtual_board::{board_plant, head_image, Board};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// When the fault strikes, after the laser enable first rises (s).
const STRIKE_S: f64 = 0.02;
/// The laser enable must be low this soon after any fault (s).
const LASER_OFF_BAR_S: f64 = 1e-3;
/// Emulated seconds a trial may run: boot, enumeration, a measurement and
/// the watchdog's timeout.
const TRIAL_SECONDS: &str = "30";

/// A fault, what the host should see, and how soon the drivers must be
/// disabled (s): at once when the firmware faulted; for the E-STOP, once
/// the serve loop has stopped the operation (the motion braked, then the
/// enables dropped), within a turn of it.
struct Trial {
    kind: &'static str,
    firmware_fault: bool,
    drivers_off_bar_s: f64,
}

const TRIALS: [Trial; 3] = [
    Trial {
        kind: "hardfault",
        firmware_fault: true,
        drivers_off_bar_s: LASER_OFF_BAR_S,
    },
    Trial {
        kind: "stack-overflow",
        firmware_fault: true,
        drivers_off_bar_s: LASER_OFF_BAR_S,
    },
    Trial {
        kind: "estop-pulse",
        firmware_fault: false,
        drivers_off_bar_s: 0.1,
    },
];

/// What the host's client met: each step's outcome, as text.
async fn host_side(pty: &str, firmware_fault: bool) -> Vec<(String, Result<String, String>)> {
    let mut steps = Vec::new();
    let head = match HeadClient::connect(&Port(pty.to_string())).await {
        Ok(h) => h,
        Err(e) => return vec![("connect".into(), Err(format!("{e:#}")))],
    };
    let measured = head.request::<MeasureEndpoint>(&MeasureRequest { at: None }).await;
    steps.push((
        "measure".into(),
        measured
            .map(|s| format!("{} V", s.signal.amplitude_v))
            .map_err(|e| format!("{e:#}")),
    ));
    if !firmware_fault {
        let status = head.request::<StatusEndpoint>(&()).await;
        steps.push((
            "status".into(),
            status
                .map(|s| format!("{:?}, E-STOP open {}", s.state, s.estop_open))
                .map_err(|e| format!("{e:#}")),
        ));
        let resumed = head.request::<ContinueEndpoint>(&()).await;
        steps.push((
            "continue".into(),
            resumed.map(|s| format!("{:?}", s.state)).map_err(|e| format!("{e:#}")),
        ));
        let again = head.request::<MeasureEndpoint>(&MeasureRequest { at: None }).await;
        steps.push((
            "measure again".into(),
            again.map(|s| format!("{} V", s.signal.amplitude_v)).map_err(|e| format!("{e:#}")),
        ));
    }
    head.close().await;
    steps
}

fn trial(root: &Path, image: &Path, plant: &Path, t: &Trial) -> Result<Value> {
    let fault = format!("{}@laser+{STRIKE_S}", t.kind);
    let board = Board::start(
        root,
        image,
        &[
            "--seconds".as_ref(),
            TRIAL_SECONDS.as_ref(),
            "--plant".as_ref(),
            plant.as_os_str(),
            "--fault".as_ref(),
            fault.as_ref(),
        ],
    )?;
    let pty = board.pty.clone();
    let host = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("a runtime for the client")?
        .block_on(host_side(&pty, t.firmware_fault));
    let report = board.stop()?;
    let f = &report["fault"];
    let laser_off = f["laser_off_after_s"].as_f64();
    let drivers_off = f["drivers_off_after_s"].as_f64();
    let mut problems = Vec::new();
    if f["struck"] != json!(true) {
        problems.push("the fault never struck (the laser never came on)".to_string());
    }
    if !laser_off.is_some_and(|s| s <= LASER_OFF_BAR_S) {
        problems.push(format!(
            "laser enable low {laser_off:?} s after the fault (bar {LASER_OFF_BAR_S} s)"
        ));
    }
    if !drivers_off.is_some_and(|s| s <= t.drivers_off_bar_s) {
        problems.push(format!(
            "drivers disabled {drivers_off:?} s after the fault (bar {} s)",
            t.drivers_off_bar_s
        ));
    }
    let outcome = |name: &str| host.iter().find(|(n, _)| n == name).map(|(_, r)| r.clone());
    if t.firmware_fault {
        let timeout = report["watchdog"]["timeout_s"].as_f64().unwrap_or(0.0);
        let reset = f["reset_after_s"].as_f64();
        if report["stopped"] != "watchdog reset" || !reset.is_some_and(|r| r <= timeout) {
            problems.push(format!(
                "no watchdog reset within its {timeout} s: {} after {reset:?} s",
                report["stopped"]
            ));
        }
        if report["locked_up"] != json!(false) {
            problems.push("the core locked up".into());
        }
        if report["safe_at_end"] != json!(true) {
            problems.push(format!("pins not safe after the reset: {}", report["driven_at_end"]));
        }
        if matches!(outcome("measure"), Some(Ok(_))) {
            problems.push("a measurement came back from a faulted head".into());
        }
    } else {
        let estop = Fault::EmergencyStop.to_string();
        if !matches!(outcome("measure"), Some(Err(e)) if e.contains(&estop)) {
            problems.push(format!("the measurement was not refused as an E-STOP: {:?}", outcome("measure")));
        }
        let faulted = format!("{:?}", HeadState::Faulted);
        if !matches!(outcome("status"), Some(Ok(s)) if s.starts_with(&faulted)) {
            problems.push(format!("the head did not hold the E-STOP: {:?}", outcome("status")));
        }
        for step in ["continue", "measure again"] {
            if !matches!(outcome(step), Some(Ok(_))) {
                problems.push(format!("{step}: {:?}", outcome(step)));
            }
        }
        if report["stopped"] != "stopped (SIGTERM)" {
            problems.push(format!("the board stopped: {}", report["stopped"]));
        }
    }
    Ok(json!({
        "kind": t.kind,
        "laser_off_us": laser_off.map(|s| (s * 1e7).round() / 10.0),
        "drivers_off_us": drivers_off.map(|s| (s * 1e7).round() / 10.0),
        "reset_after_s": f["reset_after_s"],
        "faults_taken": report["faults_taken"],
        "host": host.iter().map(|(n, r)| json!({"step": n, "ok": r.as_ref().ok(), "error": r.as_ref().err()})).collect::<Vec<_>>(),
        "emulated_s": report["virtual_seconds"],
        "wall_s": report["host_seconds"],
        "survived": problems.is_empty(),
        "problems": problems,
    }))
}

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let image = head_image(&root)?;
    let plant = board_plant(&root)?;
    let mut results = Vec::new();
    for t in &TRIALS {
        eprintln!("board-faults: {}", t.kind);
        results.push(trial(&root, &image, &plant, t).with_context(|| t.kind)?);
    }
    let survived = results.iter().filter(|r| r["survived"] == json!(true)).count();
    let laser_off_max = results.iter().filter_map(|r| r["laser_off_us"].as_f64()).fold(f64::NAN, f64::max);
    println!(
        "{}",
        json!({
            "faults": results,
            "faults_tried": TRIALS.len(),
            "faults_survived": survived,
            "laser_off_us_max": laser_off_max,
            "laser_off_bar_us": LASER_OFF_BAR_S * 1e6,
        })
    );
    if survived != TRIALS.len() {
        bail!("{} of {} faults not survived", TRIALS.len() - survived, TRIALS.len());
    }
    Ok(())
}
