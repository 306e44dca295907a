//! Faults on the virtual STM32F405 board (`tests/chip/board/`): the
//! unmodified release image faulted in the middle of a measurement, and
//! what the pins and the host then see; run by `board-faults` (in CI) and
//! `board-bench`.
//!
//! Each trial boots the image, opens its port with the host crate's client
//! (as `gonio --port` does) and asks for a measurement; `STRIKE_S` after the
//! laser enable rises, the board injects the fault (`python3 -m board --fault`):
//!
//! - `hardfault`: a bus error at whatever instruction runs;
//! - `stack-overflow`: the stack runs out (SP moved to the bottom of the
//!   CCM RAM), so the next push or exception entry falls outside memory;
//! - `estop-pulse`: the E-STOP opens for 200 µs, shorter than a turn of the
//!   serve loop;
//! - `dma-freeze`: DMA2 stream 0 stops serving the ADC (NDTR frozen, EN
//!   set) until the firmware disables and enables it;
//! - `adc-overrun`: ADC1 loses a result and sets OVR, ignoring triggers
//!   until the firmware clears it;
//! - `serve-hang`: the serve loop stuck in a loop that never yields, the
//!   interrupts still served (the watchdog starved);
//! - `estop-hung`: the E-STOP opens as the serve loop hangs: the thread
//!   cannot stop the drivers, the guard's backstop must;
//! - `usb-suspend`: the host suspends the bus for 50 ms and resumes it
//!   without a reset;
//! - `usb-replug`: the cable pulled for 100 ms and plugged back (a bus
//!   reset, enumeration, the port reopened);
//! - `usb-in-nak`: the host keeps the port open but stops reading;
//! - `crystal-stop`: the crystal stops oscillating (the clock security
//!   system's NMI, the core on the HSI);
//! - `stray-irq`: an interrupt the image has no handler for, enabled and
//!   pended at priority 0.
//!
//! Survived means: the laser enable and the chop low (the chop high when
//! the fault struck, so that its cut shows; 10 µs for the E-STOP, 1 ms for
//! the rest), and the drivers' enables high, within the fault's bound
//! (`laser_off_us`, `chop_off_us`, from the board's pin log, in
//! emulated time, from the fault: the faulting access for a fault of the
//! firmware, the injection otherwise), and then: after a fault of the
//! firmware or a hung serve loop, the independent watchdog resets the chip
//! within its timeout, every pin safe, and no sample comes back; after a
//! stopped crystal or a stray interrupt the image's own handler resets
//! the chip within the laser's bound, every pin safe, and no sample comes
//! back; after the
//! E-STOP the measurement is refused as an E-STOP, the head re-arms on a
//! continue once the input has stayed closed, and measures again; after a
//! stalled conversion chain the measurement is refused and the next one
//! succeeds; after a suspended bus or a re-plug the session ends as a lost
//! link does (the measurement is lost to the host) and the head serves the
//! next one; with a host that stops reading, the measurement ends (its
//! reply waits in the USB queue) and the head stays alive, the watchdog
//! fed.
//!
//! The laser's bound is a millisecond for every fault but the host that
//! stops reading (the measurement then runs to its end, as it should): the
//! fault handler, the E-STOP's interrupt and the guard (TIM7, which finds
//! a stalled conversion chain and a stuck thread) each cut the laser
//! enable by themselves. The drivers' bound is a millisecond where the
//! fault handler drops them, the thread's orderly stop (the motion braked,
//! then the enables) where the thread lives on, and the watchdog's timeout
//! where it does not.

use crate::virtual_board;
use anyhow::{Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_shared::icd::{ContinueEndpoint, MeasureEndpoint, MeasureRequest, StatusEndpoint};
use gonio_shared::{Fault, HeadState};
use serde_json::{json, Value};
use std::path::Path;

/// When the fault strikes, after the laser enable first rises (s): a
/// quarter period into a chop's high half (230 Hz), so that the cut of the
/// chop shows at the pin.
const STRIKE_S: f64 = 0.0185;
/// The laser enable and the chop must be low this soon after any fault (s).
const LASER_OFF_BAR_S: f64 = 1e-3;
/// ...and after the E-STOP's edge, which its interrupt handles at once.
const ESTOP_CUT_BAR_S: f64 = 10e-6;
/// Emulated seconds a trial may run: boot, enumeration, a measurement and
/// the watchdog's timeout.
const TRIAL_SECONDS: &str = "30";

/// How soon the thread stops the drivers once the guard has cut the laser
/// on a stalled conversion chain: two chop periods (230 Hz).
const THREAD_STOP_BAR_S: f64 = 0.01;
/// The E-STOP's backstop (`gonio_firmware::guard::backstop_ticks`): the
/// drivers off this soon after an opening the thread does not stop for,
/// and a tick of the guard more.
fn backstop_bar_s() -> f64 {
    let ticks = gonio_firmware::guard::backstop_ticks(&gonio_firmware::config::REFERENCE) + 1;
    f64::from(ticks) / f64::from(gonio_firmware::guard::TICK_HZ)
}

/// The independent watchdog's timeout (`chip/watchdog.rs`); the board
/// reports the one the image programmed, and that is checked too.
const WATCHDOG_BAR_S: f64 = 1.0;

/// The longest a measurement with the default settings keeps the laser on
/// (chip-bench's bar for the same measurement).
const MEASUREMENT_S: f64 = 1.0;

/// What the head does after a fault, as the host and the pins see it.
#[derive(Clone, Copy, PartialEq)]
enum After {
    /// The watchdog resets the chip; no answer comes.
    Reset,
    /// The image resets the chip at once (a system reset request); no
    /// answer comes.
    Restart,
    /// Refused as an E-STOP, held until a continue re-arms it.
    EStop,
    /// The operation refused; the next one succeeds.
    Recovers,
    /// The session ends as a lost link does; the next request is served.
    LinkLost,
    /// No answer reaches the host; the head lives on.
    Unheard,
}

/// A fault, what follows, and how soon the laser enable must be low and
/// the drivers disabled (s; `None`: they stay as the operation leaves them,
/// a measurement that ends normally). For the E-STOP the drivers go once
/// the serve loop has stopped the operation (the motion braked, then the
/// enables dropped), within a turn of it.
struct Trial {
    kind: &'static str,
    after: After,
    laser_off_bar_s: f64,
    drivers_off_bar_s: Option<f64>,
}

impl Trial {
    const fn new(kind: &'static str, after: After, laser_off_bar_s: f64, drivers_off_bar_s: Option<f64>) -> Self {
        Trial {
            kind,
            after,
            laser_off_bar_s,
            drivers_off_bar_s,
        }
    }
}

/// The trials, in the order they run.
fn trials() -> [Trial; 12] {
    [
        Trial::new("hardfault", After::Reset, LASER_OFF_BAR_S, Some(LASER_OFF_BAR_S)),
        Trial::new("stack-overflow", After::Reset, LASER_OFF_BAR_S, Some(LASER_OFF_BAR_S)),
        Trial::new("estop-pulse", After::EStop, ESTOP_CUT_BAR_S, Some(0.1)),
        Trial::new("dma-freeze", After::Recovers, LASER_OFF_BAR_S, Some(THREAD_STOP_BAR_S)),
        Trial::new("adc-overrun", After::Recovers, LASER_OFF_BAR_S, Some(THREAD_STOP_BAR_S)),
        Trial::new("serve-hang", After::Reset, LASER_OFF_BAR_S, Some(WATCHDOG_BAR_S)),
        Trial::new("estop-hung", After::Reset, ESTOP_CUT_BAR_S, Some(backstop_bar_s())),
        Trial::new("usb-suspend", After::LinkLost, LASER_OFF_BAR_S, Some(0.1)),
        Trial::new("usb-replug", After::LinkLost, LASER_OFF_BAR_S, Some(0.1)),
        Trial::new("usb-in-nak", After::Unheard, MEASUREMENT_S, None),
        Trial::new("crystal-stop", After::Restart, LASER_OFF_BAR_S, Some(LASER_OFF_BAR_S)),
        Trial::new("stray-irq", After::Restart, LASER_OFF_BAR_S, Some(LASER_OFF_BAR_S)),
    ]
}

/// A step's outcome as text.
fn outcome<T>(r: Result<T>, show: impl Fn(T) -> String) -> Result<String, String> {
    r.map(show).map_err(|e| format!("{e:#}"))
}

/// What the host's client met: each step's outcome, as text.
async fn host_side(pty: &str, after: After) -> Vec<(String, Result<String, String>)> {
    let head = match HeadClient::connect(&Port(pty.to_string())).await {
        Ok(h) => h,
        Err(e) => return vec![("connect".into(), Err(format!("{e:#}")))],
    };
    let volts = |s: gonio_shared::Sample| format!("{} V", s.signal.amplitude_v);
    let measure = MeasureRequest { at: None };
    let first = head.request::<MeasureEndpoint>(&measure);
    let measured = if after == After::Unheard {
        // No answer can come: waited for as long as the measurement takes.
        tokio::time::timeout(std::time::Duration::from_secs(3), first)
            .await
            .unwrap_or_else(|_| Err(anyhow::anyhow!("no answer within 3 s")))
    } else {
        first.await
    };
    let mut steps = vec![("measure".to_string(), outcome(measured, volts))];
    if after == After::EStop {
        let status = head.request::<StatusEndpoint>(&()).await;
        steps.push((
            "status".into(),
            outcome(status, |s| format!("{:?}, E-STOP open {}", s.state, s.estop_open)),
        ));
        let resumed = head.request::<ContinueEndpoint>(&()).await;
        steps.push(("continue".into(), outcome(resumed, |s| format!("{:?}", s.state))));
    }
    if matches!(after, After::EStop | After::Recovers | After::LinkLost) {
        let again = head.request::<MeasureEndpoint>(&measure).await;
        steps.push(("measure again".into(), outcome(again, volts)));
    }
    head.close().await;
    steps
}

fn trial(root: &Path, image: &Path, plant: &Path, t: &Trial) -> Result<Value> {
    let fault = format!("{}@laser+{STRIKE_S}", t.kind);
    let (host, report) = virtual_board::trial(
        root,
        image,
        plant,
        TRIAL_SECONDS,
        &["--fault".as_ref(), fault.as_ref()],
        async |pty| host_side(&pty, t.after).await,
    )?;
    let f = &report["fault"];
    let laser_off = f["laser_off_after_s"].as_f64();
    let chop_off = f["chop_off_after_s"].as_f64();
    let drivers_off = f["drivers_off_after_s"].as_f64();
    let mut problems = Vec::new();
    if f["struck"] != json!(true) {
        problems.push("the fault never struck (the laser never came on)".to_string());
    }
    if !laser_off.is_some_and(|s| s <= t.laser_off_bar_s) {
        problems.push(format!(
            "laser enable low {laser_off:?} s after the fault (bar {} s)",
            t.laser_off_bar_s
        ));
    }
    if t.after != After::Unheard && f["chop_high_at_fault"] != json!(true) {
        problems.push("the chop was not high when the fault struck: its cut cannot show".to_string());
    }
    if !chop_off.is_some_and(|s| s <= t.laser_off_bar_s) {
        problems.push(format!("chop low {chop_off:?} s after the fault (bar {} s)", t.laser_off_bar_s));
    }
    if let Some(bar) = t.drivers_off_bar_s {
        if !drivers_off.is_some_and(|s| s <= bar) {
            problems.push(format!("drivers disabled {drivers_off:?} s after the fault (bar {bar} s)"));
        }
    }
    let step = |name: &str| host.iter().find(|(n, _)| n == name).map(|(_, r)| r.clone());
    if matches!(t.after, After::Reset | After::Restart) {
        let (stop, bar) = if t.after == After::Reset {
            let timeout = report["watchdog"]["timeout_s"].as_f64().unwrap_or(f64::INFINITY);
            ("watchdog reset", timeout.min(WATCHDOG_BAR_S))
        } else {
            ("system reset request", t.laser_off_bar_s)
        };
        let reset = f["reset_after_s"].as_f64();
        if report["stopped"] != stop || !reset.is_some_and(|r| r <= bar) {
            problems.push(format!("no {stop} within {bar} s: {} after {reset:?} s", report["stopped"]));
        }
        if report["locked_up"] != json!(false) {
            problems.push("the core locked up".into());
        }
        if report["safe_at_end"] != json!(true) {
            problems.push(format!("pins not safe after the reset: {}", report["driven_at_end"]));
        }
        if matches!(step("measure"), Some(Ok(_))) {
            problems.push("a measurement came back from a faulted head".into());
        }
    } else if t.after == After::EStop {
        let estop = Fault::EmergencyStop.to_string();
        if !matches!(step("measure"), Some(Err(e)) if e.contains(&estop)) {
            problems.push(format!("the measurement was not refused as an E-STOP: {:?}", step("measure")));
        }
        let faulted = format!("{:?}", HeadState::Faulted);
        if !matches!(step("status"), Some(Ok(s)) if s.starts_with(&faulted)) {
            problems.push(format!("the head did not hold the E-STOP: {:?}", step("status")));
        }
        for name in ["continue", "measure again"] {
            if !matches!(step(name), Some(Ok(_))) {
                problems.push(format!("{name}: {:?}", step(name)));
            }
        }
    } else if t.after == After::Unheard {
        if !matches!(step("measure"), Some(Err(_))) {
            problems.push(format!("an answer reached a host that does not read: {:?}", step("measure")));
        }
        if report["watchdog"]["longest_gap_s"].as_f64().is_none_or(|g| g > 0.5) {
            problems.push(format!("the watchdog went unfed: {}", report["watchdog"]));
        }
    } else {
        // Refused by the head, or lost with the session.
        let refused = |e: &String| e.contains("head refused") != (t.after == After::LinkLost);
        if !matches!(step("measure"), Some(Err(e)) if refused(&e)) {
            problems.push(format!(
                "the measurement was not refused or lost as expected: {:?}",
                step("measure")
            ));
        }
        if !matches!(step("measure again"), Some(Ok(_))) {
            problems.push(format!("measure again: {:?}", step("measure again")));
        }
    }
    if !matches!(t.after, After::Reset | After::Restart) && report["stopped"] != "stopped (SIGTERM)" {
        problems.push(format!("the board stopped: {}", report["stopped"]));
    }
    Ok(json!({
        "kind": t.kind,
        "laser_off_us": laser_off.map(|s| (s * 1e7).round() / 10.0),
        "laser_off_bar_us": t.laser_off_bar_s * 1e6,
        "chop_off_us": chop_off.map(|s| (s * 1e7).round() / 10.0),
        "drivers_off_us": drivers_off.map(|s| (s * 1e7).round() / 10.0),
        "reset_after_s": f["reset_after_s"],
        "faults_taken": report["faults_taken"],
        "clocks": report["clocks"],
        "thread_turn_longest_laser_on_us": report["thread_turn_longest_laser_on_us"],
        "host": host.iter().map(|(n, r)| json!({"step": n, "ok": r.as_ref().ok(), "error": r.as_ref().err()})).collect::<Vec<_>>(),
        "emulated_s": report["virtual_seconds"],
        "wall_s": report["host_seconds"],
        "survived": problems.is_empty(),
        "problems": problems,
    }))
}

/// Every trial of [`trials`], one after the other: a JSON object with each
/// trial's figures, `faults_survived` of `faults_tried`, and
/// `laser_off_us_max` over the faults that call for the laser off (all but
/// the host that stops reading, whose measurement runs to its end).
pub fn run(root: &Path, image: &Path, plant: &Path) -> Result<Value> {
    let mut results = Vec::new();
    let mut laser_off_max = f64::NAN;
    let trials = trials();
    for t in &trials {
        eprintln!("board faults: {}", t.kind);
        let r = trial(root, image, plant, t).with_context(|| t.kind)?;
        if t.after != After::Unheard {
            // A fault whose laser never went off counts as its whole run.
            let us = r["laser_off_us"].as_f64().unwrap_or(f64::INFINITY);
            laser_off_max = laser_off_max.max(us);
        }
        results.push(r);
    }
    let survived = results.iter().filter(|r| r["survived"] == json!(true)).count();
    let estop = results.iter().find(|r| r["kind"] == "estop-pulse");
    Ok(json!({
        "estop_to_laser_enable_low_us": estop.map(|r| r["laser_off_us"].clone()),
        "estop_to_chop_low_us": estop.map(|r| r["chop_off_us"].clone()),
        "estop_to_drivers_off_us": estop.map(|r| r["drivers_off_us"].clone()),
        "faults": results,
        "faults_tried": trials.len(),
        "faults_survived": survived,
        "laser_off_us_max": laser_off_max,
        "laser_off_bar_us": LASER_OFF_BAR_S * 1e6,
    }))
}
