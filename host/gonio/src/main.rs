//! `gonio`: scan BRDFs with the retroreflection head, or with its simulator.

use clap::Parser;
use gonio::cli::failure;
use gonio_acquire::interrupt;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so printing to a reader that went away (`gonio
    // coefficients … | head`) panicked; a command-line tool ends quietly
    // there, as the shell's own do.
    #[cfg(unix)]
    // SAFETY: restoring a signal's default disposition at the start of
    // main, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = match gonio::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return failure::usage(e, std::env::args().any(|a| a == "--json")),
    };
    let json = cli.command.json();
    if let Err(e) = interrupt::install() {
        return failure::report(&e, json);
    }
    match gonio::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => failure::report(&e, json),
    }
}
