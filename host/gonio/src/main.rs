//! `gonio`: scan BRDFs with the retroreflection head, or with its simulator.

use clap::Parser;
use gonio::cli::interrupt;
use gonio_acquire::scan::directory::Interrupted;
use std::process::ExitCode;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = gonio::cli::Cli::parse();
    if let Err(e) = interrupt::install() {
        eprintln!("error: {e:#}");
        return ExitCode::FAILURE;
    }
    match gonio::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {
            eprintln!("{e}");
            ExitCode::from(interrupt::EXIT_CODE)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
