//! The pieces only the benchmarks use: the chopped signal of the lock-in
//! benchmark, the chip's costs that chip-bench leaves for the others, and
//! the virtual board's runs (the board itself, its fault trials, and the
//! scans a fault strikes). What the benchmarks share with the tests is in
//! `tests` (`gonio_tests`).

pub mod board_scans;
pub mod boot_trials;
pub mod chip_costs;
pub mod chop_signal;
pub mod chop_trials;
pub mod fault_trials;
pub mod virtual_board;
