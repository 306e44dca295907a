//! Heads on USB (VID/PID of `gonio_shared::identity`): their serial
//! number and the CDC-ACM port the kernel made for them. For `gonio devices`,
//! and to find a head again that was plugged back in on another port.

use anyhow::{Context, Result};
use gonio_shared::identity::{USB_PID, USB_VID};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct Found {
    pub serial: Option<String>,
    pub product: Option<String>,
    pub bus: u8,
    pub address: u8,
    /// The CDC-ACM port to pass to `gonio scan --port`.
    pub port: Option<String>,
}

impl std::fmt::Display for Found {
    /// A line for the operator: what, which, where on the bus, which port.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}  serial {}  bus {} address {}  port {}",
            self.product.as_deref().unwrap_or("gonio head"),
            self.serial.as_deref().unwrap_or("?"),
            self.bus,
            self.address,
            self.port.as_deref().unwrap_or("(no tty)")
        )
    }
}

/// The tty node the kernel made for the head's CDC-ACM interface.
fn tty_of(info: &nusb::DeviceInfo) -> Option<String> {
    let sys = info.sysfs_path();
    let name = sys.file_name()?.to_str()?.to_string();
    let tty_dir = sys.join(format!("{name}:1.0")).join("tty");
    let entry = std::fs::read_dir(tty_dir).ok()?.flatten().next()?;
    Some(format!("/dev/{}", entry.file_name().to_string_lossy()))
}

/// The heads on USB; `None` when the machine has no USB bus.
pub fn heads() -> Result<Option<Vec<Found>>> {
    let listing = match nusb::list_devices() {
        Ok(l) => l,
        // A machine (or container) without a USB bus has no head on it.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).context("listing USB devices"),
    };
    Ok(Some(
        listing
            .filter(|d| d.vendor_id() == USB_VID && d.product_id() == USB_PID)
            .map(|d| Found {
                serial: d.serial_number().map(str::to_string),
                product: d.product_string().map(str::to_string),
                bus: d.bus_number(),
                address: d.device_address(),
                port: tty_of(&d),
            })
            .collect(),
    ))
}

/// The port of the head with this USB serial number, if it is plugged in
/// (a head plugged back may come back on another port).
pub fn port_of_serial(serial: &str) -> Option<String> {
    heads().ok()??.into_iter().find(|f| f.serial.as_deref() == Some(serial))?.port
}
