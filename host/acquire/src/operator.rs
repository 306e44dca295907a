//! The person at the instrument, as the library sees them: what it tells
//! them while it works (notices: the reference learned, a recovery under
//! way; progress bars), and what it asks them to do by hand (mount the
//! reference plate). The command line chooses where notices go: stderr and
//! a bar on a terminal run; stderr alone under `--json` (stdout holds the
//! one JSON object, and a failed scan's object names only its last error,
//! not the recoveries before it); nowhere in tests. Library code never
//! prints itself.

use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Display;

/// Where notices and progress go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Operator {
    /// Notices on stderr, progress bars on the terminal.
    Terminal,
    /// Notices on stderr, no progress bars: a `--json` run.
    Logged,
    /// Nothing: a test.
    Silent,
}

impl Operator {
    /// The operator of a command run with or without `--json`.
    pub fn for_json(json: bool) -> Self {
        if json {
            Operator::Logged
        } else {
            Operator::Terminal
        }
    }

    /// Tells the operator something, on a line of its own.
    pub fn notice(self, msg: impl Display) {
        if self != Operator::Silent {
            eprintln!("{msg}");
        }
    }

    /// Asks the operator to do something by hand and waits until they say
    /// it is done: a line on stdin (Enter), prompted on stderr (under
    /// `--json`, whatever drives `gonio` writes the line).
    pub fn ask(self, task: impl Display) -> anyhow::Result<()> {
        use anyhow::Context;
        self.notice(format_args!("{task} and press Enter"));
        let mut line = String::new();
        std::io::stdin().read_line(&mut line).context("waiting for the operator")?;
        Ok(())
    }

    /// A bar over `len` `items` for `task`, shown on a terminal run only.
    pub fn bar(self, len: u64, task: &str, items: &str) -> ProgressBar {
        if self != Operator::Terminal {
            return ProgressBar::hidden();
        }
        let pb = ProgressBar::new(len);
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {task} [{{bar:40}}] {{pos}}/{{len}} {items}, {{msg}} ({{eta}} left)"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        pb
    }
}
