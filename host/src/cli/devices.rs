//! `gonio devices`: heads on USB, by VID/PID, with serial and serial port.

use anyhow::{Context, Result};
use gonio_shared::identity::{USB_PID, USB_VID};
use serde::Serialize;

#[derive(Debug, clap::Args)]
pub struct DevicesArgs {
    /// Print the list as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct Found {
    serial: Option<String>,
    product: Option<String>,
    bus: u8,
    address: u8,
    /// The CDC-ACM port to pass to `gonio scan --port`.
    port: Option<String>,
}

/// The tty node the kernel made for the head's CDC-ACM interface.
fn tty_of(info: &nusb::DeviceInfo) -> Option<String> {
    let sys = info.sysfs_path();
    let name = sys.file_name()?.to_str()?.to_string();
    let tty_dir = sys.join(format!("{name}:1.0")).join("tty");
    let entry = std::fs::read_dir(tty_dir).ok()?.flatten().next()?;
    Some(format!("/dev/{}", entry.file_name().to_string_lossy()))
}

pub fn devices(a: DevicesArgs) -> Result<()> {
    let listing = match nusb::list_devices() {
        Ok(l) => Some(l),
        // A machine (or container) without a USB bus has no head on it.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!("note: no USB bus visible on this machine");
            None
        }
        Err(e) => return Err(e).context("listing USB devices"),
    };
    let found: Vec<Found> = listing
        .into_iter()
        .flatten()
        .filter(|d| d.vendor_id() == USB_VID && d.product_id() == USB_PID)
        .map(|d| Found {
            serial: d.serial_number().map(str::to_string),
            product: d.product_string().map(str::to_string),
            bus: d.bus_number(),
            address: d.device_address(),
            port: tty_of(&d),
        })
        .collect();
    if a.json {
        println!("{}", serde_json::to_string_pretty(&found)?);
        return Ok(());
    }
    if found.is_empty() {
        println!("no head found on USB (VID {USB_VID:04x}, PID {USB_PID:04x})");
    }
    for f in &found {
        println!(
            "{}  serial {}  bus {} address {}  port {}",
            f.product.as_deref().unwrap_or("gonio head"),
            f.serial.as_deref().unwrap_or("?"),
            f.bus,
            f.address,
            f.port.as_deref().unwrap_or("(no tty)")
        );
    }
    Ok(())
}
