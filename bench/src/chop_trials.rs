//! The fastest chop the settings allow, at the highest ADC rate it allows,
//! measured on the virtual STM32F405 board; run by `board-faults`.
//!
//! The ADC's DMA ring holds two chop periods (`chip/adc_stream.rs`): the
//! thread must read a period within one period of its last code landing,
//! or the DMA overwrites it (an overrun: the point is measured again, and
//! a second one fails the measurement with E500). So one chop period is
//! the slack the thread has against its longest turn with the laser on.
//! The trial sets the detection to `DetectionSettings::CHOP_HZ_MAX` with
//! as many samples per period as the ADC's rate allows, measures
//! [`MEASUREMENTS`] times, and reads the board's report: every measurement
//! made, no conversion lost, and the slack, one period less the thread's
//! longest turn with the laser on, positive.

use crate::virtual_board;
use anyhow::{Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_shared::icd::{DetectionEndpoint, MeasureEndpoint, MeasureRequest};
use gonio_shared::DetectionSettings;
use serde_json::{json, Value};
use std::path::Path;

/// Emulated seconds the trial may run: boot, enumeration and the measurements.
const TRIAL_SECONDS: &str = "20";
/// Measurements made at the fastest chop.
const MEASUREMENTS: usize = 5;

/// The fastest chop, with the most samples per period (a multiple of 4)
/// the ADC's accepted rate allows, integrating 0.1 s.
pub fn fastest() -> DetectionSettings {
    let chop_hz = DetectionSettings::CHOP_HZ_MAX;
    let m = (DetectionSettings::ADC_RATE_MAX_HZ / chop_hz / 4.0).floor() as u16 * 4;
    DetectionSettings {
        chop_hz,
        samples_per_period: m.min(DetectionSettings::SAMPLES_PER_PERIOD_MAX),
        periods: (0.1 * chop_hz).round() as u16,
        ..DetectionSettings::default()
    }
}

/// Each measurement's outcome: its amplitude (V), or the refusal.
async fn host_side(pty: &str, settings: DetectionSettings) -> Result<Vec<Result<f32, String>>> {
    let head = HeadClient::connect(&Port(pty.to_string())).await.context("connecting")?;
    head.request::<DetectionEndpoint>(&settings)
        .await
        .context("the detection settings")?;
    let mut outcomes = Vec::new();
    for _ in 0..MEASUREMENTS {
        let m = head.request::<MeasureEndpoint>(&MeasureRequest { at: None }).await;
        outcomes.push(m.map(|s| s.signal.amplitude_v).map_err(|e| format!("{e:#}")));
    }
    head.close().await;
    Ok(outcomes)
}

/// The trial at [`fastest`]: its figures and whether it passed.
pub fn run(root: &Path, image: &Path, plant: &Path) -> Result<Value> {
    let settings = fastest();
    settings
        .validate()
        .map_err(|f| anyhow::anyhow!("the fastest settings are refused: {f}"))?;
    eprintln!(
        "board chop: {} Hz, {} samples per period",
        settings.chop_hz, settings.samples_per_period
    );
    let (host, report) = virtual_board::trial(root, image, plant, TRIAL_SECONDS, &[], async |pty| host_side(&pty, settings).await)?;
    let period_us = 1e6 / f64::from(settings.chop_hz);
    let turn_us = report["thread_turn_longest_laser_on_us"].as_f64();
    let slack_us = turn_us.map(|t| period_us - t);
    let lost = &report["conversions"]["lost"];
    let mut problems = Vec::new();
    let outcomes = match host {
        Ok(o) => o,
        Err(e) => {
            problems.push(format!("host: {e:#}"));
            Vec::new()
        }
    };
    let made = outcomes.iter().filter(|o| o.is_ok()).count();
    if made != MEASUREMENTS {
        problems.push(format!("{made} of {MEASUREMENTS} measurements made: {outcomes:?}"));
    }
    if lost != &json!(0) {
        problems.push(format!("{lost} conversions lost"));
    }
    if slack_us.is_none_or(|s| s <= 0.0) {
        problems.push(format!("no slack: a period of {period_us} µs, the longest turn {turn_us:?} µs"));
    }
    Ok(json!({
        "chop_hz": settings.chop_hz,
        "samples_per_period": settings.samples_per_period,
        "sample_rate_hz": settings.sample_rate_hz(),
        "measurements": MEASUREMENTS,
        "made": made,
        "refusals": outcomes.iter().filter_map(|o| o.as_ref().err()).collect::<Vec<_>>(),
        "conversions_lost": lost,
        "period_us": period_us,
        "thread_turn_longest_laser_on_us": turn_us,
        "slack_us": slack_us,
        "passed": problems.is_empty(),
        "problems": problems,
    }))
}
