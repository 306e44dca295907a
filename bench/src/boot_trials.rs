//! The crystal at boot on the virtual STM32F405 board: the unmodified
//! release image powered up with the board's 8 MHz crystal, with none, and
//! with a 12 MHz one (as on several common F405 boards); run by
//! `board-faults`. Each trial boots the image, asks its status and a
//! measurement through the host crate's client, and reads the board's
//! report.
//!
//! Passed means: the core and the USB clock at 168 and 48 MHz whatever the
//! crystal (never the 252 and 72 MHz a 12 MHz crystal gives when trusted);
//! with the good crystal, the PLL on it, the clock security system on and
//! the measurement made; with a missing or wrong one, the PLL on the HSI,
//! the status naming the crystal's fault (E601, with the frequency
//! counted), the measurement refused with it, and the laser enable never
//! raised.

use crate::virtual_board::Board;
use anyhow::{Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_firmware::config::CRYSTAL_HZ;
use gonio_shared::icd::{MeasureEndpoint, MeasureRequest, StatusEndpoint};
use gonio_shared::Fault;
use serde_json::{json, Value};
use std::path::Path;

/// Emulated seconds a trial may run: boot, enumeration and a measurement.
const TRIAL_SECONDS: &str = "10";

/// The crystals tried (Hz; None for none fitted).
const CRYSTALS: [Option<u32>; 3] = [Some(CRYSTAL_HZ), None, Some(12_000_000)];

/// The counted frequency may differ from the fitted one by the count's
/// resolution (kHz).
const COUNT_KHZ: u32 = 5;

/// What the host met: the status's last fault and the measurement.
async fn host_side(pty: &str) -> Result<(Option<Fault>, Result<f32, String>)> {
    let head = HeadClient::connect(&Port(pty.to_string())).await.context("connecting")?;
    let status = head.request::<StatusEndpoint>(&()).await.context("the status")?;
    let measured = head
        .request::<MeasureEndpoint>(&MeasureRequest { at: None })
        .await
        .map(|s| s.signal.amplitude_v)
        .map_err(|e| format!("{e:#}"));
    head.close().await;
    Ok((status.last_fault, measured))
}

fn trial(root: &Path, image: &Path, plant: &Path, crystal: Option<u32>) -> Result<Value> {
    let fitted = crystal.map_or("none".to_string(), |hz| hz.to_string());
    let board = Board::start(
        root,
        image,
        &[
            "--seconds".as_ref(),
            TRIAL_SECONDS.as_ref(),
            "--plant".as_ref(),
            plant.as_os_str(),
            "--crystal".as_ref(),
            fitted.as_ref(),
        ],
    )?;
    let pty = board.pty.clone();
    let host = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("a runtime for the client")?
        .block_on(host_side(&pty));
    let report = board.stop()?;
    let clocks = &report["clocks"];
    let laser_rose = report["pins"]
        .as_array()
        .is_some_and(|pins| pins.iter().any(|p| p["pin"] == "PB0" && p["level"] == 1));
    let mut problems = Vec::new();
    if clocks["sysclk_hz"] != json!(168_000_000) || clocks["usb_hz"] != json!(48_000_000) {
        problems.push(format!("clocks {clocks}"));
    }
    let good = crystal == Some(CRYSTAL_HZ);
    let source = if good { "HSE" } else { "HSI" };
    if clocks["pll_source"] != source || clocks["css_on"] != json!(good) {
        problems.push(format!("the PLL on {}, CSS {} ({clocks})", clocks["pll_source"], clocks["css_on"]));
    }
    let (last_fault, measured) = match &host {
        Ok((f, m)) => (*f, m.clone()),
        Err(e) => {
            problems.push(format!("host: {e:#}"));
            (None, Err(String::new()))
        }
    };
    if good {
        if last_fault.is_some() || measured.is_err() || !laser_rose {
            problems.push(format!("a good crystal: last fault {last_fault:?}, measurement {measured:?}"));
        }
    } else {
        let counted = match last_fault {
            Some(Fault::Crystal {
                measured_khz,
                expected_khz,
            }) if expected_khz == CRYSTAL_HZ / 1000 => Some(measured_khz),
            _ => None,
        };
        let fitted_khz = crystal.unwrap_or(0) / 1000;
        if counted.is_none_or(|khz| khz.abs_diff(fitted_khz) > COUNT_KHZ) {
            problems.push(format!("the status's last fault {last_fault:?}, for a {fitted_khz} kHz crystal"));
        }
        if !matches!(&measured, Err(e) if e.contains("E601")) {
            problems.push(format!("the measurement was not refused as E601: {measured:?}"));
        }
        if laser_rose {
            problems.push("the laser enable rose".into());
        }
    }
    Ok(json!({
        "crystal_hz": crystal,
        "clocks": clocks,
        "last_fault": last_fault.map(|f| f.to_string()),
        "measurement": measured.map_or_else(|e| json!({ "refused": e }), |v| json!({ "amplitude_v": v })),
        "laser_rose": laser_rose,
        "boot_instructions": report["first_sleep_instructions"],
        "emulated_s": report["virtual_seconds"],
        "wall_s": report["host_seconds"],
        "passed": problems.is_empty(),
        "problems": problems,
    }))
}

/// Every crystal of [`CRYSTALS`], one boot each: the trials and how many passed.
pub fn run(root: &Path, image: &Path, plant: &Path) -> Result<Value> {
    let mut results = Vec::new();
    for crystal in CRYSTALS {
        eprintln!("board clocks: crystal {crystal:?} Hz");
        results.push(trial(root, image, plant, crystal).with_context(|| format!("crystal {crystal:?}"))?);
    }
    let passed = results.iter().filter(|r| r["passed"] == json!(true)).count();
    Ok(json!({ "boots": results, "boots_tried": CRYSTALS.len(), "boots_passed": passed }))
}
