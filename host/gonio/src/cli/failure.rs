//! How a failed command ends: one sentence on stderr, or under `--json` one
//! object `{"error": …, "kind": …}` on stdout, and the exit code (1; 130
//! for the operator's Ctrl-C; 2 for a command line clap refuses).

use gonio_acquire::client::CallError;
use gonio_acquire::interrupt;
use gonio_acquire::scan::directory::Interrupted;
use std::process::ExitCode;

/// What went wrong, for a script to branch on.
pub fn kind(e: &anyhow::Error) -> &'static str {
    if e.downcast_ref::<Interrupted>().is_some() {
        "interrupted"
    } else if e.chain().any(|c| c.downcast_ref::<CallError>().is_some()) {
        "head"
    } else if e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some()) {
        "io"
    } else {
        "input"
    }
}

/// Reports `e` and gives the exit code.
pub fn report(e: &anyhow::Error, json: bool) -> ExitCode {
    let kind = kind(e);
    let text = match kind {
        // Its own sentence says what to do.
        "interrupted" => e.to_string(),
        _ => format!("{e:#}"),
    };
    if json {
        println!("{}", serde_json::json!({ "error": text, "kind": kind }));
    } else if kind == "interrupted" {
        eprintln!("{text}");
    } else {
        eprintln!("error: {text}");
    }
    match kind {
        "interrupted" => ExitCode::from(interrupt::EXIT_CODE),
        _ => ExitCode::FAILURE,
    }
}

/// A command line clap refuses, under `--json` as one object of kind
/// `usage`; help and version requests print as clap prints them.
pub fn usage(e: clap::Error, json: bool) -> ExitCode {
    use clap::error::ErrorKind;
    if !json || matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        e.exit();
    }
    let text = e.to_string();
    let first = text.lines().next().unwrap_or_default().trim_start_matches("error: ");
    println!("{}", serde_json::json!({ "error": first, "kind": "usage" }));
    ExitCode::from(2)
}
