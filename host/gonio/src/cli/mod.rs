//! Command-line interface. Angles on the command line are in degrees.

pub mod calibrate;
mod coefficients;
mod control;
mod convert;
pub mod demo;
pub mod detector;
mod devices;
mod export;
pub mod failure;
pub mod fit;
pub mod fit_args;
pub mod fitting;
pub mod grid;
pub mod in_process;
pub mod instrument;
pub mod material;
mod model_eval;
mod moments;
pub mod output;
mod plot;
mod rational;
mod repeatability;
pub mod scan;
mod sim;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use gonio_acquire::scan::page::Steer;
use gonio_analysis::fit::{Dataset, Units};
use std::path::Path;

#[derive(Debug, Parser)]
#[command(
    name = "gonio",
    version,
    about = "Retroreflection BRDF measurement head: scan, store, simulate, fit"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// The whole chain on the simulated head: the reference plate, the Belcour
    /// grid with its lobe rings, calibration, every model fitted, R_A and R_L;
    /// writes the scan directory, calibrated.csv, fits/, plots/ and report.html.
    Demo(demo::DemoArgs),
    /// Scan a grid on a head (real or simulated) and store the samples.
    Scan(scan::ScanArgs),
    /// List measurement heads found on USB.
    Devices(devices::DevicesArgs),
    /// Run a simulated head on a pseudo-terminal, for `gonio scan --port PATH`.
    Sim(sim::SimArgs),
    /// Turn a scan into BRDF values with a reference-plate scan, correcting laser drift.
    Calibrate(calibrate::CalibrateArgs),
    /// Coefficients of retroreflection R_A and R_L (CIE 54.2, ASTM E810, EN 1436) with uncertainties.
    Coefficients(coefficients::CoefficientsArgs),
    /// Fit one model to a data file (ALTA .dat or calibrated CSV), no starting point needed.
    Fit(fit_args::FitArgs),
    /// Fit every model to a data file and compare them (RMSE, NRMSE, NCC).
    Compare(fit_args::CompareArgs),
    /// Pictures of a data file and fits: incidence-plane, hemisphere and residual plots.
    Plot(plot::PlotArgs),
    /// Write a data file (ALTA .dat or calibrated CSV) as ALTA text.
    Convert(convert::ConvertArgs),
    /// Write a fit (FIT.json) or a simulated material for another tool: a
    /// BRDF Explorer .brdf shader, an RGL .bsdf for Mitsuba 3 and pbrt-v4,
    /// or a MERL .binary table.
    Export(export::ExportArgs),
    /// Evaluate a model at one geometry.
    Eval(model_eval::EvalArgs),
    /// Directional-hemispherical reflectance of a model, and its energy check.
    Dhr(model_eval::DhrArgs),
    /// The retro lobe's central moments per incidence in the back and light-view planes (Belcour §3.D).
    Moments(moments::MomentsArgs),
    /// Repeated scans of one sample compared geometry by geometry: mean, s and the budget's σ.
    Repeatability(repeatability::RepeatabilityArgs),
    /// Hold a running scan before its next position (from another terminal; the live page's Pause).
    Pause(control::ControlArgs),
    /// Let a held scan go on where it stopped.
    Continue(control::ControlArgs),
    /// Stop a running scan as Ctrl-C would: every sample kept, resumable.
    Abort(control::ControlArgs),
    /// Arm a head again after its E-STOP, once the input is closed.
    Rearm(control::RearmArgs),
}

impl Command {
    /// Whether the command was asked for one JSON object on stdout (its
    /// errors too). `sim` serves until stopped and prints no result.
    pub fn json(&self) -> bool {
        match self {
            Command::Demo(a) => a.output.json,
            Command::Scan(a) => a.output.json,
            Command::Devices(a) => a.json,
            Command::Sim(_) => false,
            Command::Calibrate(a) => a.json,
            Command::Coefficients(a) => a.json,
            Command::Fit(a) => a.options.json,
            Command::Compare(a) => a.options.json,
            Command::Plot(a) => a.json,
            Command::Convert(a) => a.json,
            Command::Export(a) => a.json,
            Command::Eval(a) => a.json,
            Command::Dhr(a) => a.json,
            Command::Moments(a) => a.json,
            Command::Repeatability(a) => a.json,
            Command::Pause(a) | Command::Continue(a) | Command::Abort(a) => a.json,
            Command::Rearm(a) => a.json,
        }
    }
}

/// Reads a data file for a command, with the instrument the user stated;
/// what the reader assumed or doubts goes to stderr.
pub(crate) fn load_data(path: &Path, units: Option<Units>, instrument: &instrument::InstrumentArgs) -> Result<Dataset> {
    let data = gonio_analysis::formats::load_stated(path, units, instrument.stated()?)?;
    for w in &data.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(data)
}

/// Runs a command to completion.
pub fn run(cli: Cli) -> Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    match cli.command {
        Command::Demo(a) => rt.block_on(demo::demo(a)),
        Command::Scan(a) => rt.block_on(scan::scan(a)),
        Command::Devices(a) => devices::devices(a),
        Command::Sim(a) => sim::sim(a),
        Command::Calibrate(a) => calibrate::calibrate_cmd(a),
        Command::Coefficients(a) => coefficients::coefficients_cmd(a),
        Command::Fit(a) if a.model == gonio_analysis::rational::file::MODEL => rational::fit_cmd(a),
        Command::Fit(a) => fit::fit_cmd(a),
        Command::Compare(a) => fit::compare_cmd(a),
        Command::Convert(a) => convert::convert_cmd(a),
        Command::Plot(a) => plot::plot_cmd(a),
        Command::Export(a) => export::export_cmd(a),
        Command::Eval(a) => model_eval::eval_cmd(a),
        Command::Dhr(a) => model_eval::dhr_cmd(a),
        Command::Moments(a) => moments::moments_cmd(a),
        Command::Repeatability(a) => repeatability::repeatability_cmd(a),
        Command::Pause(a) => control::control_cmd(Steer::Pause, a),
        Command::Continue(a) => control::control_cmd(Steer::Continue, a),
        Command::Abort(a) => control::control_cmd(Steer::Abort, a),
        Command::Rearm(a) => rt.block_on(control::rearm_cmd(a)),
    }
}
