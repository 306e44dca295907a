//! The image booted on the virtual STM32F405 board where it must not
//! measure, and where it must; run by `board-faults`. Each boot asks the
//! head's status and a measurement through the host crate's client, and
//! reads the board's report:
//!
//! - the board's 8 MHz crystal: the PLL on it, the clock security system
//!   on, the measurement made;
//! - no crystal, and a 12 MHz one (as on several common F405 boards): the
//!   PLL on the HSI, the status's `laser_inhibited` naming the crystal's
//!   fault (E601, with the frequency counted), the measurement refused
//!   with it;
//! - the `no-laser` image (docs/bring-up.md) with the good crystal: E604 in
//!   `laser_inhibited`, the measurement refused with it.
//!
//! Every boot: the core and the USB clock at 168 and 48 MHz (never the 252
//! and 72 MHz a trusted 12 MHz crystal gives), and the laser enable and the
//! chop never raised where the head refuses to measure.

use crate::chip_costs;
use crate::virtual_board::{self, TARGET};
use anyhow::{bail, Context, Result};
use gonio_acquire::client::HeadClient;
use gonio_acquire::target::Port;
use gonio_firmware::config::CRYSTAL_HZ;
use gonio_shared::icd::{MeasureEndpoint, MeasureRequest, StatusEndpoint};
use gonio_shared::Fault;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Emulated seconds a boot may run: boot, enumeration and a measurement.
const TRIAL_SECONDS: &str = "10";

/// The counted frequency may differ from the fitted one by the count's
/// resolution (kHz).
const COUNT_KHZ: u32 = 5;

/// A boot: the crystal fitted (Hz; None for none), whether the image is the
/// `no-laser` one, and the fault the head must refuse to measure with.
struct Boot {
    crystal: Option<u32>,
    no_laser: bool,
    refused: Option<Fault>,
}

fn boots() -> [Boot; 4] {
    let crystal = |measured_khz| Fault::Crystal {
        measured_khz,
        expected_khz: CRYSTAL_HZ / 1000,
    };
    [
        Boot {
            crystal: Some(CRYSTAL_HZ),
            no_laser: false,
            refused: None,
        },
        Boot {
            crystal: None,
            no_laser: false,
            refused: Some(crystal(0)),
        },
        Boot {
            crystal: Some(12_000_000),
            no_laser: false,
            refused: Some(crystal(12_000)),
        },
        Boot {
            crystal: Some(CRYSTAL_HZ),
            no_laser: true,
            refused: Some(Fault::LaserDisabled),
        },
    ]
}

/// The release image built with the `no-laser` feature, in a target folder
/// of its own (the full image keeps its place): its path.
pub fn no_laser_image(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let dir = chip_costs::target_dir().join("no-laser");
    let built = Command::new(cargo)
        .args([
            "build",
            "--release",
            "--locked",
            "-p",
            "gonio-firmware",
            "--target",
            TARGET,
            "--features",
            "no-laser",
        ])
        .args(["--bin", "gonio-head", "--target-dir"])
        .arg(&dir)
        .current_dir(root)
        .status()
        .context("building the no-laser image")?;
    if !built.success() {
        bail!("the no-laser image did not build");
    }
    std::path::absolute(dir.join(TARGET).join("release").join("gonio-head")).context("the no-laser image's path")
}

/// What the host met: why the status says the laser is inhibited, and the
/// measurement.
async fn host_side(pty: &str) -> Result<(Option<Fault>, Result<f32, String>)> {
    let head = HeadClient::connect(&Port(pty.to_string())).await.context("connecting")?;
    let status = head.request::<StatusEndpoint>(&()).await.context("the status")?;
    let measured = head
        .request::<MeasureEndpoint>(&MeasureRequest { at: None })
        .await
        .map(|s| s.signal.amplitude_v)
        .map_err(|e| format!("{e:#}"));
    head.close().await;
    Ok((status.laser_inhibited, measured))
}

/// Whether the head's fault is the one expected, the crystal's frequency
/// within the count's resolution.
fn same_fault(found: Option<Fault>, expected: Fault) -> bool {
    match (found, expected) {
        (
            Some(Fault::Crystal {
                measured_khz: m,
                expected_khz: e,
            }),
            Fault::Crystal {
                measured_khz,
                expected_khz,
            },
        ) => e == expected_khz && m.abs_diff(measured_khz) <= COUNT_KHZ,
        (found, expected) => found == Some(expected),
    }
}

fn trial(root: &Path, image: &Path, plant: &Path, boot: &Boot) -> Result<Value> {
    let fitted = boot.crystal.map_or("none".to_string(), |hz| hz.to_string());
    let crystal = ["--crystal".as_ref(), fitted.as_ref()];
    let (host, report) = virtual_board::trial(root, image, plant, TRIAL_SECONDS, &crystal, async |pty| host_side(&pty).await)?;
    let clocks = &report["clocks"];
    let rose = |pin: &str| {
        report["pins"]
            .as_array()
            .is_some_and(|pins| pins.iter().any(|p| p["pin"] == pin && p["level"] == 1))
    };
    let (laser_rose, chop_rose) = (rose("PB0"), rose("PA6"));
    let mut problems = Vec::new();
    if clocks["sysclk_hz"] != json!(168_000_000) || clocks["usb_hz"] != json!(48_000_000) {
        problems.push(format!("clocks {clocks}"));
    }
    let good_crystal = boot.crystal == Some(CRYSTAL_HZ);
    let source = if good_crystal { "HSE" } else { "HSI" };
    if clocks["pll_source"] != source || clocks["css_on"] != json!(good_crystal) {
        problems.push(format!("the PLL on {}, CSS {} ({clocks})", clocks["pll_source"], clocks["css_on"]));
    }
    let (inhibited, measured) = match &host {
        Ok((f, m)) => (*f, m.clone()),
        Err(e) => {
            problems.push(format!("host: {e:#}"));
            (None, Err(String::new()))
        }
    };
    match boot.refused {
        None => {
            if inhibited.is_some() || measured.is_err() || !laser_rose {
                problems.push(format!("laser inhibited {inhibited:?}, measurement {measured:?}"));
            }
        }
        Some(expected) => {
            if !same_fault(inhibited, expected) {
                problems.push(format!("the laser inhibited for {inhibited:?}, not {expected:?}"));
            }
            let code = format!("E{}", expected.code());
            if !matches!(&measured, Err(e) if e.contains(&code)) {
                problems.push(format!("the measurement was not refused as {code}: {measured:?}"));
            }
            if laser_rose || chop_rose {
                problems.push(format!("the laser enable rose: {laser_rose}, the chop: {chop_rose}"));
            }
        }
    }
    Ok(json!({
        "crystal_hz": boot.crystal,
        "no_laser_image": boot.no_laser,
        "clocks": clocks,
        "laser_inhibited": inhibited.map(|f| f.to_string()),
        "measurement": measured.map_or_else(|e| json!({ "refused": e }), |v| json!({ "amplitude_v": v })),
        "laser_rose": laser_rose,
        "chop_rose": chop_rose,
        "boot_instructions": report["first_sleep_instructions"],
        "emulated_s": report["virtual_seconds"],
        "wall_s": report["host_seconds"],
        "passed": problems.is_empty(),
        "problems": problems,
    }))
}

/// Every boot of [`boots`], one after the other, `image` being the full
/// image: the trials and how many passed.
pub fn run(root: &Path, image: &Path, plant: &Path) -> Result<Value> {
    let no_laser = no_laser_image(root)?;
    let boots = boots();
    let mut results = Vec::new();
    for boot in &boots {
        eprintln!("board boots: crystal {:?} Hz, no-laser {}", boot.crystal, boot.no_laser);
        let image = if boot.no_laser { &no_laser } else { image };
        results.push(trial(root, image, plant, boot).with_context(|| format!("crystal {:?}", boot.crystal))?);
    }
    let passed = results.iter().filter(|r| r["passed"] == json!(true)).count();
    Ok(json!({ "boots": results, "boots_tried": boots.len(), "boots_passed": passed }))
}
