//! Command-line interface. Angles on the command line are in degrees.

mod detector;
mod devices;
mod grid;
mod material;
mod plan;
mod scan;
mod sim;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "gonio", version, about = "Retroreflection BRDF measurement head: scan, store, simulate")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Full scan of the Belcour grid on the simulated head; writes samples.csv and run.json.
    Demo(scan::DemoArgs),
    /// Scan a grid on a head (real or simulated) and store the samples.
    Scan(scan::ScanArgs),
    /// List measurement heads found on USB.
    Devices(devices::DevicesArgs),
    /// Run a simulated head on a pseudo-terminal, for `gonio scan --port PATH`.
    Sim(sim::SimArgs),
}

/// Runs a command to completion.
pub fn run(cli: Cli) -> Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    match cli.command {
        Command::Demo(a) => rt.block_on(scan::demo(a)),
        Command::Scan(a) => rt.block_on(scan::scan(a)),
        Command::Devices(a) => devices::devices(a),
        Command::Sim(a) => sim::sim(a),
    }
}
