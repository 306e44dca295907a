//! `cargo run --release -p gonio-bench --bin board-faults`: the unmodified
//! release image on the virtual STM32F405 board, faulted in the middle of a
//! measurement (`gonio_bench::fault_trials`: the faults and what surviving
//! one means), and booted with a good, a missing and a wrong crystal, and
//! as the `no-laser` image (`gonio_bench::boot_trials`), and measuring at
//! the fastest chop the settings allow (`gonio_bench::chop_trials`). Prints one JSON object and fails when a
//! fault is not survived or a boot does not end as it should.

use anyhow::{bail, Result};
use gonio_bench::virtual_board::{board_plant, head_image};
use gonio_bench::{boot_trials, chop_trials, fault_trials};
use std::path::PathBuf;

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let image = head_image(&root)?;
    let plant = board_plant(&root)?;
    let mut figures = fault_trials::run(&root, &image, &plant)?;
    let boots = boot_trials::run(&root, &image, &plant)?;
    figures["boots"] = boots.clone();
    let chop = chop_trials::run(&root, &image, &plant)?;
    figures["fastest_chop"] = chop.clone();
    println!("{figures}");
    let (tried, survived) = (figures["faults_tried"].as_u64(), figures["faults_survived"].as_u64());
    if tried != survived {
        bail!("{tried:?} faults tried, {survived:?} survived");
    }
    let (booted, passed) = (boots["boots_tried"].as_u64(), boots["boots_passed"].as_u64());
    if booted != passed {
        bail!("{booted:?} boots, {passed:?} as they should");
    }
    if chop["passed"] != serde_json::json!(true) {
        bail!("the fastest chop: {}", chop["problems"]);
    }
    Ok(())
}
