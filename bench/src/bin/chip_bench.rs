//! `cargo run --release -p gonio-bench --bin chip-bench`: what the STM32F405 pays
//! for the core's hot paths, in instructions counted on an emulated
//! Cortex-M4F, as one JSON object on stdout.
//!
//! It builds `gonio-cost` (the core's hot paths in the release profile of the
//! chip image, `firmware/src/bin/cost`) for thumbv7em-none-eabihf and runs it
//! on the unicorn engine (`python3 -m board.emulate` in `tests/chip`, `pip
//! install unicorn`), which counts the instructions between the image's
//! marks. Cycles are taken as one per instruction at 168 MHz, plus 24 per
//! interrupt for exception entry and exit: the M4 needs more for loads,
//! branches and divisions, so the derived rates are upper bounds.
//!
//! Figures and bars (`docs/architecture.md`, "The chip's costs"; a bar
//! missed fails the run, as the counts are exact on every machine):
//! - `step_event_instructions_max` (≤ 250): one `Executor::fire`, the
//!   worst over a three-axis move at the axes' cruise speeds.
//! - `step_isr_instructions_max`: the TIM5 handler's logic (critical
//!   section, counter, compare), braking included.
//! - `demod_period_instructions`: one chop period of M = 64 codes
//!   (`_long_integration`: past 256 periods, which accumulates its own Gram
//!   matrix); `design_instructions`: the regression's design a configure
//!   computes (one stretch of the serve loop, at configure only).
//! - `sanity_eval_instructions_max`: the fixed-point model per sample.
//! - `plan_next_instructions_max`: the next point of a scan (queue, geometry,
//!   inverse kinematics), on the Belcour grid and a 4 096-point incidence.
//! - `move_plan_instructions`: the blocks of a three-axis move;
//!   `move_block_instructions_max`: one block, which the simulated head and
//!   the duration estimate charge as `BLOCK_PLAN_INSTRUCTIONS` (the run fails
//!   should the chip pay more).
//! - `sweep_instructions`: what a sweep pays besides its periods' demodulation:
//!   its checks and the design of its samples (once), a sweep scan's row's
//!   ends, targets and limits (once a row), the tag of a sample (per
//!   sample); `sweep_stretch_instructions_max` (≤ 100 000, the serve
//!   loop's budget between polls) the longest of them;
//!   `sweep_sample_end_instructions` what a sample's end computes (its last
//!   period's demodulation, drift fit, estimate, tag) while the next period
//!   fills the ADC's ring of two: with the serve loop's budget it must fit
//!   in a period of the fastest chop (`DetectionSettings::CHOP_HZ_MAX`).
//! - `resume_instructions_max` (≤ 1 000 000): a scan resumed near its end.
//! - `await_free_instructions_max` (≤ 100 000): the longest poll of the serve
//!   loop while it serves the full Belcour grid (all 3 441 points, with a
//!   sanity model, its plan fed as the host feeds it) and a resume two plan
//!   chunks before its end (`await_free_scan_points`,
//!   `await_free_resume_points`: the points served; fewer fails the run).
//! - `boot_instructions`, `board`: the unmodified `gonio-head` image on the
//!   virtual board (`python3 -m board` in `tests/chip`: the core taking
//!   interrupts, the peripherals modelled from RM0090) for 3 s of virtual
//!   time from reset, the E-STOP opened at 1 s; the instructions to its
//!   first idle wait, the interrupts taken, the watchdog's reloads and the
//!   driven pins. The run fails (and `.ci/run`) unless: it neither faults
//!   nor resets, the laser enable and STEP stay low and the drivers' EN high
//!   throughout, the time driver interrupts at every half period of its
//!   counter, the E-STOP's edge is taken once, and the watchdog is reloaded
//!   within 0.5 s.
//! - `usb_session`: the same image with a USB host on the board's bus
//!   (`board/usb_host.py`: bus reset, descriptors, address, configuration,
//!   line coding and DTR, then bulk transfers) bridged to a pseudo-terminal,
//!   where the host crate's own client (`HeadClient` on a `Port`, as `gonio
//!   scan --port` drives a real head) asks its identity and status, and
//!   three measurements where the stages powered up, with the simulated
//!   head's world behind the pins (`board-plant`: the photodiode through
//!   TIM2, ADC1, DMA2 and the chop on TIM3). Failing to enumerate, to
//!   identify or to answer fails the run, as do measurements that differ
//!   from each other by more than 4σ, or from the in-process simulated
//!   head's by more than 0.5 %, or a laser left on.
//! - `step_rate_hz_3axes_at_50pct_cpu` (≥ 50 000): per-axis step rate that
//!   three axes sustain on half the CPU, from the mean handler cost.
//! - `await_free_stack_bytes_max`: the stack the serve loop's deepest poll
//!   takes (the chip's stack is the 64 KiB CCM RAM, `memory.x`);
//!   `probe_stack_bytes_max`: the probe image's own deepest point.

use anyhow::{bail, Context, Result};
use gonio_bench::chip_costs::{self, EXCEPTION_CYCLES};
use gonio_bench::virtual_board::{board_plant, chip_images, Board};
use gonio_firmware::config::CPU_HZ;
use gonio_firmware::motion::blocks::BLOCK_PLAN_INSTRUCTIONS;
use gonio_shared::scan::VISIT_CHUNK;
use gonio_shared::DetectionSettings;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The serve loop's budget between two polls (instructions).
const AWAIT_FREE_BAR: u64 = 100_000;

/// Runs `python3 -m MODULE ARGS…` in `tests/chip` (the package `board`) and
/// reads the JSON it prints; paths in `args` must be absolute.
fn python(root: &Path, module: &str, args: &[&std::ffi::OsStr]) -> Result<Value> {
    let out = Command::new("python3")
        .args(["-m", module])
        .args(args)
        .current_dir(root.join("tests/chip"))
        .output()
        .with_context(|| format!("running python3 -m {module} in tests/chip (needs `pip install unicorn`)"))?;
    if !out.status.success() {
        bail!("python3 -m {module} {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    serde_json::from_slice(&out.stdout).with_context(|| format!("reading what python3 -m {module} printed"))
}

/// The longest the laser may stay on for one measurement at rest (s): its
/// ranging, settling and 100 ms integration, with room.
const LASER_MEASURE_S: f64 = 1.0;
/// Measurements the image takes over USB, one after the other.
const MEASUREMENTS: usize = 3;
/// How far the board's measurement may lie from the in-process simulated
/// head's, relative: the simulated head samples each chop period as its
/// convention has it, the board at the instants TIM2 triggers ADC1 with the
/// amplifier's response between the chop's edges (a few 0.1 %).
const SIM_AGREEMENT: f64 = 0.005;

/// Virtual seconds the unmodified image runs on the board, and when the
/// plant opens the E-STOP.
const BOARD_SECONDS: &str = "3";
const ESTOP_OPENS_AT: f64 = 1.0;

/// The board's run: from reset, for `BOARD_SECONDS`, the E-STOP opened at
/// `ESTOP_OPENS_AT`; an error says what it did that a healthy idle head
/// does not.
fn board_run(root: &Path, image: &Path) -> Result<Value> {
    let estop = format!("PB12=1@{ESTOP_OPENS_AT}");
    let run = python(
        root,
        "board",
        &[
            image.as_os_str(),
            "--seconds".as_ref(),
            BOARD_SECONDS.as_ref(),
            "--set".as_ref(),
            estop.as_ref(),
        ],
    )?;
    let seconds: f64 = BOARD_SECONDS.parse()?;
    let taken = |irq: &str| run["interrupts"][irq].as_u64().unwrap_or(0);
    // The time driver's 16-bit counter at 1 MHz interrupts at each half
    // period (32.768 ms) at least.
    let periods = (seconds / 0.032_768) as u64;
    let gap = run["watchdog"]["longest_gap_s"].as_f64();
    let problems: Vec<String> = [
        (run["stopped"] != "time").then(|| format!("stopped: {}", run["stopped"])),
        (run["unsafe"].as_array().is_none_or(|u| !u.is_empty())).then(|| format!("a safety pin left its safe level: {}", run["unsafe"])),
        (run["safe_at_end"] != Value::Bool(true)).then(|| format!("not in the safe state at the end: {}", run["driven_at_end"])),
        (taken("TIM4") < periods).then(|| {
            format!(
                "{} time-driver interrupts in {seconds} s, fewer than its {periods} half periods",
                taken("TIM4")
            )
        }),
        (taken("EXTI15_10") != 1).then(|| format!("the E-STOP's edge took {} EXTI15_10 interrupts, not 1", taken("EXTI15_10"))),
        gap.is_none_or(|g| g > 0.5)
            .then(|| format!("the watchdog's longest reload gap is {gap:?} s (its timeout: 1 s)")),
        fast_outputs(&run).map(|pins| format!("outputs faster than the low slew rate (pins.rs): {pins}")),
        (run["usb_pullup_without_vbus"] != Value::Bool(false)).then(|| {
            format!(
                "the pull-up on D+ was on with no VBUS (no USB host on the board): {}",
                run["usb_pullup_without_vbus"]
            )
        }),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !problems.is_empty() {
        bail!("the image on the virtual board: {}", problems.join("; "));
    }
    Ok(run)
}

/// The board's outputs other than USB's D−/D+ (PA11, PA12) and the debug
/// port's (PA13–15, PB3–4, as reset leaves them) whose edges
/// were driven faster than the lowest slew rate, if any (or the laser
/// enable's missing from the report: a board that logged no output).
fn fast_outputs(run: &Value) -> Option<String> {
    let Some(speeds) = run["output_speeds"].as_object().filter(|s| s.contains_key("PB0")) else {
        return Some(format!("no slew rate reported for the laser enable: {}", run["output_speeds"]));
    };
    let fast: Vec<String> = speeds
        .iter()
        .filter(|(pin, speed)| !matches!(pin.as_str(), "PA11" | "PA12" | "PA13" | "PA14" | "PA15" | "PB3" | "PB4") && *speed != "low")
        .map(|(pin, speed)| format!("{pin} {speed}"))
        .collect();
    (!fast.is_empty()).then(|| fast.join(", "))
}

/// The unmodified image on the board with a USB host that opens its port
/// and bridges it to a pseudo-terminal, driven by the host crate's own
/// client (`HeadClient` on a `Port`, as `gonio scan --port` drives a real
/// head), and the simulated head's world behind its pins (`board-plant`):
/// it identifies itself and answers a status request, in a second session
/// too, after the port was closed and the cable pulled and plugged back; in
/// the first, it measures where the stages powered up, three times, through
/// TIM2, ADC1, DMA2 and the chop on TIM3. Returns the client's view and the
/// board's report.
fn usb_session(root: &Path, image: &Path, plant: &Path) -> Result<Value> {
    use gonio_acquire::client::HeadClient;
    use gonio_acquire::target::Port;
    use gonio_shared::icd::{MeasureEndpoint, MeasureRequest, StatusEndpoint};

    let board = Board::start(
        root,
        image,
        &[
            "--replug".as_ref(),
            "--seconds".as_ref(),
            "120".as_ref(),
            "--plant".as_ref(),
            plant.as_os_str(),
        ],
    )?;
    let path = board.pty.clone();
    // The board is stopped (and its report read) whatever the client met.
    let client = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(anyhow::Error::from)
        .and_then(|rt| {
            rt.block_on(async {
                // Two sessions: the port closed after the first, the cable
                // then pulled and plugged back in (the board's host does it).
                let mut last = None;
                let mut measure = None;
                for session in 1..=2 {
                    let head = HeadClient::connect(&Port(path.clone()))
                        .await
                        .with_context(|| format!("session {session}"))?;
                    let identity = head.identity().clone();
                    let status = head
                        .request::<StatusEndpoint>(&())
                        .await
                        .with_context(|| format!("session {session}: status"))?;
                    if session == 1 {
                        let mut taken = Vec::new();
                        for _ in 0..MEASUREMENTS {
                            let s = head
                                .request::<MeasureEndpoint>(&MeasureRequest { at: None })
                                .await
                                .context("a measurement")?;
                            taken.push(s.signal);
                        }
                        measure = Some(taken);
                    }
                    head.close().await;
                    last = Some((identity, status));
                    tokio::time::sleep(std::time::Duration::from_millis(500)).await;
                }
                anyhow::Ok((last.context("no session")?, measure))
            })
        });
    let report = board.stop()?;
    let ((identity, status), measure) =
        client.with_context(|| format!("the host's client on the board's port; the board: {}", report["usb"]))?;
    // The head runs from its own supply, and says so (USB 2.0 §9.6.3).
    if report["usb"]["self_powered"] != Value::Bool(true) {
        bail!("the configuration descriptor does not say self-powered: {}", report["usb"]);
    }
    let board_signals = measure.context("no measurement")?;
    let sim = simulated_measurement()?;
    // The laser enable's high stretches, from the board's pin log (s).
    let mut laser = Vec::new();
    let mut on = None;
    for p in report["pins"].as_array().into_iter().flatten().filter(|p| p["pin"] == "PB0") {
        let t = p["t"].as_f64().unwrap_or(f64::NAN);
        match (p["level"].as_u64(), on) {
            (Some(1), None) => on = Some(t),
            (Some(0), Some(from)) => {
                laser.push(json!([from, t]));
                on = None;
            }
            _ => {}
        }
    }
    if let Some(from) = on {
        laser.push(json!([from, null]));
    }
    let mut problems = Vec::new();
    if !report["stopped"].as_str().is_some_and(|s| s.starts_with("stopped")) {
        problems.push(format!("the board stopped: {}", report["stopped"]));
    }
    // Each measurement alike (a measurement must not start with the last
    // one's codes: defect 1), and like the simulated head's.
    let first = &board_signals[0];
    for (k, s) in board_signals.iter().enumerate() {
        let sigma = (s.noise_v.powi(2) + first.noise_v.powi(2)).sqrt();
        if (s.amplitude_v - first.amplitude_v).abs() > 4.0 * sigma || !s.flags.is_empty() && s.flags != first.flags {
            problems.push(format!("measurement {k} differs from the first: {s:?} against {first:?}"));
        }
        if ((s.amplitude_v - sim.amplitude_v) / sim.amplitude_v).abs() as f64 > SIM_AGREEMENT {
            problems.push(format!(
                "measurement {k} is {} V, the simulated head's {} V (bar {SIM_AGREEMENT} relative)",
                s.amplitude_v, sim.amplitude_v
            ));
        }
    }
    // The laser is on for a measurement only: every stretch ends within
    // one measurement's time.
    let longest = laser
        .iter()
        .map(|s| s[1].as_f64().map_or(f64::INFINITY, |off| off - s[0].as_f64().unwrap_or(0.0)))
        .fold(0.0, f64::max);
    if longest > LASER_MEASURE_S || laser.len() != MEASUREMENTS {
        problems.push(format!(
            "the laser was on {} times, the longest {longest} s (bar: {MEASUREMENTS} times, {LASER_MEASURE_S} s): {laser:?}",
            laser.len()
        ));
    }
    if !problems.is_empty() {
        bail!("the image over USB on the virtual board: {}", problems.join("; "));
    }
    let signal = |s: &gonio_shared::Signal| json!({"amplitude_v": s.amplitude_v, "noise_v": s.noise_v, "phase_deg": s.phase_deg, "gain_index": s.gain_index, "flags": format!("{:?}", s.flags)});
    Ok(json!({
        "measurements": board_signals.iter().map(signal).collect::<Vec<_>>(),
        "simulated_head_measurement": signal(&sim),
        "laser_on_stretches_s": laser,
        "laser_on_longest_s": longest,
        "identity": {
            "board": identity.board.as_str(),
            "serial": identity.serial.as_str(),
            "firmware_version": identity.firmware_version.as_str(),
            "simulated": identity.simulated,
            "protocol_version": identity.protocol_version,
        },
        "status": { "state": format!("{:?}", status.state), "laser_on": status.laser_on, "drivers_enabled": status.drivers_enabled, "estop_open": status.estop_open },
        "board": { "stack_bytes_max": report["stack_bytes_max"], "busiest_functions": report["busiest_functions"], "busiest_registers": report["busiest_registers"], "instructions": report["instructions"], "stopped": report["stopped"], "virtual_seconds": report["virtual_seconds"], "host_seconds": report["host_seconds"], "interrupts": report["interrupts"], "usb": report["usb"], "unsafe": report["unsafe"] },
    }))
}

/// The in-process simulated head's measurement where its stages powered up
/// (the board's plant is the same world, with the same default head).
fn simulated_measurement() -> Result<gonio_shared::Signal> {
    use gonio_frames::{replies, send};
    use gonio_shared::icd::{MeasureEndpoint, MeasureRequest};
    let mut head = gonio_sim::FrameHead::new(&gonio_sim::SimConfig::default());
    let sent = head.serve([send::<MeasureEndpoint>(&MeasureRequest { at: None })]);
    let reply = replies::<MeasureEndpoint>(&sent)
        .pop()
        .context("the simulated head's measurement")?;
    Ok(reply.map_err(|f| anyhow::anyhow!("the simulated head refused: {f:?}"))?.signal)
}

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let images = chip_images(&root, &["gonio-cost", "gonio-head"])?;
    let run = python(&root, "board.emulate", &["costs".as_ref(), images.join("gonio-cost").as_os_str()])?;
    // The unmodified image on the virtual board, from reset.
    let board = board_run(&root, &images.join("gonio-head"))?;
    let plant = board_plant(&root)?;
    let usb = usb_session(&root, &images.join("gonio-head"), &plant)?;
    let p = &run["probes"];
    let max = |name: &str| p[name]["max"].as_u64().with_context(|| format!("no figure for {name}"));
    let mean = |name: &str| -> Result<f64> {
        Ok(p[name]["total"].as_f64().context(name.to_string())? / p[name]["count"].as_f64().context(name.to_string())?)
    };

    let step_event = max("step_event")?;
    let isr_max = max("step_isr")?.max(max("step_isr_braking")?);
    // The handler runs once per event: a step's start and its pulse's end
    // (merged when they coincide); the probe's move says how many per step.
    let events = p["step_isr"]["count"].as_f64().context("step_isr count")?;
    let steps = run["values"]["step_isr"].as_f64().context("steps of the probe's move")?;
    let events_per_step = events / steps;
    let cycles_per_step = events_per_step * (mean("step_isr")? + EXCEPTION_CYCLES as f64);
    let step_rate = 0.5 * CPU_HZ / (3.0 * cycles_per_step);
    let await_free = max("await_free")?;
    let scan_points = run["values"]["scan_points"].as_u64().context("points of the served scan")?;
    let resume_points = run["values"]["resume_points"].as_u64().context("points of the resumed scan")?;
    let resume = max("resume")?;
    // A sweep's longest stretch without a poll of the serve loop: its checks,
    // the design of its samples, or a sample's tag (the estimate yields on
    // its own, as a measurement's does).
    let sweep_tag = max("sweep_tag")?;
    let sweep_stretch = max("sweep_check")?
        .max(max("sweep_limits")?)
        .max(max("sweep_row")?)
        .max(max("design_8_periods")?)
        .max(max("sweep_drift")?)
        .max(max("sweep_estimate")?)
        .max(max("inverse")?)
        .max(sweep_tag);
    // What a sweep computes from a sample's last period to the next sample's
    // first (that period's demodulation, the drift fit, the estimate, the
    // tag): with the serve loop's other work between two polls, it must take
    // less than a period of the fastest chop, or the ADC's ring (two
    // periods) overruns.
    let demod_period = max("demod_square")?.max(max("demod_sine")?);
    let sweep_sample_end = demod_period + max("sweep_drift")? + max("sweep_estimate")? + sweep_tag;
    let sweep_sample_end_bar = (CPU_HZ / DetectionSettings::CHOP_HZ_MAX as f64) as u64 - AWAIT_FREE_BAR;
    let figures = json!({
        "emulator": run["emulator"],
        "cpu_hz_assumed": CPU_HZ,
        "step_event_instructions_max": step_event,
        "step_event_instructions_mean": mean("step_event")?,
        "step_isr_instructions_max": isr_max,
        "step_isr_instructions_mean": mean("step_isr")?,
        "step_isr_events_per_step": events_per_step,
        "demod_period_instructions": max("demod_square")?.max(max("demod_sine")?),
        "demod_period_instructions_long_integration": max("demod_long")?,
        "design_instructions": {
            "23 periods": max("design_23_periods")?,
            "256 periods": max("design_256_periods")?,
        },
        "sanity_eval_instructions_max": {
            "lambert": max("sanity_lambert")?,
            "retro-phong": max("sanity_retro_phong")?,
            "abc-retro (view)": max("sanity_abc_retro_view")?,
            "abc-retro (back)": max("sanity_abc_retro_back")?,
        },
        "inverse_kinematics_instructions_max": max("inverse")?,
        "sweep_instructions": {
            "check (once)": max("sweep_check")?,
            "limits (once)": max("sweep_limits")?,
            "scan row's place, ends, targets, limits and stretches (once per row)": max("sweep_row")?,
            "design of 8-period samples (once)": max("design_8_periods")?,
            "drift fit (per sample)": max("sweep_drift")?,
            "estimate (per sample)": max("sweep_estimate")?,
            "tag (per sample)": sweep_tag,
            "end of a sample": sweep_sample_end,
            "demodulation (per period)": demod_period,
        },
        "plan_next_instructions_max": max("plan_next")?,
        "move_plan_instructions": max("move_plan")?,
        "move_block_instructions_max": max("move_block")?,
        "resume_instructions_max": resume,
        "await_free_instructions_max": await_free,
        "await_free_polls": p["await_free"]["count"],
        "await_free_scan_points": scan_points,
        "await_free_resume_points": resume_points,
        "await_free_stack_bytes_max": p["await_free"]["stack_max"],
        "probe_stack_bytes_max": run["stack_bytes_max"],
        "step_rate_hz_3axes_at_50pct_cpu": step_rate.round(),
        "boot_instructions": board["first_sleep_instructions"],
        "board": {
            "virtual_seconds": board["virtual_seconds"],
            "host_seconds": board["host_seconds"],
            "interrupts": board["interrupts"],
            "watchdog": board["watchdog"],
            "driven_at_end": board["driven_at_end"],
            "stack_bytes_max": board["stack_bytes_max"],
        },
        "usb_session": usb,
        "bars": {
            "step_event_instructions_max": 250,
            "resume_instructions_max": 1_000_000,
            "await_free_instructions_max": AWAIT_FREE_BAR,
            "sweep_stretch_instructions_max": AWAIT_FREE_BAR,
            "sweep_sample_end_instructions": sweep_sample_end_bar,
            "step_rate_hz_3axes_at_50pct_cpu": 50_000,
        },
        "bars_met": {
            "step_event_instructions_max": step_event <= 250,
            "resume_instructions_max": resume <= 1_000_000,
            "await_free_instructions_max": await_free <= AWAIT_FREE_BAR,
            "sweep_stretch_instructions_max": sweep_stretch <= AWAIT_FREE_BAR,
            "sweep_sample_end_instructions": sweep_sample_end <= sweep_sample_end_bar,
            "step_rate_hz_3axes_at_50pct_cpu": step_rate >= 50_000.0,
        },
    });
    println!("{figures}");
    // motion-bench takes its interrupt cost from here.
    std::fs::write(chip_costs::report_path(), figures.to_string()).context("writing target/chip-bench.json")?;
    let grid = gonio_shared::ScanSpec::belcour().len() as u64;
    if scan_points != grid {
        bail!("the served scan ended after {scan_points} of the Belcour grid's {grid} points");
    }
    // The resume starts two chunks before the grid's end (probes.rs).
    let resumed = 2 * VISIT_CHUNK as u64;
    if resume_points != resumed {
        bail!("the resumed scan ended after {resume_points} of its {resumed} points");
    }
    // The simulated head and the duration estimate charge this per block.
    let block = max("move_block")?;
    if block > BLOCK_PLAN_INSTRUCTIONS as u64 {
        bail!("a block costs {block} instructions to plan, more than the {BLOCK_PLAN_INSTRUCTIONS} the simulated head and the estimate charge");
    }
    // The counts are exact and the same on every machine: a bar missed is
    // a regression of the code, and fails the run (and `.ci/run`).
    let missed: Vec<&String> = figures["bars_met"]
        .as_object()
        .context("bars_met")?
        .iter()
        .filter(|(_, met)| **met != Value::Bool(true))
        .map(|(name, _)| name)
        .collect();
    if !missed.is_empty() {
        bail!("bars missed: {missed:?}");
    }
    Ok(())
}
