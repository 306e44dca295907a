//! `gonio devices`: heads on USB, by VID/PID, with serial and serial port.

use anyhow::Result;
use gonio_acquire::usb::heads;
use gonio_shared::identity::{USB_PID, USB_VID};

#[derive(Debug, clap::Args)]
pub struct DevicesArgs {
    /// Print the list as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn devices(a: DevicesArgs) -> Result<()> {
    let found = match heads()? {
        Some(f) => f,
        None => {
            eprintln!("note: no USB bus visible on this machine");
            Vec::new()
        }
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&found)?);
        return Ok(());
    }
    if found.is_empty() {
        println!("no head found on USB (VID {USB_VID:04x}, PID {USB_PID:04x})");
    }
    for f in &found {
        println!("{f}");
    }
    Ok(())
}
