//! The plant behind the virtual board's pins (`gonio_sim::plant`), spoken to
//! by `tests/chip/board/plant.py` over stdin and stdout, one line each way:
//!
//! - at start it prints one JSON object: the outputs it listens to, the home
//!   switches' lines, the photodiode's line;
//! - `p CYCLE PIN LEVEL`: an output changed (no answer);
//! - `s CYCLE`: the switches' levels, `0`/`1` separated by spaces;
//! - `c N T0 DT`: N conversions sampled at T0 + k·DT cycles, answered as the
//!   hex of their little-endian 16-bit codes (the bytes the DMA writes);
//!
//! Times are cycles of the board's 168 MHz clock. The head is described by
//! the options `gonio simulate` takes (`--material`, `--seed`, ...), so that
//! the board's scan and a simulated scan look at the same head.

use anyhow::{bail, Context, Result};
use clap::Parser;
use gonio::cli::material::SimHeadArgs;
use gonio_sim::plant::{Plant, PHOTODIODE, SWITCHES, WIRING};
use std::fmt::Write as _;
use std::io::{BufRead, Write};

const HZ: f64 = 168e6;

/// The head behind the virtual board's pins.
#[derive(Parser)]
struct Args {
    #[command(flatten)]
    head: SimHeadArgs,
    /// Where the stages stand at power-up, ω,τ,ψ in degrees (the simulated
    /// head's power-up position by default): near their home switches, a
    /// benchmark's homing takes seconds, not the minutes of a full travel.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    power_up: Option<Vec<f32>>,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let sim = args.head.config()?;
    let power_up = match args.power_up.as_deref() {
        None => None,
        Some(&[w, t, p]) => Some([w, t, p]),
        Some(v) => bail!("--power-up takes three angles, ω,τ,ψ: {v:?}"),
    };
    let mut plant = Plant::new(&sim, 12, power_up);
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let outputs: Vec<&str> = WIRING.iter().map(|(p, _)| *p).collect();
    writeln!(
        out,
        "{}",
        serde_json::json!({"outputs": outputs, "switches": SWITCHES, "photodiode": PHOTODIODE})
    )?;
    out.flush()?;
    let mut codes = Vec::new();
    let mut hex = String::new();
    for line in std::io::stdin().lock().lines() {
        let line = line?;
        let mut f = line.split_ascii_whitespace();
        let mut num = |what: &str| -> Result<f64> {
            f.next()
                .with_context(|| format!("{line:?}: no {what}"))?
                .parse()
                .with_context(|| format!("{line:?}: {what}"))
        };
        match line.as_bytes().first() {
            Some(b'p') => {
                let mut f = line[1..].split_ascii_whitespace();
                let (Some(t), Some(pin), Some(level)) = (f.next(), f.next(), f.next()) else {
                    bail!("{line:?}: p CYCLE PIN LEVEL");
                };
                if let Some(wire) = Plant::wire(pin) {
                    plant.set(t.parse::<f64>().context("cycle")? / HZ, wire, level == "1");
                }
            }
            Some(b's') => {
                let _ = num("command");
                let levels = plant.switches(num("cycle")? / HZ);
                writeln!(out, "{}", levels.map(|l| if l { "1" } else { "0" }).join(" "))?;
                out.flush()?;
            }
            Some(b'c') => {
                let _ = num("command");
                let n = num("count")? as usize;
                let (t0, dt) = (num("start")? / HZ, num("step")? / HZ);
                codes.clear();
                plant.convert(t0, dt, n, &mut codes);
                hex.clear();
                for c in &codes {
                    let [lo, hi] = c.to_le_bytes();
                    write!(hex, "{lo:02x}{hi:02x}")?;
                }
                writeln!(out, "{hex}")?;
                out.flush()?;
            }
            _ => bail!("{line:?}: not a plant command"),
        }
    }
    Ok(())
}
