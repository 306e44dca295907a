//! `cargo run --release -p gonio-bench --bin board-faults`: the unmodified
//! release image on the virtual STM32F405 board, faulted in the middle of a
//! measurement (`gonio_bench::fault_trials`: the faults and what surviving
//! one means). Prints one JSON object and fails when a fault is not
//! survived.

use anyhow::{bail, Result};
use gonio_bench::fault_trials;
use gonio_bench::virtual_board::{board_plant, head_image};
use std::path::PathBuf;

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let image = head_image(&root)?;
    let plant = board_plant(&root)?;
    let figures = fault_trials::run(&root, &image, &plant)?;
    println!("{figures}");
    let (tried, survived) = (figures["faults_tried"].as_u64(), figures["faults_survived"].as_u64());
    if tried != survived {
        bail!("{tried:?} faults tried, {survived:?} survived");
    }
    Ok(())
}
