//! The virtual STM32F405 board (the Python package `tests/chip/board/`, run
//! as `python3 -m board` from `tests/chip`) as the benchmarks run it: the
//! unmodified image with a USB host on a pseudo-terminal, the
//! simulated head's world behind its pins (`board-plant`, built beside the
//! benchmark), and its report when it is told to stop.

use crate::chip_costs;
use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::ffi::OsStr;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, Command, Stdio};

/// `board-plant` built in this program's profile: its absolute path (the
/// board runs it from `tests/chip`).
pub fn board_plant(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut build = Command::new(cargo);
    build
        .args(["build", "--locked", "-p", "gonio-bench", "--bin", "board-plant"])
        .current_dir(root);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    if !build.status().context("building board-plant")?.success() {
        bail!("board-plant did not build");
    }
    let plant = chip_costs::target_dir()
        .join(if cfg!(debug_assertions) { "debug" } else { "release" })
        .join("board-plant");
    std::path::absolute(&plant).with_context(|| format!("the absolute path of {}", plant.display()))
}

/// The chip the image is built for.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The firmware's binaries `bins`, built in release for the chip: the
/// folder they are in, absolute (`CARGO_TARGET_DIR` may be relative, and the
/// board and the emulator run from `tests/chip`).
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
    let images = chip_costs::target_dir().join(TARGET).join("release");
    std::path::absolute(&images).with_context(|| format!("the absolute path of {}", images.display()))
}

/// The release `gonio-head` image, built: its path.
pub fn head_image(root: &Path) -> Result<PathBuf> {
    Ok(chip_images(root, &["gonio-head"])?.join("gonio-head"))
}

/// A trial on the board: `image` run for at most `seconds` of emulated
/// time with `plant` behind its pins and `args` besides, while `host`
/// drives its port (the pseudo-terminal's path) on a runtime of its own;
/// what the host met, and the board's report once it is told to stop.
pub fn trial<T, F: std::future::Future<Output = T>>(
    root: &Path,
    image: &Path,
    plant: &Path,
    seconds: &str,
    args: &[&OsStr],
    host: impl FnOnce(String) -> F,
) -> Result<(T, Value)> {
    let mut all: Vec<&OsStr> = vec!["--seconds".as_ref(), seconds.as_ref(), "--plant".as_ref(), plant.as_os_str()];
    all.extend_from_slice(args);
    let board = Board::start(root, image, &all)?;
    let met = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("a runtime for the client")?
        .block_on(host(board.pty.clone()));
    Ok((met, board.stop()?))
}

/// A board running `image` with its port on a pseudo-terminal.
pub struct Board {
    child: Child,
    err: BufReader<ChildStderr>,
    /// The pseudo-terminal a host program opens as the head's port.
    pub pty: String,
}

impl Board {
    /// Starts `python3 -m board IMAGE --pty ARGS…` in `tests/chip` and reads
    /// its pseudo-terminal. Paths in `args` must be absolute.
    pub fn start(root: &Path, image: &Path, args: &[&OsStr]) -> Result<Board> {
        // Absolute: the board runs in `tests/chip`, not here.
        let image = std::path::absolute(image).with_context(|| format!("the absolute path of {}", image.display()))?;
        let mut child = Command::new("python3")
            .args(["-m", "board"])
            .arg(&image)
            .arg("--pty")
            .args(args)
            .current_dir(root.join("tests/chip"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .context("running python3 -m board --pty in tests/chip (needs `pip install unicorn`)")?;
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
