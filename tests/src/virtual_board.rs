//! The virtual STM32F405 board (`tests/chip/board/`) as the benchmarks run
//! it: the unmodified image with a USB host on a pseudo-terminal, the
//! simulated head's world behind its pins (`board-plant`, built beside the
//! benchmark), and its report when it is told to stop.

use crate::chip_costs;
use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::ffi::OsStr;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, Command, Stdio};

/// `board-plant` built in this program's profile: its path.
pub fn board_plant(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut build = Command::new(cargo);
    build
        .args(["build", "--locked", "-p", "tests", "--bin", "board-plant"])
        .current_dir(root);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    if !build.status().context("building board-plant")?.success() {
        bail!("board-plant did not build");
    }
    Ok(chip_costs::target_dir()
        .join(if cfg!(debug_assertions) { "debug" } else { "release" })
        .join("board-plant"))
}

/// The chip the image is built for.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The firmware's binaries `bins`, built in release for the chip: the
/// folder they are in.
pub fn chip_images(root: &Path, bins: &[&str]) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut build = Command::new(cargo);
    build.args(["build", "--release", "--locked", "-p", "gonio-firmware", "--target", TARGET]);
    for bin in bins {
        build.args(["--bin", bin]);
    }
    if !build.current_dir(root).status().context("building the firmware")?.success() {
        bail!("{bins:?} did not build for {TARGET}");
    }
    Ok(chip_costs::target_dir().join(TARGET).join("release"))
}

/// The release `gonio-head` image, built: its path.
pub fn head_image(root: &Path) -> Result<PathBuf> {
    Ok(chip_images(root, &["gonio-head"])?.join("gonio-head"))
}

/// A board running `image` with its port on a pseudo-terminal.
pub struct Board {
    child: Child,
    err: BufReader<ChildStderr>,
    /// The pseudo-terminal a host program opens as the head's port.
    pub pty: String,
}

impl Board {
    /// Starts `board.py IMAGE --pty ARGS…` and reads its pseudo-terminal.
    pub fn start(root: &Path, image: &Path, args: &[&OsStr]) -> Result<Board> {
        let mut child = Command::new("python3")
            .arg(root.join("tests/chip/board/board.py"))
            .arg(image)
            .arg("--pty")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .context("running python3 tests/chip/board/board.py --pty (needs `pip install unicorn`)")?;
        let mut err = BufReader::new(child.stderr.take().context("the board's stderr")?);
        let mut line = String::new();
        err.read_line(&mut line).context("reading the board's pseudo-terminal")?;
        let Some(pty) = line.strip_prefix("pty ").map(str::trim).map(str::to_string) else {
            let _ = child.kill();
            let mut rest = String::new();
            let _ = err.read_to_string(&mut rest);
            bail!("the board printed {line:?}, not its pseudo-terminal: {rest}");
        };
        Ok(Board { child, err, pty })
    }

    /// Tells the board to stop (it prints its report then) and reads the report.
    pub fn stop(mut self) -> Result<Value> {
        let _ = Command::new("kill").arg("-TERM").arg(self.child.id().to_string()).status();
        let out = self.child.wait_with_output().context("waiting for the board")?;
        let mut rest = String::new();
        let _ = self.err.read_to_string(&mut rest);
        serde_json::from_slice(&out.stdout).with_context(|| format!("the board's report (stderr: {rest})"))
    }
}
